//! Command-line interface (clap).

use clap::{Args, Parser, Subcommand, ValueEnum};
use lucent_core::bssrdf::ProfileKind;
use lucent_core::mesh::refine::Refine;
pub use lucent_core::session::{Method, SolveMode};
use lucent_core::shading::SingleScattering;
use lucent_core::solver::Oracle;
use lucent_core::solver::transmission::Transmission;
use std::path::{Path, PathBuf};

mod parse;
pub use parse::{HierarchyChoice, parse_rgb};
use parse::{names, parse_albedo, parse_hierarchy, parse_mfp, parse_oracle, parse_profile, parse_refine};
use parse::{parse_single_scattering, parse_transmission};

#[derive(Parser, Debug)]
#[command(
    name = "lucent",
    version,
    about = "Interactive rendering of translucent objects (Mertens et al. 2003; Shopf 2007)",
    after_help = "Examples:\n  \
        lucent render                                   # the embedded default scene -> lucent.png\n  \
        lucent render --mesh bunny.obj --material skimmilk --scale 0.05 --out bunny.png\n  \
        lucent render --light point:0,2,-3 --light dir:0,-1,0 --width 1024 --height 768\n  \
        lucent render --scene examples/scenes/bunny_courtyard.toml --out courtyard.png\n  \
        lucent render --deform twist:60 --frames 30 --out frames/  # frames/frame_0001.png ...\n  \
        lucent bench formfactor --json\n  \
        lucent view --mesh bunny.obj"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand, Debug)]
// Parsed once per process: the size of the render variant (with its HTSM options) is irrelevant.
#[allow(clippy::large_enum_variant)]
pub enum Command {
    /// Render a translucent mesh to a PNG image (the default command).
    Render(RenderArgs),
    /// Measure accuracy and speed; `--json` prints machine-readable rows.
    Bench(BenchArgs),
    /// Open the interactive viewer.
    View(ViewArgs),
}

impl Default for Command {
    /// `lucent` with no subcommand renders the default scene.
    fn default() -> Self {
        let cli = Cli::parse_from(["lucent", "render"]);
        cli.command.expect("render is a subcommand")
    }
}

#[derive(Args, Debug, Clone)]
#[command(after_help = "Examples:\n  \
    lucent render --mesh bunny.obj --material marble --scale 0.1 --light dir:1,-1,1 --out m.png\n  \
    lucent render --method exact --mesh small.ply --out exact.png\n  \
    lucent render --scene examples/scenes/candle.toml --out candle.png\n  \
    lucent render --env courtyard --material marble --scale 0.1\n  \
    lucent render --scene examples/scenes/candle.toml --frames 48 --out frames/\n  \
    lucent render --frames 36 --orbit-light --out orbit/\n\n\
    Precedence: a flag given on the command line overrides the scene file's value (--mesh, \
    --material, --scale, --exposure, --yaw, --pitch, --distance, --deform, --env, --env-rotation); \
    any --light replaces all of the scene's lights; --no-shadows turns off every light's shadows. \
    Values neither given nor in the scene take the defaults shown.")]
pub struct RenderArgs {
    /// Scene file (TOML; see examples/scenes/): mesh, material, scale, exposure, lights,
    /// environment, camera and deformations. Flags given explicitly override it.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Mesh file (OBJ, PLY, OFF, glTF/GLB); the scene's mesh, else the embedded bunny.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Material preset (case-insensitive): apple, chicken1, chicken2, cream, ketchup, marble,
    /// potato, skimmilk, skin1, skin2, wholemilk, wax. Default: the scene's, else a glTF mesh's own (README), else skimmilk.
    #[arg(long)]
    pub material: Option<String>,
    /// Material by colour: the albedo R,G,B a flat, thick slab of it shows under uniform light
    /// (linear, each 0.001..=0.999), with --mfp; lucent finds sigma_s' and sigma_a by inverting
    /// the pbd profile's effective albedo (eta 1.3) and prints them. Scene key:
    /// `material = { albedo = [..], mfp = [..], eta = 1.3 }`.
    #[arg(long, value_name = "R,G,B", value_parser = parse_albedo, requires = "mfp", conflicts_with = "material")]
    pub albedo: Option<[f64; 3]>,
    /// Material by distance: the reduced mean free path R,G,B (scatter distance 1 / sigma_t',
    /// mm, each 0.0001..=1e3) that goes with --albedo.
    #[arg(long, value_name = "R,G,B", value_parser = parse_mfp, requires = "albedo")]
    pub mfp: Option<[f64; 3]>,
    /// Model scale: the largest side of the mesh's bounding box, in metres. Default: the
    /// scene's, else 0.05.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::SCALE_M), allow_negative_numbers = true)]
    pub scale: Option<f64>,
    /// A light: `point:x,y,z` (mesh units) or `dir:x,y,z` (direction the light travels).
    /// Repeatable; replaces the scene's lights. White; a point light gives irradiance 1 at the
    /// distance of the object's centre, a directional light irradiance 1. Default: the scene's
    /// lights, else (without an environment) a key light in front, above and to the right, and
    /// a back light behind and above.
    #[arg(long)]
    pub light: Vec<String>,
    /// Lights cast no shadows (by default command-line lights cast BVH ray-cast shadows and
    /// scene lights follow their `shadows` flag).
    #[arg(long)]
    pub no_shadows: bool,
    /// Bounces of subsurface light between facing parts of the object through the air (a
    /// crevice, feet under a body): 0 switches them off. Up to 64 rays per face, traced once
    /// until the mesh moves; each bounce then gathers over the stored links again (links anew
    /// on the fly). Default: the scene's `bounces`, else 3.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::BOUNCES), allow_negative_numbers = true)]
    pub bounces: Option<u32>,
    /// Splits of every face into four before the solve (the surface stays where it is): `auto`
    /// splits until the mean edge is at most 6 reduced mean free paths of the most opaque
    /// channel, at most twice and not past 1M faces, so B and single scattering resolve a
    /// shadow edge, except where transport is far below the mean face (dense materials: the
    /// local limit B = R_d E is taken at the vertices instead) and for `--method exact` (it
    /// says what the splits would cost); a count 0..=3 forces it. Not for `--method htsm`.
    /// Default: the scene's `refine`, else auto.
    #[arg(long, value_parser = parse_refine)]
    pub refine: Option<Refine>,
    /// Corrections of the default path left out, for measuring each against the path tracer
    /// (`validation/lucent_validation.py ablate`, docs/corrections.md): comma-separated names
    /// of `lucent_core::session::Ablations::NAMES`. Hidden: not for pictures.
    #[arg(long, hide = true, value_name = "NAME[,NAME]")]
    pub ablate: Option<lucent_core::session::Ablations>,
    /// Environment light and reflection map: `courtyard`, `forest` (the maps in assets/) or an
    /// equirectangular .hdr/.exr path. Replaces the scene's environment.
    #[arg(long)]
    pub env: Option<String>,
    /// Rotation of the environment about +Y, degrees. Default: the scene's, else 0.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::ANGLE_DEG), allow_negative_numbers = true)]
    pub env_rotation: Option<f32>,
    /// Keep the flat background with an environment (by default the map is drawn behind the
    /// object, at the environment's intensity).
    #[arg(long)]
    pub no_env_background: bool,
    /// Image width in pixels.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::IMAGE_SIDE), allow_negative_numbers = true, default_value_t = 800)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::IMAGE_SIDE), allow_negative_numbers = true, default_value_t = 600)]
    pub height: u32,
    /// Output file (PNG, or OpenEXR when it ends in .exr); with --frames, the output directory
    /// (created if its parent exists). Default lucent.png (lucent.exr with --format exr), or
    /// frames/ with --frames.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Output format: `png` (tone-mapped 8-bit) or `exr` (linear radiance before exposure and
    /// tone curve, R, G, B premultiplied by A = coverage of the object, 32-bit float; the
    /// background is 0 with alpha 0). Default: exr when --out ends in .exr, else png; with
    /// --frames, png (frame_0001.png, or frame_0001.exr with --format exr).
    #[arg(long, value_enum)]
    pub format: Option<ImageFormat>,
    /// Switch off the surface reflection (the Fresnel-weighted environment reflection) and the
    /// specular highlight (HTSM: its lit-side diffuse and specular terms too), leaving only the
    /// subsurface term F_t B / pi. Scene key: `surface = false`.
    #[arg(long)]
    pub no_surface: bool,
    /// Diffusion profile (homogeneous methods): `pbd` (photon beam diffusion, Habel et al.
    /// 2013, multiple and single scattering; default), `dipole` (Jensen et al. 2001 in distance
    /// form) or `mertens` (the paper's dipole on the receiver's normal, to reproduce its
    /// tables). Scene key `profile`.
    #[arg(long, value_parser = parse_profile)]
    pub profile: Option<ProfileKind>,
    /// Single scattering: `view` (default; also `on`: integrated along the refracted view ray
    /// through the object, shadowed, per vertex), `profile` (PBD's tabulated term in the
    /// diffusion profile, a function of distance only) or `off`. The mertens profile has none.
    /// Scene key `single_scattering`.
    #[arg(long, value_parser = parse_single_scattering)]
    pub single_scattering: Option<SingleScattering>,
    /// How the view terms (the body's chord along the view ray, view-ray single scattering)
    /// are evaluated: `per-eye` (default; rays traced for the eye, the reference) or `split`
    /// (what the viewer shows while the camera moves: an eye-independent part per pose and
    /// light, closed forms per eye; docs/speed.md gives the difference).
    #[arg(long, default_value = "per-eye", value_parser = |s: &str| s.parse::<lucent_core::session::ViewTerms>())]
    pub view_terms: lucent_core::session::ViewTerms,
    /// Light that crosses the body to a face on its far side (homogeneous profiles with a
    /// finite-body gain): `curved` (default: the exact transmittance of a slab of the face's
    /// thickness in place of the profile's far-side share on slab-like parts, and of a sphere
    /// of that diameter, by random walk, on curved ones, the latter at `eta = 1` only;
    /// docs/transmission.md), `slab` (the slab's alone) or `halfspace` (the profile at the
    /// chord, as before issue 50).
    #[arg(long, value_parser = parse_transmission)]
    pub transmission: Option<Transmission>,
    /// Solver: `hierarchical` (Mertens 2003's hierarchical boundary elements, default), `exact`
    /// (every face against every face, O(N^2): the reference) or `htsm` (Heterogeneous
    /// Translucent Shadow Maps on the GPU, Shopf 2007).
    #[arg(long, default_value = "hierarchical", value_parser = names::<Method>(&Method::ALL.map(Method::name)))]
    pub method: Method,
    /// Mesh hierarchy of the hierarchical solve (Mertens §5.1): `face-cluster` (§5.1.1, over the
    /// input mesh) or `shrink-wrap:LEVELS` (§5.1.2: the input, which must be closed and genus 0,
    /// is resampled by an icosahedron subdivided LEVELS times, 20 x 4^LEVELS triangles, LEVELS
    /// 0..=9; that wrapped mesh is what is solved and rendered).
    #[arg(long, default_value = "face-cluster", value_parser = parse_hierarchy)]
    pub hierarchy: HierarchyChoice,
    /// Refinement oracle of the hierarchical solve (Mertens §5.2): `transport` (default: the
    /// profile's thresholds, ε1 = 0.3, ε2 = 0.1, ε_abs = 5e-4 for pbd, 0.1, 0.03, 3e-4 for
    /// dipole, 0.3, 0.1, 1e-3 for mertens, ε_share = 0, contrast 1, within 1% of exact on the bunny),
    /// `transport:EPS1,EPS2[,EPS_ABS[,EPS_SHARE[,CONTRAST]]]`,
    /// `transport-constant:EPS1,EPS2[,...]` (one value per receiver cluster, as the paper,
    /// instead of a value and its gradient: to compare), `transport-linear:EPS1,EPS2[,...]` (a
    /// value and its gradient, without the curvature), or the paper's solid angles `solid-angle:EPS1,EPS2` (steradians). Larger
    /// thresholds: fewer links, faster, less accurate (`lucent bench solver --sweep` measures
    /// the trade).
    #[arg(long, default_value = "transport", value_parser = parse_oracle)]
    pub oracle: Oracle,
    /// Mode of the hierarchical solve (Mertens §5.5): `on-the-fly` (refine and gather from
    /// scratch, no stored links), `render` (store the links, then pull, gather and push over
    /// them), `incremental` (link on the rest mesh, then update the links to the deformed
    /// one) or `refit` (link on the rest mesh, keep the links and re-evaluate their
    /// coefficients on the deformed one, relinking where a sampled error estimate asks).
    /// Default for one image: render with bounces between parts (links made once, each bounce
    /// a gather; on the fly if the links would not fit in half the free memory), on-the-fly
    /// without; refit for an animation.
    #[arg(long, value_parser = names::<SolveMode>(&SolveMode::ALL.map(SolveMode::name)))]
    pub mode: Option<SolveMode>,
    /// Deform the mesh before solving: `twist:DEGREES`, `bump:x,y,z,radius,height` (mesh
    /// units) or `noise:amplitude,frequency`; replaces the scene's deformations. With `--mode
    /// incremental` the links are made on the rest mesh and updated incrementally to the
    /// deformed one.
    #[arg(long)]
    pub deform: Option<String>,
    /// Render an animation of N frames into the --out directory (frame_0001.png, ...): the
    /// deformation ramped from the rest pose to full (a noise deformation flows through the
    /// surface instead), or with --orbit-light the lights turning once about the vertical axis
    /// through the object.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::FRAMES), allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// With --frames: move the lights on a circle about the vertical axis through the object's
    /// centre (one full turn over the animation) instead of ramping the deformation.
    #[arg(long, requires = "frames")]
    pub orbit_light: bool,
    /// Exposure multiplier applied to radiance before tone mapping. Default: the scene's,
    /// else 1.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::EXPOSURE), allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// Tone curve: `gamma` (clamp, then the gamma curve, as in the paper) or `aces` (a filmic
    /// roll-off of highlights, then the gamma curve).
    #[arg(long, value_enum, default_value_t = ToneCurve::Gamma)]
    pub tonemap: ToneCurve,
    /// Display gamma of the tone curve.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::GAMMA), allow_negative_numbers = true, default_value_t = 2.2)]
    pub gamma: f32,
    /// Camera yaw about the vertical axis, degrees (0: looking along -z; lights default
    /// behind). Default: the scene's, else 0.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::ANGLE_DEG), allow_negative_numbers = true)]
    pub yaw: Option<f32>,
    /// Camera pitch above the horizon, degrees (-89..89). Default: the scene's, else 15.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::PITCH_DEG), allow_negative_numbers = true)]
    pub pitch: Option<f32>,
    /// Camera distance from the object's centre in bounding-sphere radii (> 1); by default the
    /// scene's, else the object just fits the image.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::CAMERA_DISTANCE), allow_negative_numbers = true)]
    pub distance: Option<f32>,
    /// HTSM options (`--method htsm`, Shopf 2007).
    #[command(flatten)]
    pub htsm: HtsmArgs,
}

impl RenderArgs {
    /// What these flags say about the scene (the rest are about the image and its output).
    pub fn overrides(&self) -> lucent::scene::Overrides {
        lucent::scene::Overrides {
            scene: self.scene.clone(),
            mesh: self.mesh.clone(),
            material: self.material.clone(),
            colour: self.albedo.zip(self.mfp),
            scale: self.scale,
            exposure: self.exposure,
            profile: self.profile,
            single_scattering: self.single_scattering,
            transmission: self.transmission,
            lights: self.light.clone(),
            no_shadows: self.no_shadows,
            bounces: self.bounces,
            refine: self.refine,
            env: self.env.clone(),
            env_rotation: self.env_rotation,
            deform: self.deform.clone(),
            yaw: self.yaw,
            pitch: self.pitch,
            distance: self.distance,
            no_surface: self.no_surface,
            method: Some(self.method),
            mode: self.mode,
            // Plain `transport` means the profile's own thresholds.
            oracle: (self.oracle != Oracle::default()).then_some(self.oracle),
            ablate: self.ablate.unwrap_or_default(),
            ..Default::default()
        }
    }
}

/// Options of `--method htsm` (Heterogeneous Translucent Shadow Maps, Shopf 2007). Lengths are in
/// *object units*: fractions of the mesh's largest bounding-box side.
#[derive(Args, Debug, Clone)]
pub struct HtsmArgs {
    /// Density volume over the mesh's bounding box: `veins[:SEED[:SCALE]]` (marble/mineral
    /// veins), `cube[:SIZE]` (dense cube inside a clear body, Shopf fig. 5.8), `uniform:D`
    /// (D in 0..1), `raw:PATH:NXxNYxNZ:u8|u16|f32` or `file:PATH` (lucent's LVOL format).
    #[arg(long, default_value = "veins", help_heading = "HTSM (--method htsm)")]
    pub volume: String,
    /// Voxels along the largest side of procedural volumes (other sides follow the box).
    #[arg(long, default_value_t = 64, help_heading = "HTSM (--method htsm)")]
    pub volume_res: u32,
    /// Sample rays per pixel in the hierarchical pattern: 1, 5, 9 or 13 (Shopf fig. 4.3).
    #[arg(long, default_value_t = 9, help_heading = "HTSM (--method htsm)")]
    pub samples: u32,
    /// Ray-cast steps through the density volume per sample ray.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::HTSM_STEPS), allow_negative_numbers = true, default_value_t = 16, help_heading = "HTSM (--method htsm)")]
    pub steps: u32,
    /// Absorption the density adds at density 1, mm^-1: one number (grey) or R,G,B, each in
    /// 0..=1000. The medium is the scene's material (sigma_s', sigma_a, eta) with absorption
    /// sigma_a + density * this; HTSM attenuates by its diffusion coefficient (docs/htsm.md).
    /// Default 0.5.
    #[arg(long, allow_negative_numbers = true, help_heading = "HTSM (--method htsm)")]
    pub density_absorption: Option<String>,
    /// Former input (no physical medium; replaces the scene's material for HTSM): transport
    /// colour r,g,b (each in (0, 1]), the colour light takes after the transport distance.
    /// Default 0.9,0.6,0.3, or the glTF file's KHR_materials_volume attenuationColor.
    #[arg(long, alias = "transport-color", help_heading = "HTSM (--method htsm)")]
    pub transport_colour: Option<String>,
    /// Former input (as --transport-colour): transport distance, object units (> 0). Default
    /// 0.5, or the glTF file's KHR_materials_volume attenuationDistance divided by the mesh's
    /// largest side.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::TRANSPORT_DISTANCE), allow_negative_numbers = true, help_heading = "HTSM (--method htsm)")]
    pub transport_distance: Option<f32>,
    /// Henyey-Greenstein asymmetry g in (-1, 1) of HTSM's phase weight. Default 0 with the
    /// scene's material (its sigma_s' is the isotropic equivalent), 0.3 with the former inputs.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::PHASE_G), allow_negative_numbers = true, help_heading = "HTSM (--method htsm)")]
    pub phase_g: Option<f32>,
    /// Former input (as --transport-colour): extra absorption of density 1, per object unit
    /// (sigma_at = sigma_a + scale * density). Default 20.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::DENSITY_SCALE), allow_negative_numbers = true, help_heading = "HTSM (--method htsm)")]
    pub density_scale: Option<f32>,
    /// Also write the density volume HTSM renders to PATH in lucent's LVOL format (e.g. for a
    /// path tracer's grid volume).
    #[arg(long, value_name = "PATH", help_heading = "HTSM (--method htsm)")]
    pub volume_out: Option<std::path::PathBuf>,
    /// Transport model: `diffusion` (samples weighted by the medium's diffusion kernel, the
    /// default with the scene's material), `beer-lambert` (exp(-sigma D - alpha), the default
    /// with the former inputs, which have no medium for `diffusion`) or `thesis` (Shopf table
    /// 4.1). docs/htsm.md measures each against a path tracer.
    #[arg(long, value_enum, help_heading = "HTSM (--method htsm)")]
    pub htsm_model: Option<HtsmModel>,
    /// Side of the light-view reference images, texels (16..=device limit).
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::HTSM_SIZE), allow_negative_numbers = true, default_value_t = 256, help_heading = "HTSM (--method htsm)")]
    pub htsm_size: u32,
}

/// The file format of `lucent render --out` (`--format`).
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImageFormat {
    /// Tone-mapped, gamma-encoded 8-bit RGBA PNG (what the eye sees).
    #[default]
    Png,
    /// Linear HDR radiance and coverage, 32-bit float RGBA OpenEXR (what a path tracer compares).
    Exr,
}

impl ImageFormat {
    /// The file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            ImageFormat::Png => "png",
            ImageFormat::Exr => "exr",
        }
    }

    /// `--format` if given; else `exr` when `out` is a single file ending in `.exr`
    /// (case-insensitive); else `png`. A `--frames` directory has no extension to go by.
    pub fn resolve(flag: Option<ImageFormat>, out: Option<&Path>, frames: bool) -> ImageFormat {
        if let Some(f) = flag {
            return f;
        }
        let exr = !frames
            && out
                .and_then(|p| p.extension())
                .and_then(|e| e.to_str())
                .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if exr { ImageFormat::Exr } else { ImageFormat::Png }
    }
}

/// HTSM transport model.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HtsmModel {
    /// Shopf's table 4.1: T_c (1/n) sum E_i max(0, (2 T_d - (D_i + alpha_i)) / T_d) f(theta_i).
    Thesis,
    /// (1/n) sum E_i exp(-sigma D_i - alpha_i) f(theta_i), sigma = -ln(T_c) / T_d.
    #[default]
    BeerLambert,
    /// Each sample weighs the diffusion kernel over the area it stands for, times the
    /// half-space's albedo (lit side) or the slab's transmittance (through the body).
    Diffusion,
}

/// Tone curve of `lucent render`.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneCurve {
    /// Exposure, clamp to 0..1, gamma curve (Mertens 2003 §5.4).
    #[default]
    Gamma,
    /// Exposure, Narkowicz's ACES filmic fit, gamma curve.
    Aces,
}

#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// What to measure.
    #[arg(value_enum)]
    pub what: BenchTarget,
    /// Print one JSON object per line instead of a table.
    #[arg(long)]
    pub json: bool,
    /// `bench solver` only: sweep the oracle thresholds against error and link count.
    #[arg(long)]
    pub sweep: bool,
    /// `bench solver` only: Mertens table 5 (form factor against point sampling).
    #[arg(long)]
    pub table5: bool,
    /// `bench solver` only: the bunny and the dragons `scripts/fetch_dragon.sh` fetched.
    #[arg(long)]
    pub real: bool,
    /// `bench solver` only: cost over sigma (1e-4..1e3 mm^-1) and scale (1 mm..10 m), bunny.
    #[arg(long)]
    pub locality: bool,
    /// `bench solver` table 3 and `--real`, `bench energy`: the oracle (as `render --oracle`:
    /// plain `transport` is the profile's own thresholds), e.g. `solid-angle:0.2,0.8`.
    #[arg(long, value_parser = parse_oracle)]
    oracle: Option<Oracle>,
    /// `bench energy` only: the mesh (a file, or a built-in name: bunny, candle, cube, sphere).
    /// Default bunny.
    #[arg(long)]
    pub mesh: Option<String>,
    /// `bench energy` only: the material preset. Default marble.
    #[arg(long)]
    pub material: Option<String>,
    /// `bench energy` only: model scale, metres (> 0). Default 0.1.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::SCALE_M), allow_negative_numbers = true)]
    pub scale: Option<f64>,
    /// `bench energy` only: the diffusion profile (as `lucent render --profile`). Default pbd.
    #[arg(long, value_parser = parse_profile)]
    pub profile: Option<ProfileKind>,
}

impl BenchArgs {
    /// The oracle asked for, `None` for the profile's own ([`Oracle::for_profile`]): as for
    /// `render`, plain `transport` (the default thresholds) means the profile's.
    pub fn oracle(&self) -> Option<Oracle> {
        self.oracle.filter(|o| *o != Oracle::default())
    }
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchTarget {
    /// Colour materials: for requested slab albedos (0.05..0.99) and mean free paths (0.1, 1,
    /// 10 mm) at eta 1.3 and 1.0, the albedo a large flat slab renders (hierarchical solve, and
    /// the exact solve beside it), and the relative errors.
    Albedo,
    /// What a user's action costs (light, camera, material, bump, twist) per stage on the bunny
    /// and the fetched dragons, and its error against a fresh solve (LUCENT_BENCH_MAX_TRIANGLES,
    /// default 60000; LUCENT_BENCH_MIN_TRIANGLES, LUCENT_BENCH_MATERIAL as for `solver --real`).
    Interactive,
    /// Energy under uniform irradiance 1: the largest B per face with and without the energy
    /// bound (`max_b_uniform` must not exceed 1) on `--mesh`.
    Energy,
    /// Semi-analytic form factor against converged Monte Carlo (Mertens fig. 3).
    Formfactor,
    /// Hierarchical solver: Mertens table 3 (links, on-the-fly, incremental and render times on
    /// a marble butterfly model at 2.5 cm); `--sweep`, `--table5`.
    Solver,
    /// HTSM frame time for n = 1, 5, 9, 13 at 512^2 and 1024^2 (Shopf fig. 5.9).
    Htsm,
}

#[derive(Args, Debug, Clone)]
#[command(after_help = "Mouse: left-drag orbits (or dents / picks, per the panel's tool), right or \
    middle drag pans, the wheel zooms. Keys: F12 or P saves a screenshot \
    (lucent-YYYYMMDD-HHMMSS.png), Escape quits.\n\n\
    Examples:\n  \
    lucent view --mesh bunny.obj --material marble --scale 0.1\n  \
    xvfb-run -a lucent view --frames 20 --script \"dent:0.1,0.2,0.3;light:0,1,-2\" --screenshot out.png\n\n\
    Script actions (separated by ';'; each runs once the previous one's solution is drawn):\n  \
    dent:x,y,z  light:x,y,z  twist:k  material:NAME  scale:M  camera:YAW,PITCH,DIST\n  \
    exposure:K  clusters:x,y,z  method:htsm|mertens  shot:PATH  animate:SECONDS\n  \
    albedo:R,G,B,MFP_R,MFP_G,MFP_B (slab albedo, mean free paths in mm)  save:NEW.toml (material as a scene)\n\
    Positions are in normalised mesh units: the mesh is centred with a bounding-box side of 1.")]
pub struct ViewArgs {
    /// Mesh file (OBJ, PLY, OFF, glTF/GLB); the scene's mesh, else the embedded bunny.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Material preset (case-insensitive), as for `lucent render` [default: the scene's, else
    /// skimmilk].
    #[arg(long)]
    pub material: Option<String>,
    /// Model scale: the largest side of the mesh's bounding box, in metres [default: the
    /// scene's, else 0.05].
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::SCALE_M), allow_negative_numbers = true)]
    pub scale: Option<f64>,
    /// Scene file (TOML, as for `lucent render`): mesh, material, scale, exposure, lights and
    /// environment (courtyard or forest); its deformations are baked into the starting mesh.
    /// Flags given beside it win, as for `lucent render`.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Save a PNG of the final frame (3D view and panel) to this path, then exit (scripted run).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Scripted run: draw at least N frames (default 10 when --script or --screenshot is given),
    /// then exit once every scripted action's solution has been drawn.
    #[arg(long)]
    pub frames: Option<u64>,
    /// Scripted actions, e.g. "dent:0.1,0.2,0.3;light:0,1,-2" (see below).
    #[arg(long)]
    pub script: Option<String>,
    /// Window width, logical pixels.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::IMAGE_SIDE), allow_negative_numbers = true, default_value_t = 1100)]
    pub width: u32,
    /// Window height, logical pixels.
    #[arg(long, value_parser = crate::ranges::parser(crate::ranges::IMAGE_SIDE), allow_negative_numbers = true, default_value_t = 700)]
    pub height: u32,
}
