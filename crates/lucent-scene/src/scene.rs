//! Scenes: the file format ([`SceneFile`], TOML: mesh, material, scale, lights, environment,
//! camera, deformations and exposure in one file) and the one resolved [`Scene`] that the
//! command line's flags and a scene file resolve into (defaults and validation in one place),
//! for `lucent render`, the benches and the viewer. See
//! `examples/scenes/*.toml` for complete examples.
//!
//! ```toml
//! mesh = "bunny"              # a built-in name, or a file path relative to this file (inside its folder)
//! material = "marble"         # a preset, { sigma_s_prime = [..], sigma_a = [..], eta = 1.3 }
//!                             # or { albedo = [0.9, 0.7, 0.5], mfp = [1.0, 0.5, 0.25] } (mm)
//! scale = 0.05                # largest bounding-box side, metres
//! exposure = 1.0
//! surface = true             # false: subsurface term only (no reflection, no highlight)
//! profile = "pbd"             # diffusion profile, as --profile
//! single_scattering = "view"  # along the view ray (default), "profile" or "off"
//! transmission = "curved"     # light crossing the body: "curved" (default), "slab" or "halfspace"
//! deform = ["twist:30"]       # twist:DEGREES, bump:x,y,z,radius,height, noise:amplitude,frequency
//!
//! [[light]]                   # any number; every type and key: `LightSpec` (scene/light.rs)
//! type = "spot"
//! position = [0.0, 2.0, 1.0]  # mesh units
//! direction = [0.0, -1.0, -0.5]
//! color = [1.0, 0.9, 0.8]
//! intensity = 1.0
//! cone_angle = 30.0           # half-angle, degrees
//! soft_edge = 0.2             # fraction of the cone over which it fades
//! shadows = true
//!
//! [environment]
//! path = "courtyard"          # built-in probe (courtyard, forest) or an .hdr/.exr file beside this one
//! rotation = 90.0             # degrees about +Y
//! intensity = 1.0
//!
//! [camera]
//! yaw = 30.0                  # degrees
//! pitch = 15.0                # degrees
//! distance = 3.0              # bounding-sphere radii (optional: frame the object)
//! fov = 35.0                  # vertical, degrees
//! ```
//!
//! Files a scene names must lie inside the scene file's folder (no absolute paths, no `..`, no
//! links leading out), so a scene from elsewhere cannot make lucent read other files. Every
//! number is checked against its range in [`crate::ranges`].

use anyhow::{Context, Result, bail};
use glam::Vec3;
use lucent_core::bssrdf::Material;
use lucent_core::camera::OrbitCamera;
use lucent_core::irradiance::{EnvMap, Environment, SceneLight};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::deform::Deformation;
use serde::Deserialize;
use std::path::{Path, PathBuf};

pub mod gltf_material;
mod light;
mod material;
mod meshes;
mod resolve;
pub mod save;
pub use material::{CustomMaterial, MaterialSpec, SingleScatteringKey};
pub use meshes::{
    BUILTIN_MESHES, MeshSource, TexturedMesh, is_gltf, load_mesh_file, load_named_mesh,
    load_textured_mesh_file,
};
use meshes::{builtin_mesh, builtin_mesh_label};

pub use light::{LightSpec, default_lights, orbit_lights, parse_light, parse_three};
pub use resolve::{Overrides, Scene};

/// A scene as read from a TOML file (what [`Scene::resolve`] reads beside the flags). Every field has a default, so an empty file is the default
/// scene (the bunny in skim milk with one light).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The mesh: a built-in name (`"bunny"`, `"candle"`, `"cube"`, `"sphere"`; see
    /// [`SceneFile::load_mesh`]) or a file path (OBJ, PLY, OFF, glTF/GLB) relative to the
    /// scene file's folder. A string with a file extension or a path separator is a path.
    /// Default `"bunny"`.
    #[serde(default = "default_mesh")]
    pub mesh: String,
    /// The material: a preset name (`"skimmilk"`, `"marble"`, `"wax"`, ...) or a table with
    /// `sigma_s_prime` and `sigma_a` (mm^-1, per RGB channel), optional `eta` (default 1.3) and
    /// optional `name`. Default: a glTF mesh's own material (see [`gltf_material`]), else
    /// `"skimmilk"`.
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    /// Model scale: the largest side of the mesh's bounding box, in metres (> 0). Default 0.05.
    #[serde(default = "default_scale")]
    pub scale: f64,
    /// Exposure multiplier applied to radiance before tone mapping (> 0). Default 1.
    #[serde(default = "one")]
    pub exposure: f32,
    /// Whether the surface reflection (Fresnel-weighted environment reflection) and the specular
    /// highlight are drawn; `false` leaves only the subsurface term `F_t B / pi` (as
    /// `lucent render --no-surface`). Default true.
    #[serde(default = "yes")]
    pub surface: bool,
    /// Bounces of subsurface light between facing parts through the air (0..=4; 0 switches
    /// them off), as `lucent render --bounces`. Default 3, or 0 with the `mertens` profile
    /// ([`crate::ranges::default_bounces`]).
    #[serde(default)]
    pub bounces: Option<u32>,
    /// Diffusion profile by name (`lucent_core::bssrdf::ProfileKind::name`; the default
    /// `"pbd"`, photon beam diffusion), as `lucent render --profile`, whose help lists them.
    #[serde(default)]
    pub profile: Option<String>,
    /// Single scattering, as `lucent render --single-scattering`: `"view"` (default), `"profile"`,
    /// `"off"`, or `true` (view) / `false` (off). `mertens` has none.
    #[serde(default)]
    pub single_scattering: Option<SingleScatteringKey>,
    /// Light that crosses the body to a face on its far side, as `lucent render
    /// --transmission`: `"curved"` (default: the exact slab transmittance at the face's
    /// thickness on slab-like parts and a sphere's, by random walk, on curved ones), `"slab"`
    /// (the slab's alone) or `"halfspace"` (the profile at the chord, as before issue 50).
    #[serde(default)]
    pub transmission: Option<String>,
    /// Splits of every face into four before the solve, as `lucent render --refine`: `"auto"`
    /// (default: until the mean edge is at most 6 reduced mean free paths, at most twice) or a
    /// count 0..=3 (`lucent_core::mesh::refine`).
    #[serde(default)]
    pub refine: Option<RefineKey>,
    /// Lights (`[[light]]` tables). Default: none, and the renderer adds its default light when
    /// there is neither a light nor an environment.
    #[serde(default, rename = "light")]
    pub lights: Vec<LightSpec>,
    /// Distant environment light and reflection map. Default: none.
    #[serde(default)]
    pub environment: Option<EnvironmentSpec>,
    /// The orbit camera. Default: the renderer's default framing.
    #[serde(default)]
    pub camera: CameraSpec,
    /// Deformations applied in order, as strings: `twist:DEGREES` (about +Y over the mesh's
    /// height), `bump:x,y,z,radius,height` (mesh units), `noise:amplitude,frequency`.
    /// Default: none.
    #[serde(default)]
    pub deform: Vec<String>,
    /// The folder of the scene file; relative paths inside the file are resolved against it.
    #[serde(skip)]
    pub dir: PathBuf,
}

/// The scene key `refine`: `"auto"` or a number of splits.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum RefineKey {
    /// A number of splits.
    Levels(i64),
    /// `"auto"` (or a number as a string).
    Word(String),
}

impl RefineKey {
    /// What it asks for; an error names the value and the accepted range.
    pub fn refine(&self) -> Result<lucent_core::mesh::refine::Refine, String> {
        match self {
            RefineKey::Levels(n) => n.to_string().parse(),
            RefineKey::Word(w) => w.parse(),
        }
    }
}

fn default_mesh() -> String {
    "bunny".into()
}
fn default_scale() -> f64 {
    resolve::DEFAULT_SCALE_M
}
fn one() -> f32 {
    1.0
}
fn yes() -> bool {
    true
}
fn white() -> [f32; 3] {
    [1.0; 3]
}
/// The `[environment]` table.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSpec {
    /// A built-in probe (`courtyard`, `forest`) or an equirectangular `.hdr` or `.exr` file,
    /// relative to the scene file's folder and inside it.
    pub path: String,
    /// Rotation about +Y, degrees. Default 0.
    #[serde(default)]
    pub rotation: f32,
    /// Radiance multiplier (>= 0). Default 1.
    #[serde(default = "one")]
    pub intensity: f32,
}

/// The `[camera]` table: an orbit camera around the mesh's bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Rotation about +Y, degrees; positive moves the camera towards +X. Default 0.
    #[serde(default)]
    pub yaw: f32,
    /// Elevation above the XZ plane, degrees (-89..89). Default 15.
    #[serde(default = "default_pitch")]
    pub pitch: f32,
    /// Distance from the centre in bounding-sphere radii (> 1). Default: framed to fit.
    #[serde(default)]
    pub distance: Option<f32>,
    /// Vertical field of view, degrees (0..180). Default 35.
    #[serde(default = "default_fov")]
    pub fov: f32,
}

fn default_pitch() -> f32 {
    15.0
}
fn default_fov() -> f32 {
    35.0
}

impl Default for CameraSpec {
    fn default() -> Self {
        CameraSpec { yaw: 0.0, pitch: default_pitch(), distance: None, fov: default_fov() }
    }
}

/// An environment ready for the solver and the renderer.
#[derive(Clone, Debug)]
pub struct LoadedEnvironment {
    /// What named it: a built-in probe's name or the file's path as given.
    pub name: String,
    /// SH coefficients with rotation and intensity, for the leaf irradiance.
    pub environment: Environment,
    /// A 256 x 128 equirect copy of the map for the GPU's Fresnel-weighted reflection, already
    /// rotated by the scene's rotation (to the nearest 360/256 degrees), intensity not applied
    /// (pass it as the shading's environment weight). Same mapping as `lucent-gpu`'s
    /// `equirect_uv` in `mesh.wgsl`.
    pub reflection: EnvMap,
}

impl LoadedEnvironment {
    /// The reflection texels as RGBA (alpha 1), rows top first, for
    /// `lucent_gpu::mesh_pass::EnvironmentMap::from_rgba_f32`.
    pub fn reflection_rgba(&self) -> Vec<[f32; 4]> {
        self.reflection.texels.iter().map(|t| t.extend(1.0).to_array()).collect()
    }
}

impl SceneFile {
    /// Reads and validates a scene file. Errors name the file and, for syntax and type errors,
    /// the line and column.
    pub fn load(path: &Path) -> Result<SceneFile> {
        let bytes = lucent_core::limits::read_input(path)
            .map_err(|reason| anyhow::anyhow!("cannot read scene file {}: {reason}", path.display()))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| anyhow::anyhow!("scene file {}: not UTF-8 text", path.display()))?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        SceneFile::parse(&text, dir).with_context(|| format!("scene file {}", path.display()))
    }

    /// Parses and validates scene text; relative paths resolve against `dir`.
    pub fn parse(text: &str, dir: PathBuf) -> Result<SceneFile> {
        let mut scene: SceneFile =
            toml::from_str(text).map_err(|e| anyhow::anyhow!(toml_error_line(text, &e)))?;
        scene.dir = dir;
        scene.validate()?;
        Ok(scene)
    }

    /// Checks ranges that the types do not express.
    fn validate(&self) -> Result<()> {
        use crate::ranges::{self as r, check};
        let ok = |e: String| anyhow::anyhow!(e);
        check("scale (metres)", self.scale, &r::SCALE_M).map_err(ok)?;
        check("exposure", self.exposure, &r::EXPOSURE).map_err(ok)?;
        if let Some(b) = self.bounces {
            check("bounces", b, &r::BOUNCES).map_err(ok)?;
        }
        self.material()?;
        for (i, l) in self.lights.iter().enumerate() {
            l.validate().with_context(|| format!("light {} ([[light]] #{})", i + 1, i + 1))?;
        }
        if let Some(env) = &self.environment {
            check("environment intensity", env.intensity, &r::INTENSITY).map_err(ok)?;
            check("environment rotation (degrees)", env.rotation, &r::ANGLE_DEG).map_err(ok)?;
        }
        let c = &self.camera;
        if !(c.fov > 0.0 && c.fov < 180.0) {
            bail!("camera fov must be within 0..180 degrees, got {}", c.fov);
        }
        check("camera pitch (degrees)", c.pitch, &r::PITCH_DEG).map_err(ok)?;
        check("camera yaw (degrees)", c.yaw, &r::ANGLE_DEG).map_err(ok)?;
        if let Some(d) = c.distance {
            check("camera distance (bounding-sphere radii)", d, &r::CAMERA_DISTANCE).map_err(ok)?;
        }
        self.deformations()?;
        Ok(())
    }

    /// The material, validated (the default preset when the file names none).
    pub fn material(&self) -> Result<Material> {
        Ok(match &self.material {
            None => Material::by_name(resolve::DEFAULT_MATERIAL)?,
            Some(MaterialSpec::Preset(name)) => Material::by_name(name)?,
            Some(MaterialSpec::Custom(c)) => c.resolve()?,
        })
    }

    /// Where the mesh comes from: a path if the string has an extension or a path separator,
    /// else a built-in name.
    pub fn mesh_source(&self) -> MeshSource {
        let p = Path::new(&self.mesh);
        if p.extension().is_some() || self.mesh.contains(['/', '\\']) {
            MeshSource::File(self.dir.join(p))
        } else {
            MeshSource::Builtin(self.mesh.trim().to_ascii_lowercase())
        }
    }

    /// The deformations, parsed (see `lucent_core::mesh::deform::Deformation`).
    pub fn deformations(&self) -> Result<Vec<Deformation>> {
        Ok(self.deform.iter().map(|d| d.parse::<Deformation>()).collect::<Result<Vec<_>, _>>()?)
    }

    /// Loads or generates the mesh (rest pose, before deformations). Built-in names: `bunny`
    /// (embedded Stanford bunny), `candle`, `cube` (32 x 32 squares per side), `sphere`
    /// (icosphere, 5 subdivisions). Errors name the file or list the known names.
    pub fn load_mesh(&self) -> Result<Mesh> {
        match self.mesh_source() {
            MeshSource::File(_) => {
                // Only files inside the scene's folder: a scene from elsewhere may not read others.
                let path = lucent_core::limits::resolve_inside(&self.dir, &self.mesh)
                    .map_err(|reason| anyhow::anyhow!("mesh: {reason}"))?;
                load_mesh_file(&path)
            }
            MeshSource::Builtin(name) => builtin_mesh(&name),
        }
    }

    /// Loads the mesh like [`SceneFile::load_mesh`] with its texture, if its file has one.
    pub fn load_textured_mesh(&self) -> Result<TexturedMesh> {
        match self.mesh_source() {
            MeshSource::File(_) => {
                let path = lucent_core::limits::resolve_inside(&self.dir, &self.mesh)
                    .map_err(|reason| anyhow::anyhow!("mesh: {reason}"))?;
                load_textured_mesh_file(&path)
            }
            MeshSource::Builtin(name) => Ok((builtin_mesh(&name)?, None)),
        }
    }

    /// The camera as the renderer's orbit camera.
    pub fn camera(&self) -> OrbitCamera {
        OrbitCamera {
            yaw_deg: self.camera.yaw,
            pitch_deg: self.camera.pitch,
            distance: self.camera.distance,
            fov_y_deg: self.camera.fov,
            ..OrbitCamera::default()
        }
    }

    /// The lights for the irradiance computation (see [`LightSpec::light`]), brightness set at
    /// the distance of `center` (mesh units; the centre of the mesh's bounding box).
    pub fn lights(&self, center: Vec3) -> Vec<SceneLight> {
        self.lights.iter().map(|l| l.light(center)).collect()
    }

    /// Loads the environment map (if any), projects it onto SH and makes the 256 x 128
    /// reflection copy. Errors name the map file.
    pub fn environment(&self) -> Result<Option<LoadedEnvironment>> {
        let Some(spec) = &self.environment else {
            return Ok(None);
        };
        let map = match EnvMap::builtin(&spec.path) {
            Some(probe) => probe?,
            None => {
                let path = lucent_core::limits::resolve_inside(&self.dir, &spec.path)
                    .map_err(|reason| anyhow::anyhow!("environment: {reason}"))?;
                EnvMap::load(&path)?
            }
        };
        resolve::environment_of(&spec.path, &map, spec.rotation, spec.intensity).map(Some)
    }
}

/// toml's error as one line: `line L, column C: message` (its default rendering quotes the
/// offending text over several lines).
fn toml_error_line(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
    match e.span() {
        Some(span) => {
            let before = &text.as_bytes()[..span.start.min(text.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            format!("line {line}, column {column}: {message}")
        }
        None => message,
    }
}

#[cfg(test)]
mod tests;
