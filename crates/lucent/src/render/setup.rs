//! What `lucent render` draws, resolved from the command line and an optional scene file
//! ([`crate::scene`]): a flag given explicitly wins over the file, the file over the defaults.
//! Everything that can fail (files, numbers, names) fails here, before any output exists.

use crate::cli::RenderArgs;
use crate::scene::{self as scene_file, LoadedEnvironment};
use anyhow::{Context, Result, bail};
use glam::Vec3;
use lucent_core::bssrdf::{Dipole, Material, ProfileKind};
use lucent_core::irradiance::{EnvMap, Environment, Light, SceneLight};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::deform::Deformation;
use lucent_core::solver::Oracle;
use lucent_gpu::camera::OrbitCamera;
use std::path::{Path, PathBuf};

/// Side of the equirect copy of an environment map that the GPU reflects (as the scene module).
const REFLECTION_SIZE: (usize, usize) = (256, 128);

/// What `lucent render` works on, after loading and parsing.
pub struct Scene {
    /// Where the mesh came from, for messages (`"embedded bunny"`, a built-in name or the path).
    pub source: String,
    /// The mesh in its rest pose (before [`Scene::deform`]), mesh units.
    pub mesh: Mesh,
    /// The mesh file, when the mesh came from one (HTSM reads glTF volume parameters from it).
    pub mesh_path: Option<PathBuf>,
    /// The scattering material.
    pub material: Material,
    /// Model scale: the largest side of the mesh's bounding box, metres.
    pub scale: f64,
    /// The diffusion profile (`--profile`) with its coefficients converted to mesh units by the
    /// model scale.
    pub dipole: Dipole,
    /// Lights (mesh units) with whether each casts shadows.
    pub lights: Vec<SceneLight>,
    /// Distant environment: SH for the solve, a small map for the GPU reflection.
    pub environment: Option<LoadedEnvironment>,
    /// Whether the mesh shadows the environment (ray cast per face,
    /// `lucent_core::irradiance::occlusion`); false with `--no-shadows`.
    pub environment_shadows: bool,
    /// Bounces of subsurface light between facing parts through the air
    /// (`lucent_core::irradiance::interreflection`; 0..=4, default 0).
    pub bounces: u32,
    /// Deformations applied in order to the rest mesh (empty: none).
    pub deform: Vec<Deformation>,
    /// The camera around the rest mesh's bounding sphere.
    pub camera: OrbitCamera,
    /// Exposure multiplier before tone mapping (> 0).
    pub exposure: f32,
    /// Whether the surface reflection and highlight are drawn (false: `--no-surface` or the
    /// scene's `surface = false`, the subsurface term alone).
    pub surface: bool,
    /// A hierarchy built with `mesh` (`--hierarchy shrink-wrap:L`); `None`: the solver builds
    /// the face-cluster hierarchy of `mesh`.
    pub hierarchy: Option<lucent_core::hierarchy::Hierarchy>,
}

impl Scene {
    /// The oracle to solve with: `requested` when it names thresholds, else (plain
    /// `transport`, the default) the profile's own defaults ([`Oracle::for_profile`]).
    pub fn oracle(&self, requested: Oracle) -> Oracle {
        if requested == Oracle::default() { Oracle::for_profile(self.dipole.profile) } else { requested }
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

/// Loads the scene file (if any), the mesh, material, lights and environment named by `args`.
pub fn load_scene(args: &RenderArgs) -> Result<Scene> {
    let file = args.scene.as_deref().map(scene_file::Scene::load).transpose()?;
    // Errors from the file's contents (mesh, environment) name the file too.
    let in_file = |e: anyhow::Error| match &args.scene {
        Some(p) => e.context(format!("scene file {}", p.display())),
        None => e,
    };
    let (source, mesh, mesh_path) = match (&args.mesh, &file) {
        (Some(path), _) => {
            (path.display().to_string(), scene_file::load_mesh_file(path)?, Some(path.clone()))
        }
        (None, Some(f)) => {
            let mesh = f.load_mesh().map_err(in_file)?;
            match f.mesh_source() {
                scene_file::MeshSource::File(p) => (p.display().to_string(), mesh, Some(p)),
                scene_file::MeshSource::Builtin(name) => (format!("built-in {name}"), mesh, None),
            }
        }
        (None, None) => ("embedded bunny".to_string(), lucent_core::mesh::embedded::bunny(), None),
    };
    let colour_flags = args.albedo.zip(args.mfp);
    let material = match (&args.material, colour_flags, &file) {
        (Some(name), _, _) => Material::by_name(name)?,
        (None, Some((albedo, mfp)), _) => Material::from_albedo_mfp("custom", albedo, mfp, 1.3)?,
        (None, None, Some(f)) => f.material()?,
        (None, None, None) => Material::by_name("skimmilk")?,
    };
    // A colour-and-distance material (flags, else scene keys) says what it became.
    let by_colour = match &args.material {
        Some(_) => None,
        None => colour_flags.or_else(|| file.as_ref().and_then(|f| f.material.by_colour())),
    };
    if let Some((albedo, mfp)) = by_colour {
        println!("lucent: {}", colour_material_line(albedo, mfp, &material));
    }
    // Flags and scene keys were range-checked where they were read (`crate::ranges`).
    let scale = args.scale.or(file.as_ref().map(|f| f.scale)).unwrap_or(0.05);
    let exposure = args.exposure.or(file.as_ref().map(|f| f.exposure)).unwrap_or(1.0);
    let profile = match (args.profile, file.as_ref().and_then(|f| f.profile.as_deref())) {
        (Some(p), _) => p,
        (None, Some(name)) => name.parse::<ProfileKind>().map_err(|e| anyhow::anyhow!("scene file: {e}"))?,
        (None, None) => ProfileKind::default(),
    };
    let single_scattering = args
        .single_scattering
        .or(file.as_ref().and_then(|f| f.single_scattering))
        .unwrap_or(profile.single_scattering_by_default());
    let dipole =
        Dipole::profile_for_model_scale(&material, mesh.extent() as f64, scale, profile, single_scattering);
    let (center, _) = lucent_gpu::camera::bounding_sphere(&mesh.positions);

    let environment = match (&args.env, &file) {
        (Some(spec), _) => {
            let rotation = args.env_rotation.unwrap_or(0.0);
            Some(environment_of(&load_env_map(spec)?, rotation, 1.0)?)
        }
        (None, Some(f)) => {
            let mut f = f.clone();
            if let (Some(spec), Some(r)) = (&mut f.environment, args.env_rotation) {
                spec.rotation = r;
            }
            f.environment().map_err(in_file)?
        }
        (None, None) => None,
    };
    if let Some(env) = &environment {
        // The DC term: the map's mean radiance, what decides an environment-lit image's level.
        let mean = env.environment.sh.coeffs[0] * (0.282_094_8 * env.environment.intensity);
        log::info!("environment: mean radiance {mean:.3}, rotation {} deg", env.environment.rotation_deg);
    }
    let mut lights: Vec<SceneLight> = if !args.light.is_empty() {
        args.light.iter().map(|s| parse_light(s, center).map(SceneLight::from)).collect::<Result<Vec<_>>>()?
    } else if let Some(f) = &file {
        f.lights(center)
    } else {
        Vec::new()
    };
    if lights.is_empty() && environment.is_none() {
        lights.extend(default_lights(&mesh).map(SceneLight::from));
    }
    if args.no_shadows {
        lights.iter_mut().for_each(|l| l.shadows = false);
    }
    let deform = match (&args.deform, &file) {
        (Some(spec), _) => vec![spec.parse::<Deformation>().with_context(|| format!("--deform {spec:?}"))?],
        (None, Some(f)) => f.deformations()?,
        (None, None) => Vec::new(),
    };
    let mut camera = file.as_ref().map(|f| f.camera()).unwrap_or_default();
    if let Some(y) = args.yaw {
        camera.yaw_deg = y;
    }
    if let Some(p) = args.pitch {
        camera.pitch_deg = p;
    }
    if args.distance.is_some() {
        camera.distance = args.distance;
    }
    if !camera.yaw_deg.is_finite() || !(-89.0..=89.0).contains(&camera.pitch_deg) {
        bail!("--pitch must be within -89..89 degrees and --yaw finite");
    }
    if let Some(d) = camera.distance
        && !(d.is_finite() && d > 1.0)
    {
        bail!("--distance is in bounding-sphere radii and must be > 1, got {d}");
    }
    Ok(Scene {
        source,
        mesh,
        mesh_path,
        material,
        scale,
        dipole,
        lights,
        environment,
        environment_shadows: !args.no_shadows,
        bounces: args.bounces.or(file.as_ref().map(|f| f.bounces)).unwrap_or(0),
        deform,
        camera,
        exposure,
        surface: !args.no_surface && file.as_ref().is_none_or(|f| f.surface),
        hierarchy: None,
    })
}

/// `courtyard` and `forest` name the light probes compiled into lucent; anything else is a path
/// to an equirectangular `.hdr` or `.exr` map.
fn load_env_map(spec: &str) -> Result<EnvMap> {
    Ok(match EnvMap::builtin(spec) {
        Some(map) => map?,
        None => EnvMap::load(Path::new(spec))?,
    })
}

/// The SH projection for the solve and the rotated reflection copy of `map`.
fn environment_of(map: &EnvMap, rotation: f32, intensity: f32) -> Result<LoadedEnvironment> {
    if !rotation.is_finite() {
        bail!("--env-rotation must be finite");
    }
    let environment = Environment { rotation_deg: rotation, intensity, ..Environment::from_map(map) };
    let (w, h) = REFLECTION_SIZE;
    Ok(LoadedEnvironment { environment, reflection: map.downsampled(w, h).rotated(rotation) })
}

/// A key light in front of the object (towards the default camera), above and to the right, and
/// a back light behind and above that shows the translucency of thin parts (Mertens fig. 6.3);
/// each gives irradiance 1 at the object's centre.
fn default_lights(mesh: &Mesh) -> [Light; 2] {
    let (center, radius) = lucent_gpu::camera::bounding_sphere(&mesh.positions);
    let key = center + Vec3::new(1.0, 1.1, 1.8) * radius;
    let back = center + Vec3::new(-0.3, 0.6, -2.2) * radius;
    [point_light(key, center), point_light(back, center)]
}

/// A white point light whose irradiance at the object's centre distance is 1 (arbitrary but
/// consistent units), so images look alike whatever the mesh units.
fn point_light(position: Vec3, center: Vec3) -> Light {
    let d2 = position.distance_squared(center).max(1e-12);
    Light::Point { position, intensity: Vec3::splat(d2) }
}

/// What a colour-and-distance material became, on one line: `material: albedo 0.800,0.600,0.400
/// mfp 1,0.5,0.25 mm -> sigma_s' 0.9794,1.979,3.979 sigma_a 0.02065,0.02111,0.02089 mm^-1 (eta 1.3)`.
fn colour_material_line(albedo: [f64; 3], mfp_mm: [f64; 3], m: &Material) -> String {
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

/// Parses three comma-separated numbers; errors start with `label` and end with `usage`.
pub(crate) fn parse_three(label: &str, text: &str, usage: &str) -> Result<Vec3> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("{label}: {e}; {usage}"))?;
    let [x, y, z] = v[..] else {
        bail!("{label}: {} numbers given; {usage}", v.len());
    };
    Ok(Vec3::new(x, y, z))
}

/// Parses `point:x,y,z` (position, mesh units) or `dir:x,y,z` (direction the light travels).
/// Point lights give irradiance 1 at the distance of `center`; directional lights give 1.
pub fn parse_light(spec: &str, center: Vec3) -> Result<Light> {
    let usage = "expected point:x,y,z (position, mesh units) or dir:x,y,z (direction of travel)";
    let (kind, rest) = spec.split_once(':').with_context(|| format!("--light {spec:?}: {usage}"))?;
    let p = parse_three(&format!("--light {spec:?}"), rest, usage)?;
    let range = crate::ranges::COORDINATE;
    if !p.to_array().iter().all(|c| range.contains(c)) {
        bail!("--light {spec:?}: coordinates must be within {}..={}", range.start(), range.end());
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

/// The lights turned by `angle` radians about the vertical axis through `center` (positions
/// and directions), for `--orbit-light`.
pub fn orbit_lights(lights: &[SceneLight], center: Vec3, angle: f32) -> Vec<SceneLight> {
    let q = glam::Quat::from_rotation_y(angle);
    let turn = |p: Vec3| center + q * (p - center);
    lights
        .iter()
        .map(|l| SceneLight {
            light: match l.light {
                Light::Point { position, intensity } => Light::Point { position: turn(position), intensity },
                Light::Directional { direction, irradiance } => {
                    Light::Directional { direction: q * direction, irradiance }
                }
                Light::Spot { position, direction, intensity, cone_angle, soft_edge } => Light::Spot {
                    position: turn(position),
                    direction: q * direction,
                    intensity,
                    cone_angle,
                    soft_edge,
                },
            },
            shadows: l.shadows,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    fn args(extra: &[&str]) -> RenderArgs {
        let mut v = vec!["lucent", "render"];
        v.extend_from_slice(extra);
        match Cli::parse_from(v).command {
            Some(Command::Render(a)) => a,
            _ => unreachable!(),
        }
    }

    fn candle() -> String {
        format!("{}/../../examples/scenes/candle.toml", env!("CARGO_MANIFEST_DIR"))
    }

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

    /// Flags given explicitly win over the scene file; the rest comes from the file.
    #[test]
    fn flags_override_the_scene_file() {
        let s = load_scene(&args(&["--scene", &candle()])).unwrap();
        assert_eq!(s.material.name, "Wax");
        assert_eq!((s.scale, s.exposure, s.camera.yaw_deg), (0.1, 1.0, 20.0));
        assert_eq!(s.lights.len(), 2);
        assert!(s.lights[0].shadows && !s.lights[1].shadows);
        assert_eq!(s.deform, vec![Deformation::Twist { degrees: 40.0 }]);

        let s = load_scene(&args(&[
            "--scene",
            &candle(),
            "--material",
            "marble",
            "--scale",
            "0.2",
            "--exposure",
            "2",
            "--yaw",
            "-10",
            "--light",
            "dir:0,-1,0",
            "--deform",
            "twist:10",
            "--no-shadows",
        ]))
        .unwrap();
        assert_eq!(s.material.name, "Marble");
        assert_eq!((s.scale, s.exposure, s.camera.yaw_deg, s.camera.pitch_deg), (0.2, 2.0, -10.0, 10.0));
        assert_eq!(s.lights.len(), 1);
        assert!(!s.lights[0].shadows);
        assert_eq!(s.deform, vec![Deformation::Twist { degrees: 10.0 }]);
    }

    /// `--albedo`/`--mfp` invert to a material at eta 1.3, said on one line.
    #[test]
    fn colour_flags_make_the_material_and_say_so() {
        let s = load_scene(&args(&["--albedo", "0.8,0.6,0.4", "--mfp", "1,0.5,0.25"])).unwrap();
        let m = &s.material;
        assert_eq!(*m, Material::from_albedo_mfp("custom", [0.8, 0.6, 0.4], [1.0, 0.5, 0.25], 1.3).unwrap());
        let line = colour_material_line([0.8, 0.6, 0.4], [1.0, 0.5, 0.25], m);
        assert!(
            line.starts_with("material: albedo 0.800,0.600,0.400 mfp 1,0.5,0.25 mm -> sigma_s' "),
            "{line}"
        );
        assert!(line.ends_with(" mm^-1 (eta 1.3)") && !line.contains('\n'), "{line}");
        let tiny = Material::from_albedo_mfp("t", [0.001; 3], [1e3; 3], 1.3).unwrap();
        let tiny_line = colour_material_line([0.001; 3], [1e3; 3], &tiny);
        assert!(tiny_line.contains("sigma_s' 1.3"), "{tiny_line}");
    }

    #[test]
    fn defaults_without_a_scene() {
        let s = load_scene(&args(&[])).unwrap();
        assert_eq!((s.material.name.as_str(), s.scale, s.exposure), ("Skimmilk", 0.05, 1.0));
        assert_eq!(s.lights.len(), 2, "the default key and back lights");
        assert!(s.lights.iter().all(|l| l.shadows), "default lights cast shadows");
        assert!(s.environment.is_none() && s.deform.is_empty());
        // An environment alone needs no extra light.
        let s = load_scene(&args(&["--env", "forest", "--env-rotation", "45"])).unwrap();
        assert!(s.lights.is_empty());
        assert_eq!(s.environment.unwrap().environment.rotation_deg, 45.0);
    }

    /// Orbiting keeps the distance to the centre and turns about +Y.
    #[test]
    fn orbit_turns_about_the_vertical_axis() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let l = [SceneLight::from(Light::Point { position: c + Vec3::X, intensity: Vec3::ONE })];
        let turned = orbit_lights(&l, c, std::f32::consts::FRAC_PI_2);
        let Light::Point { position, .. } = turned[0].light else { panic!() };
        assert!((position - (c - Vec3::Z)).length() < 1e-6, "{position}");
    }
}
