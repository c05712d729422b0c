//! The one resolved [`Scene`]: what `lucent render`, the benches and `lucent view` work on,
//! from [`Overrides`] (the command line) and an optional scene file. A value given as a flag
//! wins over the file, the file over the defaults, and every default is written here once.
//! Everything that can fail (files, numbers, names) fails here, before any output exists.

use super::light::{default_lights, parse_light};
use super::{LoadedEnvironment, MeshSource, SceneFile, TexturedMesh};
use anyhow::{Context, Result, bail};
use lucent_core::bssrdf::{Material, ProfileKind};
use lucent_core::camera::OrbitCamera;
use lucent_core::hierarchy::Hierarchy;
use lucent_core::irradiance::{EnvMap, Environment, Light, SceneLight};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::deform::Deformation;
use lucent_core::mesh::refine::{self, Refine};
use lucent_core::mesh::texture::Texture;
use lucent_core::session::{Ablations, FrameSession, FrameSettings, Method, SolveMode, Transport};
use lucent_core::solver::Oracle;
use std::path::{Path, PathBuf};

/// Side of the equirect copy of an environment map that the GPU reflects.
const REFLECTION_SIZE: (usize, usize) = (256, 128);
/// The material when neither a flag nor the file names one.
pub const DEFAULT_MATERIAL: &str = "skimmilk";
/// The model scale when neither a flag nor the file gives one, metres.
pub const DEFAULT_SCALE_M: f64 = 0.05;
/// Relative index of refraction of a material given by colour and distance on the command line.
pub const DEFAULT_ETA: f64 = 1.3;

/// What the command line says about a scene; `None` (or empty, or false) leaves the scene
/// file's value, else the default. Numbers were range-checked by the flags' parsers
/// (`crate::ranges`).
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// A scene file (TOML) to start from.
    pub scene: Option<PathBuf>,
    /// A mesh file (OBJ, PLY, OFF, glTF/GLB).
    pub mesh: Option<PathBuf>,
    /// A mesh given in memory with its name for messages (the Python module's vertex and face
    /// arrays): validated as a loaded file is, and wins over `mesh` and the scene file's.
    pub mesh_data: Option<(String, Mesh)>,
    /// A material preset by name.
    pub material: Option<String>,
    /// A material given in full (the Python module's `Material`): wins over `material`,
    /// `colour` and the scene file's.
    pub material_data: Option<Material>,
    /// A material by colour and distance: slab albedo (0.001..=0.999) and reduced mean free
    /// path (mm), per channel.
    pub colour: Option<([f64; 3], [f64; 3])>,
    /// Model scale, metres.
    pub scale: Option<f64>,
    /// Exposure multiplier.
    pub exposure: Option<f32>,
    /// Diffusion profile.
    pub profile: Option<ProfileKind>,
    /// Where single scattering is computed.
    pub single_scattering: Option<lucent_core::shading::SingleScattering>,
    /// How light crossing the body is carried (`curved`, default, `slab` or `halfspace`).
    pub transmission: Option<lucent_core::solver::transmission::Transmission>,
    /// Lights as `point:x,y,z` or `dir:x,y,z`; any replaces all of the file's lights.
    pub lights: Vec<String>,
    /// Turns off every shadow (lights and environment).
    pub no_shadows: bool,
    /// Bounces of subsurface light between facing parts (0..=4).
    pub bounces: Option<u32>,
    /// Splits of the mesh before the solve (`auto` or 0..=3).
    pub refine: Option<lucent_core::mesh::refine::Refine>,
    /// Environment: `courtyard`, `forest` or an `.hdr`/`.exr` path.
    pub env: Option<String>,
    /// Environment rotation about +Y, degrees.
    pub env_rotation: Option<f32>,
    /// One deformation (`twist:DEG`, `bump:...`, `noise:...`), replacing the file's.
    pub deform: Option<String>,
    /// Camera yaw, degrees.
    pub yaw: Option<f32>,
    /// Camera pitch, degrees (-89..89).
    pub pitch: Option<f32>,
    /// Camera distance, bounding-sphere radii (> 1).
    pub distance: Option<f32>,
    /// Drops the surface reflection and highlight.
    pub no_surface: bool,
    /// Hierarchical, exact or HTSM.
    pub method: Option<Method>,
    /// Render, incremental, refit or on-the-fly.
    pub mode: Option<SolveMode>,
    /// Refinement thresholds; `None`: the profile's defaults.
    pub oracle: Option<Oracle>,
    /// Corrections left out, for the validation's ablation (none by default).
    pub ablate: Ablations,
}

/// A scene after loading and parsing: everything a frame needs.
pub struct Scene {
    /// Where the mesh came from, for messages (`"embedded bunny"`, `"built-in candle"` and so
    /// on for the generated meshes, or the path).
    pub source: String,
    /// The mesh in its rest pose (before [`Scene::deformed`]), mesh units.
    pub mesh: Mesh,
    /// The mesh file, when the mesh came from one (HTSM reads glTF volume parameters from it).
    pub mesh_path: Option<PathBuf>,
    /// The mesh's colour texture, when its file names one: it scales the irradiance at entry
    /// (the session) and the radiance at exit (the GPU), the square root each.
    pub texture: Option<Texture>,
    /// Material, model scale, profile and single scattering.
    pub transport: Transport,
    /// Lights (mesh units) with whether each casts shadows.
    pub lights: Vec<SceneLight>,
    /// Distant environment: SH for the solve, a small map for the GPU reflection.
    pub environment: Option<LoadedEnvironment>,
    /// Method, oracle, environment shadows and bounces; the mode is `None` unless asked for
    /// (see [`Scene::settings`]).
    pub settings: FrameSettings,
    /// The mode asked for, if any.
    pub mode: Option<SolveMode>,
    /// Deformations applied in order to the rest mesh (empty: none).
    pub deform: Vec<Deformation>,
    /// The camera around the rest mesh's bounding sphere.
    pub camera: OrbitCamera,
    /// Exposure multiplier before tone mapping (> 0). Default 1.
    pub exposure: f32,
    /// Whether the surface reflection and highlight are drawn (false: the subsurface term
    /// alone). Default true.
    pub surface: bool,
    /// A hierarchy built with `mesh` (shrink-wrap); `None`: the face-cluster hierarchy.
    pub hierarchy: Option<Hierarchy>,
    /// Times every face of the loaded mesh was split into four (`refine`); `mesh` and
    /// `texture` are the split ones.
    pub refine_levels: u32,
    /// Splits `refine = auto` would make for the hierarchical method but did not because the
    /// method is exact, whose cost grows with the square of the faces (0 otherwise): a front
    /// end says what asking for them would cost.
    pub refine_declined: u32,
}

impl Scene {
    /// Loads the scene file (if any), the mesh, material, lights and environment, with the
    /// flags in `o` overriding the file.
    pub fn resolve(o: &Overrides) -> Result<Scene> {
        let file = o.scene.as_deref().map(SceneFile::load).transpose()?;
        let in_file = |e: anyhow::Error| match &o.scene {
            Some(p) => e.context(format!("scene file {}", p.display())),
            None => e,
        };
        let (source, (mesh, texture), mesh_path) = load_mesh(o, file.as_ref()).map_err(in_file)?;
        let transport = transport(o, file.as_ref(), &mesh, mesh_path.as_deref())?;
        let method = o.method.unwrap_or_default();
        let refine = match (o.refine, file.as_ref().and_then(|f| f.refine.as_ref())) {
            (Some(r), _) => r,
            (None, Some(key)) => key.refine().map_err(|e| in_file(anyhow::anyhow!(e)))?,
            (None, None) => Refine::default(),
        };
        let (refine_levels, refine_declined) = refine_levels(&mesh, &transport, method, refine);
        // Split only when asked: a copy of an 871K-face scan is not free.
        let (mesh, texture) = match refine_levels {
            0 => (mesh, texture),
            n => (
                refine::split_midpoints(&mesh, n),
                texture.map(|t| Texture { corner_uvs: refine::split_corner_uvs(&t.corner_uvs, n), ..t }),
            ),
        };
        let (center, _) = lucent_core::camera::bounding_sphere(&mesh.positions);
        let environment = environment(o, file.as_ref()).map_err(in_file)?;
        let mut lights: Vec<SceneLight> = if !o.lights.is_empty() {
            o.lights.iter().map(|s| parse_light(s, center).map(SceneLight::from)).collect::<Result<_>>()?
        } else {
            file.as_ref().map(|f| f.lights(center)).unwrap_or_default()
        };
        if lights.is_empty() && environment.is_none() {
            lights.extend(default_lights(&mesh).map(SceneLight::from));
        }
        if o.no_shadows {
            lights.iter_mut().for_each(|l| l.shadows = false);
        }
        let deform = match (&o.deform, &file) {
            (Some(spec), _) => {
                vec![spec.parse::<Deformation>().with_context(|| format!("--deform {spec:?}"))?]
            }
            (None, Some(f)) => f.deformations()?,
            (None, None) => Vec::new(),
        };
        let settings = FrameSettings {
            method,
            mode: o.mode.unwrap_or_default(),
            oracle: o.oracle,
            environment_shadows: !o.no_shadows && !o.ablate.env_shadows,
            bounces: o
                .bounces
                .or(file.as_ref().and_then(|f| f.bounces))
                .unwrap_or(crate::ranges::default_bounces(transport.profile)),
            ablate: o.ablate,
        };
        Ok(Scene {
            source,
            mesh,
            mesh_path,
            texture,
            transport,
            lights,
            environment,
            settings,
            mode: o.mode,
            deform,
            camera: camera(o, file.as_ref())?,
            exposure: o.exposure.or(file.as_ref().map(|f| f.exposure)).unwrap_or(1.0),
            surface: !o.no_surface && file.as_ref().is_none_or(|f| f.surface),
            hierarchy: None,
            refine_levels,
            refine_declined,
        })
    }

    /// The scattering material.
    pub fn material(&self) -> &Material {
        &self.transport.material
    }

    /// Model scale: the rest mesh's largest bounding-box side, metres.
    pub fn scale(&self) -> f64 {
        self.transport.scale_m
    }

    /// The frame settings with the mode asked for, else `default_mode` (on-the-fly for a
    /// single image, where nothing is reused; incremental for an animation; render in the
    /// viewer, where lights change more often than shapes).
    pub fn settings(&self, default_mode: SolveMode) -> FrameSettings {
        FrameSettings { mode: self.mode.unwrap_or(default_mode), ..self.settings }
    }

    /// The camera framed on the rest mesh for a `width` x `height` image (fixed over an
    /// animation), as the GPU side draws it and view-ray single scattering sees it.
    pub fn camera_view(&self, (width, height): (u32, u32)) -> lucent_core::camera::CameraView {
        let (center, radius) = lucent_core::camera::bounding_sphere(&self.mesh.positions);
        self.camera.frame(center, radius, width as f32 / height.max(1) as f32)
    }

    /// A frame session on the rest mesh with the scene's transport, lights and environment.
    pub fn session(&self, default_mode: SolveMode) -> FrameSession {
        let mut s = FrameSession::new(
            self.mesh.clone(),
            self.hierarchy.clone(),
            self.transport.clone(),
            self.settings(default_mode),
        );
        s.set_lights(self.lights.clone());
        s.set_environment(self.environment.as_ref().map(|e| e.environment));
        s.set_entry_factors(self.texture.as_ref().map(Texture::entry_factors));
        s
    }

    /// The rest mesh deformed by every deformation at animation parameter `t` (0 = rest pose,
    /// 1 = as specified; see `Deformation::apply`).
    pub fn deformed(&self, t: f32) -> Mesh {
        let mut mesh = self.mesh.clone();
        let mut pos = Vec::with_capacity(mesh.positions.len());
        for d in &self.deform {
            d.apply(&mesh, t, &mut pos);
            std::mem::swap(&mut mesh.positions, &mut pos);
        }
        mesh
    }

    /// The lights alone, for the GPU highlight.
    pub fn plain_lights(&self) -> Vec<Light> {
        self.lights.iter().map(|l| l.light).collect()
    }
}

/// The mesh from `--mesh`, else the file's, else the embedded bunny, with its texture if any:
/// `(source, (mesh, texture), path)`.
/// `(splits made, splits declined)` of `mesh` for `refine` under `method`. HTSM shades per
/// pixel from the light's view: never split. `auto` splits to a few mean free paths
/// (`refine::auto_levels`) except where transport at the mean face is local
/// (`refine::mean_face_is_local`: the session takes the local limit at the vertices instead),
/// and never for the exact method, whose cost is the faces squared: what it would have split
/// is returned as declined, for the front end to say.
fn refine_levels(mesh: &Mesh, transport: &Transport, method: Method, refine: Refine) -> (u32, u32) {
    let auto = || {
        let metres_per_unit = transport.scale_m / mesh.extent() as f64;
        let levels = refine.levels(mesh, metres_per_unit, transport.shortest_mean_free_path_m());
        // Only a mesh the rule splits (edges over 6 mean free paths) can have local faces:
        // the profile (tens of milliseconds) is made for those alone.
        if levels == 0 {
            return 0;
        }
        let reach = lucent_core::solver::local::Locality::of(&transport.profile_at(mesh.extent())).reach;
        if refine::mean_face_is_local(mesh, reach as f64) { 0 } else { levels }
    };
    match (method, refine) {
        (Method::Htsm, _) => (0, 0),
        (Method::Exact, Refine::Auto) => (0, auto()),
        (_, Refine::Auto) => (auto(), 0),
        (_, Refine::Levels(n)) => (n, 0),
    }
}

fn load_mesh(o: &Overrides, file: Option<&SceneFile>) -> Result<(String, TexturedMesh, Option<PathBuf>)> {
    if let Some((name, mesh)) = &o.mesh_data {
        let (mesh, _) = lucent_core::mesh::validate::validate(mesh.clone(), name)?;
        return Ok((name.clone(), (mesh, None), None));
    }
    Ok(match (&o.mesh, file) {
        (Some(path), _) => {
            (path.display().to_string(), super::load_textured_mesh_file(path)?, Some(path.clone()))
        }
        (None, Some(f)) => {
            let mesh = f.load_textured_mesh()?;
            match f.mesh_source() {
                MeshSource::File(p) => (p.display().to_string(), mesh, Some(p)),
                MeshSource::Builtin(name) => (super::builtin_mesh_label(&name), mesh, None),
            }
        }
        (None, None) => ("embedded bunny".to_string(), (lucent_core::mesh::embedded::bunny(), None), None),
    })
}

/// Material, scale, profile and single scattering. The material: `--material`, else
/// `--albedo`/`--mfp`, else the scene file's `material` key, else a glTF mesh's subsurface
/// extensions (see [`super::gltf_material`]), else the default. A colour-and-distance or glTF
/// material says on stdout what it became.
fn transport(
    o: &Overrides,
    file: Option<&SceneFile>,
    mesh: &Mesh,
    mesh_path: Option<&Path>,
) -> Result<Transport> {
    let scale_m = o.scale.or(file.map(|f| f.scale)).unwrap_or(DEFAULT_SCALE_M);
    let file_material = file.filter(|f| f.material.is_some());
    let material = match (&o.material_data, &o.material, o.colour, file_material) {
        (Some(m), _, _, _) => m.validate().map(|()| m.clone())?,
        (None, Some(name), _, _) => Material::by_name(name)?,
        (None, None, Some((albedo, mfp)), _) => {
            Material::from_albedo_mfp("custom", albedo, mfp, DEFAULT_ETA)?
        }
        (None, None, None, Some(f)) => f.material()?,
        (None, None, None, None) => {
            let default = Material::by_name(DEFAULT_MATERIAL)?;
            match mesh_path.filter(|p| super::is_gltf(p)) {
                Some(path) => gltf_material(path, mesh, scale_m, default)?,
                None => default,
            }
        }
    };
    let by_colour = match (&o.material, &o.material_data) {
        (Some(_), _) | (_, Some(_)) => None,
        (None, None) => o.colour.or_else(|| file_material.and_then(|f| f.material.as_ref()?.by_colour())),
    };
    if let Some((albedo, mfp)) = by_colour {
        println!("lucent: {}", colour_material_line(albedo, mfp, &material));
    }
    let profile = match (o.profile, file.and_then(|f| f.profile.as_deref())) {
        (Some(p), _) => p,
        (None, Some(name)) => name.parse::<ProfileKind>().map_err(|e| anyhow::anyhow!("scene file: {e}"))?,
        (None, None) => ProfileKind::default(),
    };
    let from_file = match file.and_then(|f| f.single_scattering.as_ref()) {
        Some(v) => Some(v.mode().map_err(|e| anyhow::anyhow!("scene file: {e}"))?),
        None => None,
    };
    let single_scattering = o.single_scattering.or(from_file).unwrap_or_default();
    let transmission = match (o.transmission, file.and_then(|f| f.transmission.as_deref())) {
        (Some(t), _) => t,
        (None, Some(name)) => name.parse().map_err(|e| anyhow::anyhow!("scene file: {e}"))?,
        (None, None) => Default::default(),
    };
    Ok(Transport { material, scale_m, profile, single_scattering, transmission })
}

/// The material a glTF file's first material maps to (printing what was approximated and the
/// coefficients it became), or `default` when it has no subsurface extension. Errors name the
/// file and the value.
fn gltf_material(path: &Path, mesh: &Mesh, scale_m: f64, default: Material) -> Result<Material> {
    let Some(g) = lucent_core::mesh::load_gltf_material(path)? else {
        return Ok(default);
    };
    let mm_per_unit = scale_m * 1e3 / f64::from(mesh.extent()).max(1e-30);
    let mapped = super::gltf_material::map(&g, mm_per_unit, &default)
        .with_context(|| format!("{}: glTF material {}", path.display(), g.index))?;
    Ok(match mapped {
        Some(m) => {
            println!("lucent: {}: {}", path.display(), m.note);
            println!("lucent: {}", colour_material_line(m.albedo, m.mfp_mm, &m.material));
            m.material
        }
        None => default,
    })
}

/// `--env` (with `--env-rotation`), else the file's environment.
fn environment(o: &Overrides, file: Option<&SceneFile>) -> Result<Option<LoadedEnvironment>> {
    let env = match (&o.env, file) {
        (Some(spec), _) => {
            Some(environment_of(spec, &load_env_map(spec)?, o.env_rotation.unwrap_or(0.0), 1.0)?)
        }
        (None, Some(f)) => {
            let mut f = f.clone();
            if let (Some(spec), Some(r)) = (&mut f.environment, o.env_rotation) {
                spec.rotation = r;
            }
            f.environment()?
        }
        (None, None) => None,
    };
    if let Some(env) = &env {
        // The DC term: the map's mean radiance, what decides an environment-lit image's level.
        let mean = env.environment.sh.coeffs[0] * (0.282_094_8 * env.environment.intensity);
        log::info!("environment: mean radiance {mean:.3}, rotation {} deg", env.environment.rotation_deg);
    }
    Ok(env)
}

/// The file's camera with `--yaw`, `--pitch` and `--distance` applied.
fn camera(o: &Overrides, file: Option<&SceneFile>) -> Result<OrbitCamera> {
    let mut camera = file.map(|f| f.camera()).unwrap_or_default();
    camera.yaw_deg = o.yaw.unwrap_or(camera.yaw_deg);
    camera.pitch_deg = o.pitch.unwrap_or(camera.pitch_deg);
    camera.distance = o.distance.or(camera.distance);
    if !camera.yaw_deg.is_finite() || !(-89.0..=89.0).contains(&camera.pitch_deg) {
        bail!("--pitch must be within -89..89 degrees and --yaw finite");
    }
    if let Some(d) = camera.distance
        && !(d.is_finite() && d > 1.0)
    {
        bail!("--distance is in bounding-sphere radii and must be > 1, got {d}");
    }
    Ok(camera)
}

/// `courtyard` and `forest` name the light probes compiled into lucent; anything else is a path
/// to an equirectangular `.hdr` or `.exr` map.
pub fn load_env_map(spec: &str) -> Result<EnvMap> {
    Ok(match EnvMap::builtin(spec) {
        Some(map) => map?,
        None => EnvMap::load(Path::new(spec))?,
    })
}

/// The SH projection for the solve and the rotated reflection copy of `map`, named `name`.
pub fn environment_of(name: &str, map: &EnvMap, rotation: f32, intensity: f32) -> Result<LoadedEnvironment> {
    if !rotation.is_finite() {
        bail!("--env-rotation must be finite");
    }
    let environment = Environment { rotation_deg: rotation, intensity, ..Environment::from_map(map) };
    let (w, h) = REFLECTION_SIZE;
    let reflection = map.downsampled(w, h).rotated(rotation);
    Ok(LoadedEnvironment { name: name.to_string(), environment, reflection })
}

/// What a colour-and-distance material became, on one line: `material: albedo 0.800,0.600,0.400
/// mfp 1,0.5,0.25 mm -> sigma_s' 0.9794,1.979,3.979 sigma_a 0.02065,0.02111,0.02089 mm^-1 (eta 1.3)`.
pub fn colour_material_line(albedo: [f64; 3], mfp_mm: [f64; 3], m: &Material) -> String {
    let join = |v: [f64; 3], f: &dyn Fn(f64) -> String| v.map(f).join(",");
    // Four significant figures, with an exponent only outside 0.001..10000.
    let sig4 = |x: f64| match x.abs() {
        a if (1e-3..1e4).contains(&a) => {
            let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
            format!("{x:.decimals$}")
        }
        _ => format!("{x:.3e}"),
    };
    format!(
        "material: albedo {} mfp {} mm -> sigma_s' {} sigma_a {} mm^-1 (eta {})",
        join(albedo, &|x| format!("{x:.3}")),
        join(mfp_mm, &|x| format!("{x}")),
        join(m.sigma_s_prime, &sig4),
        join(m.sigma_a, &sig4),
        m.eta
    )
}

#[cfg(test)]
#[path = "resolve_tests.rs"]
mod tests;
