//! `lucent render`: mesh ─► irradiance at the faces with ray-cast shadows and the SH environment
//! (Mertens §5.3) ─► subsurface solve (§3, §5.2, §5.5) ─► area-weighted per-vertex `B / pi`
//! (§3.2) ─► GPU raster with the exit Fresnel factor, highlights and the Fresnel-weighted
//! environment reflection, tone mapped (§5.4) ─► PNG, or the HDR frame as OpenEXR, written
//! atomically ([`output`]).
//!
//! * [`crate::scene::Scene`]: the scene from the flags and an optional scene file (flags win).
//! * `lucent_core::session::FrameSession`: the solve, reusable across frames; [`frame`]: the
//!   GPU frame, likewise.
//! * [`animation`]: `--frames N`, a deformation ramp or an orbiting light.
//!
//! `--method htsm` takes its own GPU path ([`htsm`]): Shopf 2007 renders on the GPU from
//! light-view maps and has no per-vertex solve.

pub mod animation;
pub mod htsm;
// The GPU frame and the image files live in the library, for the Python module.
pub use lucent::{frame, output};

pub use crate::scene::Scene;

use crate::cli::{HierarchyChoice, ImageFormat, Method, RenderArgs, ToneCurve};
use anyhow::{Context, Result, bail};
use lucent_gpu::GpuContext;
use lucent_gpu::tonemap::{ToneMap, ToneOperator};
use output::{Frame, output_dir};
use std::path::PathBuf;
use std::time::Instant;

pub fn run(args: &RenderArgs) -> Result<()> {
    check_args(args)?;
    let scene = shrink_wrap_scene(Scene::resolve(&args.overrides())?, args)?;
    if let Some(note) = declined_refine_note(&scene) {
        println!("{note}");
    }
    if let Some(frames) = args.frames {
        let out = args.out.clone().unwrap_or_else(animation::default_out);
        return animation::run(args, &scene, frames, &out);
    }
    let format = image_format(args);
    let out = single_out(args);
    let started = Instant::now();
    let (image, timings) = match args.method {
        Method::Htsm => render_htsm(&scene, args, format)?,
        method => render_mertens(&scene, args, method, format)?,
    };
    image.write(&out)?;
    println!(
        "lucent: {}: {} triangles{}, {} at {} m, {} solve {:.0} ms{}, render {:.0} ms on {}, total {:.0} ms -> {}",
        scene.source,
        scene.mesh.triangles.len(),
        match scene.refine_levels {
            0 => String::new(),
            n => format!(
                " (each face split in four {})",
                if n == 1 { "once".into() } else { format!("{n} times") }
            ),
        },
        scene.material().name,
        scene.scale(),
        args.method.name(),
        timings.solve_ms,
        timings.links.map(|l| format!(" ({l} links)")).unwrap_or_default(),
        timings.render_ms,
        timings.adapter,
        started.elapsed().as_secs_f64() * 1e3,
        out.display()
    );
    Ok(())
}

/// With `--hierarchy shrink-wrap:L`, replaces the scene's mesh by its shrink-wrapped resampling
/// (Mertens §5.1.2) and keeps that mesh's subdivision hierarchy for the solver.
fn shrink_wrap_scene(mut scene: Scene, args: &RenderArgs) -> Result<Scene> {
    use lucent_core::hierarchy::shrink_wrap::{ShrinkWrapOptions, shrink_wrap};
    let HierarchyChoice::ShrinkWrap(levels) = args.hierarchy else {
        return Ok(scene);
    };
    if args.method == Method::Htsm {
        bail!("--hierarchy shrink-wrap works with --method hierarchical or exact, not htsm");
    }
    let t = Instant::now();
    let w = shrink_wrap(&scene.mesh, levels, &ShrinkWrapOptions::default())
        .with_context(|| format!("--hierarchy shrink-wrap:{levels}: cannot shrink-wrap {}", scene.source))?;
    let extent = scene.mesh.extent().max(f32::MIN_POSITIVE);
    println!(
        "lucent: shrink-wrapped {} ({} triangles) to {} triangles in {:.0} ms; max distance to the input {:.4} mesh units \
         ({:.2} % of its size)",
        scene.source,
        scene.mesh.triangles.len(),
        w.subdivided.mesh.triangles.len(),
        t.elapsed().as_secs_f64() * 1e3,
        w.hausdorff(),
        100.0 * w.hausdorff() / extent
    );
    scene.mesh = w.subdivided.mesh;
    scene.hierarchy = Some(w.subdivided.hierarchy);
    scene.refine_levels = 0;
    Ok(scene)
}

/// Wall-clock times of the stages, for the summary line.
pub struct Timings {
    /// Irradiance plus solve plus per-vertex averaging, milliseconds.
    pub solve_ms: f64,
    /// GPU upload, draw, tone map and read-back (not adapter start-up), milliseconds.
    pub render_ms: f64,
    /// The adapter used, e.g. `"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)"`.
    pub adapter: String,
    /// Links of the hierarchical solve, if it made any.
    pub links: Option<usize>,
}

/// What the exact method left unsplit (`Scene::refine_declined`): the faces and the cost of
/// asking for the splits, which grows with the square of the faces.
fn declined_refine_note(scene: &Scene) -> Option<String> {
    let n = scene.refine_declined;
    let faces = scene.mesh.triangles.len();
    (n > 0).then(|| {
        format!(
            "lucent: --method exact solves the {faces} faces as loaded; --refine auto would split them {n} time{} \
             to {} faces, {}x the cost (O(N^2)): ask with --refine {n}",
            if n == 1 { "" } else { "s" },
            faces << (2 * n),
            1u64 << (4 * n)
        )
    })
}

/// Says so when transport reaches less far than faces are wide: those faces took the local
/// limit `B = R_d E` (one link each) instead of a refinement.
fn local_limit_note(mesh: &lucent_core::mesh::Mesh, profile: &lucent_core::bssrdf::Profile) {
    use lucent_core::hierarchy::face_cluster;
    use lucent_core::solver::local::Locality;
    let loc = Locality::of(profile);
    // Only a face wider than twice the reach can be local: skip the hierarchy otherwise.
    let widest = mesh.triangles.iter().enumerate().map(|(f, _)| mesh.face_area(f)).fold(0.0f32, f32::max);
    if widest < 4.0 * loc.reach * loc.reach {
        return;
    }
    let h = face_cluster::build(mesh);
    let local = loc.local_clusters(&h, mesh).iter().zip(&h.nodes).filter(|(l, n)| **l && n.is_leaf()).count();
    if local > 0 {
        println!(
            "lucent: transport reaches {:.3e} mm, below the faces: {local} of {} faces took the local limit B = R_d E",
            loc.reach as f64 * profile.mm_per_unit,
            mesh.triangles.len()
        );
    }
}

/// The output format: `--format`, else by `--out`'s extension.
pub(crate) fn image_format(args: &RenderArgs) -> ImageFormat {
    ImageFormat::resolve(args.format, args.out.as_deref(), args.frames.is_some())
}

/// The output file of a single image: `--out`, else `lucent.png` or `lucent.exr`.
fn single_out(args: &RenderArgs) -> PathBuf {
    let default = || PathBuf::from(format!("lucent.{}", image_format(args).extension()));
    args.out.clone().unwrap_or_else(default)
}

/// Rejects an unwritable output location before any work is done.
fn check_args(args: &RenderArgs) -> Result<()> {
    // Numbers were range-checked by the flags' parsers (`crate::ranges`).
    if args.frames.is_some() {
        return animation::check_out_dir(&args.out.clone().unwrap_or_else(animation::default_out));
    }
    let out = single_out(args);
    let dir = output_dir(&out);
    if !dir.is_dir() {
        bail!("{}: the output directory {} does not exist", out.display(), dir.display());
    }
    if out.is_dir() {
        bail!("{}: --out names a directory; give a .png or .exr file (or use --frames)", out.display());
    }
    Ok(())
}

/// Mertens 2003: solve on the CPU (with `--deform` applied in full), then rasterise per-vertex
/// radiance on the GPU.
fn render_mertens(
    scene: &Scene,
    args: &RenderArgs,
    method: Method,
    format: ImageFormat,
) -> Result<(Frame, Timings)> {
    // The adapter first: without one, fail before the (possibly long) solve.
    let ctx = GpuContext::new()?;
    let size = (args.width, args.height);
    let t = Instant::now();
    debug_assert_eq!(scene.settings.method, method);
    let (mesh, mut session) = lucent::still::session(scene, size);
    let watch = crate::progress::Watch::new();
    session.set_progress(Some(watch.progress()));
    session.set_view_terms(args.view_terms);
    let profile = session.profile().clone();
    session.solve();
    if args.view_terms == lucent_core::session::ViewTerms::Split {
        // A solve is seen per eye; the split serves the camera moves after one. Arrive at the
        // eye by such a move, so that the image is the split's (docs/speed.md compares them).
        let eye = scene.camera_view(size).eye;
        session.set_eye(Some(eye + glam::Vec3::X * (1e-3 * mesh.extent())));
        session.solve();
        session.set_eye(Some(eye));
    }
    let solved = session.solve();
    drop(watch);
    let solve_ms = t.elapsed().as_secs_f64() * 1e3;
    if method == Method::Hierarchical {
        local_limit_note(&mesh, &profile);
    }
    log::info!("{}", solved.timings.line());

    let t = Instant::now();
    let tone = tone_map(args, scene.exposure);
    let hdr = format == ImageFormat::Exr;
    let (image, adapter) =
        lucent::still::draw(ctx, scene, size, tone, &mesh, solved, !args.no_env_background, hdr)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok((image, Timings { solve_ms, render_ms, adapter, links: solved.links }))
}

/// Shopf 2007: Heterogeneous Translucent Shadow Maps, rendered entirely on the GPU.
fn render_htsm(scene: &Scene, args: &RenderArgs, format: ImageFormat) -> Result<(Frame, Timings)> {
    htsm::render(scene, args, format)
}

pub(crate) fn tone_map(args: &RenderArgs, exposure: f32) -> ToneMap {
    ToneMap {
        exposure,
        gamma: args.gamma,
        operator: match args.tonemap {
            ToneCurve::Gamma => ToneOperator::Gamma,
            ToneCurve::Aces => ToneOperator::AcesFilmic,
        },
        ..Default::default()
    }
}
