//! `lucent render`: mesh ─► irradiance at the faces (Mertens §5.3) ─► subsurface solve (§3,
//! §5.2) ─► area-weighted per-vertex `B / pi` (§3.2) ─► GPU raster with the exit Fresnel factor
//! and tone mapping (§5.4) ─► PNG, written atomically.
//!
//! `--method htsm` takes a separate path ([`render_htsm`]): Shopf 2007 renders on the GPU from
//! light-view maps and has no per-vertex solve.

use crate::cli::{Method, RenderArgs, SolveMode, ToneCurve};
use anyhow::{Context, Result, bail};
use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::{Dipole, Material};
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::irradiance::{self, Light};
use lucent_core::mesh::Mesh;
use lucent_core::{shading, solver};
use lucent_gpu::GpuContext;
use lucent_gpu::camera::OrbitCamera;
use lucent_gpu::mesh_pass::{GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::tonemap::{ToneMap, ToneOperator};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `lucent render` works on, after loading and parsing.
pub struct Scene {
    /// Where the mesh came from, for messages (`"embedded bunny"` or the path).
    pub source: String,
    /// The mesh, in mesh units.
    pub mesh: Mesh,
    /// The scattering material.
    pub material: Material,
    /// Dipole coefficients converted to mesh units by the model scale.
    pub dipole: Dipole,
    /// Lights, mesh units.
    pub lights: Vec<Light>,
}

pub fn run(args: &RenderArgs) -> Result<()> {
    check_args(args)?;
    let scene = load_scene(args)?;
    let started = Instant::now();
    let (image, timings) = match args.method {
        Method::Htsm => render_htsm(&scene, args)?,
        method => render_mertens(&scene, args, method)?,
    };
    write_png_atomically(&image, &args.out)?;
    println!(
        "lucent: {}: {} triangles, {} at {} m, {} solve {:.0} ms, render {:.0} ms on {}, total {:.0} ms -> {}",
        scene.source,
        scene.mesh.triangles.len(),
        scene.material.name,
        args.scale,
        method_name(args.method),
        timings.solve_ms,
        timings.render_ms,
        timings.adapter,
        started.elapsed().as_secs_f64() * 1e3,
        args.out.display()
    );
    Ok(())
}

/// Wall-clock times of the stages, for the summary line.
pub struct Timings {
    /// Irradiance plus solve plus per-vertex averaging, milliseconds.
    pub solve_ms: f64,
    /// GPU upload, draw, tone map and read-back (not adapter start-up), milliseconds.
    pub render_ms: f64,
    /// The adapter used, e.g. `"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)"`.
    pub adapter: String,
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Hierarchical => "hierarchical",
        Method::Exact => "exact",
        Method::Htsm => "htsm",
    }
}

/// Rejects bad numbers and an unwritable output location before any work is done.
fn check_args(args: &RenderArgs) -> Result<()> {
    if !(args.scale.is_finite() && args.scale > 0.0) {
        bail!("--scale must be a positive number of metres, got {}", args.scale);
    }
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("--exposure must be a positive number, got {}", args.exposure);
    }
    if !(args.gamma.is_finite() && args.gamma > 0.0) {
        bail!("--gamma must be a positive number, got {}", args.gamma);
    }
    if args.width == 0 || args.height == 0 {
        bail!("--width and --height must be at least 1, got {}x{}", args.width, args.height);
    }
    if let Some(d) = args.distance
        && !(d.is_finite() && d > 1.0)
    {
        bail!("--distance is in bounding-sphere radii and must be > 1, got {d}");
    }
    let dir = output_dir(&args.out);
    if !dir.is_dir() {
        bail!("{}: the output directory {} does not exist", args.out.display(), dir.display());
    }
    Ok(())
}

fn output_dir(out: &Path) -> PathBuf {
    match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Loads the mesh, material and lights named by `args`.
pub fn load_scene(args: &RenderArgs) -> Result<Scene> {
    let (source, mesh) = match &args.mesh {
        Some(path) => (path.display().to_string(), lucent_core::mesh::load_mesh(path)?),
        None => ("embedded bunny".to_string(), lucent_core::mesh::embedded::bunny()),
    };
    let material = Material::by_name(&args.material)?;
    let dipole = Dipole::for_model_scale(&material, mesh.extent() as f64, args.scale);
    let lights = if args.light.is_empty() {
        vec![default_light(&mesh)]
    } else {
        let (center, _) = lucent_gpu::camera::bounding_sphere(&mesh.positions);
        args.light.iter().map(|s| parse_light(s, center)).collect::<Result<Vec<_>>>()?
    };
    Ok(Scene { source, mesh, material, dipole, lights })
}

/// Behind (-z, away from the default camera) and above the object, at 2.5 bounding radii.
fn default_light(mesh: &Mesh) -> Light {
    let (center, radius) = lucent_gpu::camera::bounding_sphere(&mesh.positions);
    let position = center + Vec3::new(0.0, 1.2, -2.2) * radius;
    point_light(position, center)
}

/// A white point light whose irradiance at the object's centre distance is 1 (arbitrary but
/// consistent units), so images look alike whatever the mesh units.
fn point_light(position: Vec3, center: Vec3) -> Light {
    let d2 = position.distance_squared(center).max(1e-12);
    Light::Point { position, intensity: Vec3::splat(d2) }
}

/// Parses `point:x,y,z` (position, mesh units) or `dir:x,y,z` (direction the light travels).
/// Point lights give irradiance 1 at the distance of `center`; directional lights give 1.
pub fn parse_light(spec: &str, center: Vec3) -> Result<Light> {
    let usage = "expected point:x,y,z (position, mesh units) or dir:x,y,z (direction of travel)";
    let (kind, rest) = spec.split_once(':').with_context(|| format!("--light {spec:?}: {usage}"))?;
    let v: Vec<f32> = rest
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("--light {spec:?}: {e}; {usage}"))?;
    let [x, y, z] = v[..] else {
        bail!("--light {spec:?}: {} numbers given; {usage}", v.len());
    };
    let p = Vec3::new(x, y, z);
    if !p.is_finite() {
        bail!("--light {spec:?}: coordinates must be finite");
    }
    match kind.trim().to_ascii_lowercase().as_str() {
        "point" => Ok(point_light(p, center)),
        "dir" | "directional" => {
            if p.length_squared() == 0.0 {
                bail!("--light {spec:?}: a direction cannot be zero");
            }
            Ok(Light::Directional { direction: p.normalize(), irradiance: Vec3::ONE })
        }
        other => bail!("--light {spec:?}: unknown kind {other:?}; {usage}"),
    }
}

/// Per-face `B` by the method chosen.
fn solve_faces(
    method: Method,
    scene: &Scene,
    rest: &Mesh,
    mode: SolveMode,
    face_irradiance: &[Rgb],
) -> Result<Vec<Rgb>> {
    let opts = FormFactorOptions::default();
    Ok(match method {
        Method::Exact => solver::exact::solve(&scene.mesh, &scene.dipole, face_irradiance, &opts),
        Method::Hierarchical => solve_hierarchical(scene, rest, mode, face_irradiance, &opts)?,
        Method::Htsm => bail!("--method htsm has no per-face solve"),
    })
}

/// The hierarchical solve (Mertens §3.2, §5.5) over a face cluster hierarchy, in the mode of
/// `--mode`. `rest` is the undeformed mesh (links of `--mode incremental` are made on it first).
fn solve_hierarchical(
    scene: &Scene,
    rest: &Mesh,
    mode: SolveMode,
    face_irradiance: &[Rgb],
    opts: &FormFactorOptions,
) -> Result<Vec<Rgb>> {
    let h = lucent_core::hierarchy::face_cluster::build(rest);
    let oracle = solver::Oracle::default();
    let mut s = solver::HierarchicalSolver::new(rest.clone(), h, scene.dipole, oracle);
    s.ff_opts = *opts;
    let sol = match mode {
        SolveMode::OnTheFly => {
            s.set_positions(&scene.mesh.positions);
            s.solve_on_the_fly(face_irradiance)
        }
        SolveMode::Render => {
            s.set_positions(&scene.mesh.positions);
            s.solve_render(face_irradiance)
        }
        SolveMode::Incremental => {
            s.link();
            let st = s.update_incremental(&scene.mesh.positions, None);
            log::info!("incremental update: {} links, {:.1} ms", st.links, st.total_ms);
            s.solve_render(face_irradiance)
        }
    };
    log::info!(
        "hierarchical ({mode:?}): {} links, {} form factors, {:.1} ms",
        sol.stats.links,
        sol.stats.form_factors,
        sol.stats.total_ms
    );
    Ok(sol.face_b)
}

/// Mertens 2003: solve on the CPU, then rasterise per-vertex radiance on the GPU.
fn render_mertens(scene: &Scene, args: &RenderArgs, method: Method) -> Result<(image::RgbaImage, Timings)> {
    // `--deform`: solve and draw the deformed mesh (the rest mesh stays for incremental mode).
    let deformed = match &args.deform {
        Some(spec) => {
            let d: lucent_core::mesh::deform::Deformation =
                spec.parse().with_context(|| format!("--deform {spec:?}"))?;
            let mut pos = Vec::new();
            d.apply(&scene.mesh, 1.0, &mut pos);
            Some(Scene {
                source: scene.source.clone(),
                mesh: Mesh::new(pos, scene.mesh.triangles.clone()),
                material: scene.material.clone(),
                dipole: scene.dipole,
                lights: scene.lights.clone(),
            })
        }
        None => None,
    };
    let rest = &scene.mesh;
    let scene = deformed.as_ref().unwrap_or(scene);
    // The adapter first: without one, fail before the (possibly long) solve.
    let ctx = GpuContext::new()?;
    let t = Instant::now();
    let e = irradiance::face_irradiance(&scene.mesh, &scene.lights, scene.material.eta);
    let b = solve_faces(method, scene, rest, args.mode, &e)?;
    let radiance = shading::diffuse_radiance(&scene.mesh.face_to_vertex(&b));
    let solve_ms = t.elapsed().as_secs_f64() * 1e3;

    let t = Instant::now();
    let normals = scene.mesh.vertex_normals();
    let gpu_mesh = GpuMesh::new(&ctx, &scene.mesh.positions, &normals, &radiance, &scene.mesh.triangles)?;
    let renderer = OffscreenRenderer::new(&ctx, args.width, args.height)?;
    let camera = renderer.camera_view(&gpu_mesh, &orbit_camera(args));
    let shading =
        Shading { eta: scene.material.eta as f32, lights: scene.lights.clone(), ..Default::default() };
    renderer.render(&ctx, &gpu_mesh, &camera, &shading, &tone_map(args))?;
    let image = renderer.read_image(&ctx)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok((image, Timings { solve_ms, render_ms, adapter: ctx.describe() }))
}

/// Shopf 2007: Heterogeneous Translucent Shadow Maps, rendered entirely on the GPU.
fn render_htsm(scene: &Scene, args: &RenderArgs) -> Result<(image::RgbaImage, Timings)> {
    crate::render_htsm::render(scene, args)
}

pub(crate) fn orbit_camera(args: &RenderArgs) -> OrbitCamera {
    OrbitCamera { yaw_deg: args.yaw, pitch_deg: args.pitch, distance: args.distance, ..Default::default() }
}

pub(crate) fn tone_map(args: &RenderArgs) -> ToneMap {
    ToneMap {
        exposure: args.exposure,
        gamma: args.gamma,
        operator: match args.tonemap {
            ToneCurve::Gamma => ToneOperator::Gamma,
            ToneCurve::Aces => ToneOperator::AcesFilmic,
        },
        ..Default::default()
    }
}

/// Encodes `image` as PNG into a temporary file next to `out`, then renames it over `out`:
/// readers never see a partial file, and on error `out` is left untouched.
pub fn write_png_atomically(image: &image::RgbaImage, out: &Path) -> Result<()> {
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .context("encoding the PNG")?;
    let name =
        out.file_name().with_context(|| format!("{}: not a file name", out.display()))?.to_string_lossy();
    let tmp = output_dir(out).join(format!(".{name}.{}.png.tmp", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&png)?;
        f.sync_all()?;
        std::fs::rename(&tmp, out)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("{}: cannot write the image", out.display()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_parse_and_bad_ones_are_rejected() {
        let c = Vec3::ZERO;
        assert_eq!(
            parse_light("point:0,3,4", c).unwrap(),
            Light::Point { position: Vec3::new(0.0, 3.0, 4.0), intensity: Vec3::splat(25.0) }
        );
        assert_eq!(
            parse_light("dir: 0, -2, 0", c).unwrap(),
            Light::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::ONE }
        );
        for bad in ["point:1,2", "spot:1,2,3", "point", "dir:0,0,0", "point:a,b,c", "point:1,2,inf"] {
            let e = parse_light(bad, c).unwrap_err().to_string();
            assert!(e.contains(bad), "{bad}: {e}");
        }
    }
}
