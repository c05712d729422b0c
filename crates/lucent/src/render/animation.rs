//! `lucent render --frames N --out DIR`: an animation, rendered frame by frame into
//! `DIR/frame_0001.png`, ... (each written atomically). Either the scene's deformation ramps
//! from the rest pose (frame 1) to full (frame N), or with `--orbit-light` the lights make one
//! turn about the vertical axis through the object. The hierarchical solver keeps its links
//! across frames (Mertens §5.5: refit mode by default, render mode for lighting alone).

use super::frame::GpuFrame;
use super::htsm::HtsmFrame;
use super::output::Frame;
use super::{image_format, tone_map};
use crate::cli::{ImageFormat, Method, RenderArgs, SolveMode};
use crate::scene::{Scene, orbit_lights};
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use lucent_core::clock::ms_since;
use lucent_core::session::{FrameSession, Solved, Timings};
use lucent_gpu::GpuContext;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The frames' file name: 1-based, four digits, as video tools expect (`frame_%04d.png`, or
/// `.exr`).
pub fn frame_name(index: u32, format: ImageFormat) -> String {
    format!("frame_{:04}.{}", index + 1, format.extension())
}

/// Checks the output directory before any work: an existing directory, or a path whose parent
/// exists (it is created once everything else has succeeded).
pub fn check_out_dir(out: &Path) -> Result<()> {
    if out.is_dir() {
        return Ok(());
    }
    if out.exists() {
        bail!("{}: --out must be a directory with --frames (this is a file)", out.display());
    }
    let parent = super::output::output_dir(out);
    if !parent.is_dir() {
        bail!("{}: the output directory's parent {} does not exist", out.display(), parent.display());
    }
    Ok(())
}

/// Renders the animation and prints per-frame medians.
pub fn run(args: &RenderArgs, scene: &Scene, frames: u32, out: &Path) -> Result<()> {
    if frames == 0 {
        bail!("--frames must be at least 1");
    }
    if scene.deform.is_empty() && !args.orbit_light {
        bail!("--frames animates a deformation (--deform or the scene's) or the lights (--orbit-light)");
    }
    let format = image_format(args);
    let mut ctx = Some(GpuContext::new()?);
    let started = Instant::now();
    // Refit by default: the links made on the first frame are kept and their coefficients
    // re-evaluated, not rebuilt (`--mode incremental` updates them as a fresh link would).
    let mut session = scene.session(SolveMode::Refit);
    let mode = session.settings().mode;
    session.set_eye(Some(scene.camera_view((args.width, args.height)).eye));
    session.set_view_terms(args.view_terms);
    let (center, _) = lucent_core::camera::bounding_sphere(&scene.mesh.positions);
    let frame_at = |i: u32| {
        let t = if frames > 1 { i as f32 / (frames - 1) as f32 } else { 1.0 };
        if args.orbit_light {
            // One turn, the last frame one step short of the first (the loop closes).
            let angle = std::f32::consts::TAU * i as f32 / frames as f32;
            (scene.deformed(1.0), orbit_lights(&scene.lights, center, angle))
        } else {
            (scene.deformed(t), scene.lights.clone())
        }
    };

    let mut drawer: Option<Drawer> = None;
    let mut times: Vec<Timings> = Vec::new();
    let bar = ProgressBar::new(frames as u64).with_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames, {elapsed} (eta {eta}) {msg}")
            .expect("valid template"),
    );
    let mut created_dir = false;
    let mut first_links = None;
    for i in 0..frames {
        let (mesh, lights) = frame_at(i);
        session.set_positions(&mesh.positions);
        session.set_lights(lights);
        let solved = session.solve().clone();
        first_links = first_links.or(solved.links);
        let t = Instant::now();
        let d = match &mut drawer {
            Some(d) => d,
            None => {
                drawer.insert(Drawer::new(ctx.take().expect("used once"), scene, args, &session, &solved)?)
            }
        };
        // Every frame but a still one moves the mesh (the drawers start from the rest pose).
        let image = d.draw(&session, &solved, !scene.deform.is_empty(), format)?;
        let render_ms = ms_since(t);
        let t = Instant::now();
        if !created_dir {
            std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
            created_dir = true;
        }
        image.write(&out.join(frame_name(i, format)))?;
        times.push(Timings { raster_ms: render_ms, write_ms: ms_since(t), ..solved.timings });
        bar.set_message(format!("solve {:.0} ms", solved.timings.total_ms()));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let adapter = drawer.as_ref().map(Drawer::adapter).unwrap_or_default();
    println!(
        "lucent: {}: {} triangles, {} at {} m, {}{}, {} frames in {:.1} s on {} -> {}",
        scene.source,
        scene.mesh.triangles.len(),
        scene.material().name,
        scene.scale(),
        args.method.name(),
        if args.method == Method::Hierarchical { format!(" ({})", mode.name()) } else { String::new() },
        frames,
        started.elapsed().as_secs_f64(),
        adapter,
        out.join(frame_name(0, format)).display(),
    );
    let first_link_ms = times.first().map_or(0.0, |t| t.link_ms);
    println!(
        "lucent: per frame (median of {frames}): {}; first frame link/update {:.1} ms{}",
        Timings::median(&times).line(),
        first_link_ms,
        first_links.map(|l| format!(", {l} links")).unwrap_or_default(),
    );
    Ok(())
}

/// What draws the frames: the mesh pass over the solve's per-vertex radiance (Mertens), or
/// HTSM from the session's pose, lights and environment (Shopf).
enum Drawer {
    Mertens(Box<GpuFrame>),
    Htsm(Box<HtsmFrame>),
}

impl Drawer {
    fn new(
        ctx: GpuContext,
        scene: &Scene,
        args: &RenderArgs,
        session: &FrameSession,
        solved: &Solved,
    ) -> Result<Self> {
        Ok(match args.method {
            Method::Htsm => {
                let frame = HtsmFrame::new(ctx, scene, args)?;
                println!("lucent: htsm: {}", frame.summary);
                Drawer::Htsm(Box::new(frame))
            }
            _ => {
                let size = (args.width, args.height);
                let tone = tone_map(args, scene.exposure);
                let background = !args.no_env_background;
                let (mesh, radiance) = (session.mesh(), &solved.vertex_radiance);
                Drawer::Mertens(Box::new(GpuFrame::new(ctx, scene, size, tone, mesh, radiance, background)?))
            }
        })
    }

    fn draw(
        &mut self,
        session: &FrameSession,
        solved: &Solved,
        moved: bool,
        format: ImageFormat,
    ) -> Result<Frame> {
        match self {
            Drawer::Mertens(g) => {
                let mesh = moved.then_some(session.mesh());
                g.draw(mesh, solved, session.lights(), format == ImageFormat::Exr)
            }
            Drawer::Htsm(h) => h.draw(session, moved, format),
        }
    }

    fn adapter(&self) -> String {
        match self {
            Drawer::Mertens(g) => g.adapter(),
            Drawer::Htsm(h) => h.adapter(),
        }
    }
}

/// The default output directory of an animation.
pub fn default_out() -> PathBuf {
    PathBuf::from("frames")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_names_sort_and_start_at_one() {
        assert_eq!(frame_name(0, ImageFormat::Png), "frame_0001.png");
        assert_eq!(frame_name(41, ImageFormat::Exr), "frame_0042.exr");
        assert!(frame_name(8, ImageFormat::Png) < frame_name(9, ImageFormat::Png));
    }

    /// (Moved here with `output.rs` into the library, which has no `cli`.)
    #[test]
    fn format_from_flag_then_extension() {
        let exr = Some(Path::new("a/b.EXR"));
        assert_eq!(ImageFormat::resolve(None, exr, false), ImageFormat::Exr);
        assert_eq!(ImageFormat::resolve(None, Some(Path::new("b.png")), false), ImageFormat::Png);
        assert_eq!(ImageFormat::resolve(None, None, false), ImageFormat::Png);
        assert_eq!(ImageFormat::resolve(None, exr, true), ImageFormat::Png, "a directory");
        assert_eq!(ImageFormat::resolve(Some(ImageFormat::Exr), None, true), ImageFormat::Exr);
    }
}
