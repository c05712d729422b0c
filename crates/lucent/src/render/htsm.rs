//! `lucent render --method htsm`: Heterogeneous Translucent Shadow Maps (Shopf 2007, chapter 4)
//! through [`lucent_gpu::htsm`].
//!
//! The mesh comes from the shared scene loader; the density volume from `--volume`; the material
//! from `--transport-colour` / `--transport-distance`, else from the glTF file's
//! `KHR_materials_volume` (attenuation colour, attenuation distance in mesh units, converted to
//! object units), else the defaults. HTSM renders from every light (point, spot, directional)
//! and the SH environment, with the mesh in the session's pose (the density follows the mesh
//! through its rest-pose coordinates); [`HtsmFrame`] serves single images and `--frames`.

use crate::cli::{HtsmArgs, HtsmModel, ImageFormat, RenderArgs, SolveMode};
use crate::render::output::{Frame, HdrImage};
use crate::render::{Scene, Timings, tone_map};
use anyhow::{Context, Result, bail};
use glam::Vec3;
use lucent_core::bssrdf::Material;
use lucent_core::camera::bounding_sphere;
use lucent_core::mesh::Mesh;
use lucent_core::session::FrameSession;
use lucent_core::volume::{DensityVolume, VolumeSpec};
use lucent_gpu::GpuContext;
use lucent_gpu::htsm::medium::DEFAULT_DENSITY_SIGMA_A;
use lucent_gpu::htsm::{HtsmMedium, HtsmParams, HtsmRenderer, HtsmView, TransportModel, volume_dims_for};
use std::time::Instant;

/// Default transport colour `T_c` (a wax-like orange).
pub const DEFAULT_TRANSPORT_COLOUR: [f32; 3] = [0.9, 0.6, 0.3];
/// Default transport distance `T_d`, object units (half the object's size).
pub const DEFAULT_TRANSPORT_DISTANCE: f32 = 0.5;
/// Default Henyey-Greenstein `g` with the former inputs.
pub const DEFAULT_FORMER_PHASE_G: f32 = 0.3;
/// Default density scale with the former inputs, per object unit.
pub const DEFAULT_DENSITY_SCALE: f32 = 20.0;
/// A transport distance standing in for glTF's infinite attenuation distance (no absorption),
/// object units: far beyond any path through the object.
const CLEAR_TRANSPORT_DISTANCE: f32 = 1.0e4;

/// The GPU side of an HTSM frame across frames: the renderer (reference images, volume,
/// phase table) made once on the rest mesh, then per frame the session's pose, lights and
/// environment.
pub struct HtsmFrame {
    ctx: GpuContext,
    renderer: HtsmRenderer,
    params: HtsmParams,
    camera: lucent_core::camera::CameraView,
    size: (u32, u32),
    /// The summary line's description of the volume and model.
    pub summary: String,
    /// Building the density volume, milliseconds.
    pub volume_ms: f64,
}

impl HtsmFrame {
    /// The renderer for `scene`'s rest mesh with `args`' HTSM options, framed as the scene's
    /// camera says.
    pub fn new(ctx: GpuContext, scene: &Scene, args: &RenderArgs) -> Result<Self> {
        let gltf = match &scene.mesh_path {
            Some(path) if crate::scene::is_gltf(path) => lucent_core::mesh::load_gltf_volume_params(path)?,
            _ => None,
        };
        let medium = htsm_medium(&args.htsm, scene.material(), scene.scale())?;
        let mut params =
            htsm_params(&args.htsm, &scene.mesh, gltf, (medium, scene.material().eta as f32), args)?;
        params.tone = tone_map(args, scene.exposure);
        if !scene.surface {
            // The lit side's Lambert and Blinn-Phong terms: only the transport term remains.
            params.diffuse = 0.0;
            params.specular = 0.0;
        }
        let t = Instant::now();
        let volume = build_volume(&args.htsm, &scene.mesh)?;
        let volume_ms = t.elapsed().as_secs_f64() * 1e3;
        if let Some(path) = &args.htsm.volume_out {
            lucent_core::volume::save_lvol(path, &volume)
                .with_context(|| format!("--volume-out {}", path.display()))?;
        }
        let renderer = HtsmRenderer::new(&ctx, &scene.mesh, &volume, args.htsm.htsm_size)
            .with_context(|| format!("setting up HTSM for {}", scene.source))?;
        let (centre, radius) = bounding_sphere(&scene.mesh.positions);
        let camera = scene.camera.frame(centre, radius, args.width as f32 / args.height as f32);
        let summary = format!(
            "volume {} {}x{}x{}, n = {}, K = {}, {} model, {}; \
             reference images {}^2 + volume = {:.2} MB",
            args.htsm.volume,
            volume.dims[0],
            volume.dims[1],
            volume.dims[2],
            params.samples,
            params.steps,
            model_name(params.model),
            medium_summary(&params, former_inputs(&args.htsm), &medium),
            renderer.reference_size(),
            renderer.memory().thesis_bytes() as f64 / 1e6,
        );
        Ok(HtsmFrame { ctx, renderer, params, camera, size: (args.width, args.height), summary, volume_ms })
    }

    /// Draws the session's current state: its mesh pose (`moved`: the positions changed since
    /// the last draw), every light and the environment; the tone-mapped image, or for
    /// [`ImageFormat::Exr`] the HDR radiance.
    pub fn draw(&mut self, session: &FrameSession, moved: bool, format: ImageFormat) -> Result<Frame> {
        if moved {
            self.renderer.set_positions(&self.ctx, &session.mesh().positions)?;
        }
        let (width, height) = self.size;
        let view = HtsmView {
            camera: self.camera,
            lights: session.lights().iter().map(|l| l.light).collect(),
            environment: session.environment().copied(),
            width,
            height,
        };
        Ok(match format {
            ImageFormat::Png => Frame::Ldr(self.renderer.render(&self.ctx, &view, &self.params)?),
            ImageFormat::Exr => Frame::Hdr(HdrImage {
                width,
                height,
                pixels: self.renderer.render_hdr(&self.ctx, &view, &self.params)?,
            }),
        })
    }

    /// The adapter, for the summary line.
    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }
}

/// Renders `scene` (deformed in full) with HTSM from every light and the environment; returns
/// the frame in `format` and the timings of the summary line.
pub fn render(scene: &Scene, args: &RenderArgs, format: ImageFormat) -> Result<(Frame, Timings)> {
    let ctx = GpuContext::new()?;
    let mut frame = HtsmFrame::new(ctx, scene, args)?;
    let mut session = scene.session(SolveMode::OnTheFly);
    let deformed = scene.deformed(1.0);
    session.set_positions(&deformed.positions);
    let t = Instant::now();
    let image = frame.draw(&session, !scene.deform.is_empty(), format)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    println!("lucent: htsm: {}", frame.summary);
    let timings = Timings { solve_ms: frame.volume_ms, render_ms, adapter: frame.adapter(), links: None };
    Ok((image, timings))
}

/// The summary line's account of the medium.
fn medium_summary(p: &HtsmParams, former: bool, medium: &HtsmMedium) -> String {
    if former {
        return format!(
            "former inputs T_c = {}, T_d = {} object units, density scale {}",
            p.transport_colour, p.transport_distance, p.density_scale
        );
    }
    format!(
        "medium sigma_s' = {} sigma_a = {} + density x {} mm^-1 at {} m (T_c = {}, T_d = {:.3} object units)",
        medium.sigma_s_prime,
        medium.sigma_a,
        medium.density_sigma_a,
        medium.scale_m,
        p.transport_colour,
        p.transport_distance
    )
}

fn model_name(m: TransportModel) -> &'static str {
    match m {
        TransportModel::Thesis => "thesis",
        TransportModel::BeerLambert => "beer-lambert",
        TransportModel::Diffusion => "diffusion",
    }
}

/// Whether any of the former inputs (`--transport-colour`, `--transport-distance`,
/// `--density-scale`) is given: they replace the scene's material as HTSM's medium.
fn former_inputs(h: &HtsmArgs) -> bool {
    h.transport_colour.is_some() || h.transport_distance.is_some() || h.density_scale.is_some()
}

/// The HTSM medium of the scene's `material` (sigma_s', sigma_a in mm^-1) at `scale_m` metres
/// with `--density-absorption` (mm^-1, one number or R,G,B; default
/// [`DEFAULT_DENSITY_SIGMA_A`]).
pub fn htsm_medium(h: &HtsmArgs, material: &Material, scale_m: f64) -> Result<HtsmMedium> {
    let density = match &h.density_absorption {
        None => Vec3::splat(DEFAULT_DENSITY_SIGMA_A),
        Some(s) => match s.trim().parse::<f32>() {
            Ok(v) => Vec3::splat(v),
            Err(_) => Vec3::from(
                crate::cli::parse_rgb::<f32>(s).map_err(|e| anyhow::anyhow!("--density-absorption: {e}"))?,
            ),
        },
    };
    let f = |v: [f64; 3]| Vec3::from(v.map(|x| x as f32));
    let medium = HtsmMedium {
        sigma_s_prime: f(material.sigma_s_prime),
        sigma_a: f(material.sigma_a),
        density_sigma_a: density,
        scale_m: scale_m as f32,
    };
    medium.validate().map_err(|e| anyhow::anyhow!("--density-absorption {density}: {e}"))?;
    Ok(medium)
}

/// The HTSM parameters from the flags. By default the medium is the scene's (`medium`, with
/// its material's `eta`): see [`lucent_gpu::htsm::medium`]. With any former input the
/// attenuation comes from the transport colour and distance instead, falling back on the glTF
/// material's `KHR_materials_volume` (`gltf`) and then on the defaults.
pub fn htsm_params(
    h: &HtsmArgs,
    mesh: &Mesh,
    gltf: Option<([f32; 3], f32)>,
    medium: (HtsmMedium, f32),
    args: &RenderArgs,
) -> Result<HtsmParams> {
    let base = HtsmParams {
        samples: h.samples,
        steps: h.steps,
        model: match h.htsm_model {
            Some(HtsmModel::Thesis) => TransportModel::Thesis,
            Some(HtsmModel::BeerLambert) => TransportModel::BeerLambert,
            Some(HtsmModel::Diffusion) => TransportModel::Diffusion,
            None if former_inputs(h) => TransportModel::BeerLambert,
            None => TransportModel::Diffusion,
        },
        tone: tone_map(args, args.exposure.unwrap_or(1.0)),
        ..HtsmParams::default()
    };
    let params = if former_inputs(h) {
        if h.htsm_model == Some(HtsmModel::Diffusion) {
            bail!(
                "--htsm-model diffusion needs the scene's material as HTSM's medium; it cannot be \
                 combined with --transport-colour, --transport-distance or --density-scale (the \
                 former inputs): use --htsm-model beer-lambert or thesis with them"
            );
        }
        if h.density_absorption.is_some() {
            bail!(
                "--density-absorption sets the medium's absorption; it cannot be combined with \
                 --transport-colour, --transport-distance or --density-scale (the former inputs)"
            );
        }
        former_params(h, mesh, gltf, base)?
    } else {
        let (medium, eta) = medium;
        HtsmParams { phase_g: h.phase_g.unwrap_or(0.0), eta, ..medium.apply(base) }
    };
    params.validate()?;
    Ok(params)
}

/// The former inputs: transport colour and distance, density scale (object units).
fn former_params(
    h: &HtsmArgs,
    mesh: &Mesh,
    gltf: Option<([f32; 3], f32)>,
    base: HtsmParams,
) -> Result<HtsmParams> {
    let extent = mesh.extent();
    let (gltf_colour, gltf_distance) = match gltf {
        // glTF allows 0 in the colour (total absorption) and an infinite distance (none); keep
        // both inside the model's domain.
        Some((c, d)) => (
            Some(Vec3::from(c).clamp(Vec3::splat(1e-4), Vec3::ONE)),
            Some(if d.is_finite() && d > 0.0 { d / extent } else { CLEAR_TRANSPORT_DISTANCE }),
        ),
        None => (None, None),
    };
    let transport_colour = match &h.transport_colour {
        Some(s) => Vec3::from(
            crate::cli::parse_rgb::<f32>(s).map_err(|e| anyhow::anyhow!("--transport-colour: {e}"))?,
        ),
        None => gltf_colour.unwrap_or(Vec3::from(DEFAULT_TRANSPORT_COLOUR)),
    };
    Ok(HtsmParams {
        transport_colour,
        transport_distance: h.transport_distance.or(gltf_distance).unwrap_or(DEFAULT_TRANSPORT_DISTANCE),
        phase_g: h.phase_g.unwrap_or(DEFAULT_FORMER_PHASE_G),
        density_scale: h.density_scale.unwrap_or(DEFAULT_DENSITY_SCALE),
        ..base
    })
}

/// The density volume named by `--volume`; procedural ones get `--volume-res` voxels along the
/// mesh's largest side.
pub fn build_volume(h: &HtsmArgs, mesh: &Mesh) -> Result<DensityVolume> {
    if !(1..=lucent_core::volume::MAX_DIM).contains(&h.volume_res) {
        bail!("--volume-res must be in 1..={}, got {}", lucent_core::volume::MAX_DIM, h.volume_res);
    }
    let spec: VolumeSpec = h.volume.parse()?;
    Ok(spec.build(volume_dims_for(mesh, h.volume_res))?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    fn args(extra: &[&str]) -> RenderArgs {
        let mut v = vec!["lucent", "render", "--method", "htsm"];
        v.extend_from_slice(extra);
        match Cli::parse_from(v).command {
            Some(Command::Render(a)) => a,
            _ => unreachable!(),
        }
    }

    /// Skim milk at 5 cm, eta 1.3.
    fn med() -> (HtsmMedium, f32) {
        let a = args(&[]);
        (htsm_medium(&a.htsm, &Material::by_name("skimmilk").unwrap(), 0.05).unwrap(), 1.3)
    }

    #[test]
    fn by_default_the_medium_is_the_scenes_material() {
        let a = args(&["--density-absorption", "0.1,0.2,0.3"]);
        let m = htsm_medium(&a.htsm, &Material::by_name("skimmilk").unwrap(), 0.05).unwrap();
        assert_eq!(m.density_sigma_a, Vec3::new(0.1, 0.2, 0.3));
        let p = htsm_params(&a.htsm, &cube(), None, (m, 1.0), &a).unwrap();
        assert_eq!((p.eta, p.phase_g), (1.0, 0.0));
        assert_eq!(p.medium, Some(m.coefficients()));
        let a = args(&[]);
        let p = htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap();
        assert_eq!(p.medium.unwrap().density_sigma_a, Vec3::splat(DEFAULT_DENSITY_SIGMA_A * 50.0));
        // The former inputs replace the medium; mixing them with the medium's is an error.
        let a = args(&["--transport-distance", "0.3"]);
        let p = htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap();
        assert_eq!(
            (p.medium, p.phase_g, p.density_scale),
            (None, DEFAULT_FORMER_PHASE_G, DEFAULT_DENSITY_SCALE)
        );
        let a = args(&["--transport-distance", "0.3", "--density-absorption", "1"]);
        let e = format!("{:#}", htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap_err());
        assert!(e.contains("--density-absorption") && e.contains("--transport-distance"), "{e}");
        // The default model: diffusion with the medium, beer-lambert with the former inputs,
        // which have no medium for diffusion (asking for it is an error naming both).
        let a = args(&[]);
        assert_eq!(htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap().model, TransportModel::Diffusion);
        let a = args(&["--transport-distance", "0.3"]);
        assert_eq!(
            htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap().model,
            TransportModel::BeerLambert
        );
        let a = args(&["--transport-distance", "0.3", "--htsm-model", "diffusion"]);
        let e = format!("{:#}", htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap_err());
        assert!(e.contains("--htsm-model diffusion") && e.contains("--transport-distance"), "{e}");
        for bad in ["-1", "1,2", "x", "1e30", "nan"] {
            let a = args(&["--density-absorption", bad]);
            let e = format!(
                "{:#}",
                htsm_medium(&a.htsm, &Material::by_name("skimmilk").unwrap(), 0.05).unwrap_err()
            );
            assert!(e.contains("--density-absorption"), "{bad}: {e}");
        }
    }

    fn cube() -> Mesh {
        Mesh::new(vec![Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)], vec![])
    }

    #[test]
    fn flags_map_to_parameters_and_gltf_fills_what_is_not_given() {
        let a = args(&["--samples", "13", "--transport-colour", "0.5,0.6,0.7", "--phase-g", "-0.2"]);
        let p = htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap();
        assert_eq!((p.samples, p.phase_g), (13, -0.2));
        assert_eq!(p.transport_colour, Vec3::new(0.5, 0.6, 0.7));
        assert_eq!(p.transport_distance, DEFAULT_TRANSPORT_DISTANCE);

        // KHR_materials_volume: distance 0.5 mesh units on a mesh 2 units long = 0.25 object units
        // (with the former inputs; the scene's material has the file's volume otherwise).
        let a = args(&["--density-scale", "20"]);
        let p = htsm_params(&a.htsm, &cube(), Some(([0.2, 0.4, 0.8], 0.5)), med(), &a).unwrap();
        assert_eq!(p.transport_colour, Vec3::new(0.2, 0.4, 0.8));
        assert_eq!(p.transport_distance, 0.25);
        // Explicit flags win over the file.
        let a = args(&["--transport-distance", "0.8"]);
        let p = htsm_params(&a.htsm, &cube(), Some(([0.2, 0.4, 0.8], 0.5)), med(), &a).unwrap();
        assert_eq!(p.transport_distance, 0.8);
        // The extension's defaults: white and infinitely far, i.e. no absorption.
        let p = htsm_params(&a.htsm, &cube(), Some(([1.0; 3], f32::INFINITY)), med(), &args(&[])).unwrap();
        assert!(p.sigma().max_element() < 1e-6);
    }

    #[test]
    fn bad_flags_are_rejected_with_the_flag_named() {
        for (extra, what) in [
            (&["--samples", "4"][..], "samples"),
            (&["--transport-colour", "1,2"][..], "--transport-colour"),
            (&["--transport-colour", "0,0.5,0.5"][..], "transport colour"),
        ] {
            let a = args(extra);
            let e = format!("{:#}", htsm_params(&a.htsm, &cube(), None, med(), &a).unwrap_err());
            assert!(e.contains(what), "{extra:?}: {e}");
        }
        // Numbers out of range are refused by the flag's parser (`crate::ranges`).
        for flag in ["--transport-distance", "--phase-g", "--steps", "--htsm-size"] {
            let value = if flag == "--phase-g" { "1" } else { "0" };
            let e = Cli::try_parse_from(["lucent", "render", "--method", "htsm", flag, value]).unwrap_err();
            assert!(e.to_string().contains(flag) && e.to_string().contains("range"), "{flag}: {e}");
        }
        let a = args(&["--volume", "marble"]);
        let e = format!("{:#}", build_volume(&a.htsm, &cube()).unwrap_err());
        assert!(e.contains("marble"), "{e}");
        let a = args(&["--volume", "file:/nonexistent/v.lvol"]);
        let e = format!("{:#}", build_volume(&a.htsm, &cube()).unwrap_err());
        assert!(e.contains("/nonexistent/v.lvol"), "{e}");
    }
}
