//! `lucent view --scene FILE`: a TOML scene (see [`crate::scene`]) turned into the viewer's
//! start-up state. The viewer works in normalised mesh units (centred, bounding-box side 1), so
//! light positions and intensities are converted. The file's deformations are baked into the mesh
//! the viewer starts from; the panel's tools (dent, twist, noise) then act on top of them.

use super::core_adapter;
use super::state::{EnvChoice, LightKind, LightSpec, ViewState};
use crate::scene::Scene;
use glam::Vec3;
use lucent_core::irradiance::Light;
use lucent_core::mesh::Mesh;
use std::path::Path;

/// What a scene file gives the viewer: the normalised mesh, the state and the exposure.
pub struct SceneStart {
    /// The scene's mesh, normalised (see [`core_adapter::normalise`]).
    pub mesh: Mesh,
    /// Material, scale, lights and environment from the file.
    pub state: ViewState,
    /// The `[camera]` table as it is: the viewer frames the mesh's bounding sphere as
    /// `lucent render` does (see [`super::framing`]).
    pub camera: lucent_gpu::camera::OrbitCamera,
}

/// Loads `path` (errors name the file) and converts it.
pub fn load(path: &Path) -> anyhow::Result<SceneStart> {
    let scene = Scene::load(path)?;
    let mut rest = scene.load_mesh()?;
    let mut deformed = Vec::new();
    for d in scene.deformations()? {
        d.apply(&rest, 1.0, &mut deformed);
        rest = Mesh::new(std::mem::take(&mut deformed), rest.triangles);
    }
    let (lo, hi) = rest.bounds();
    let (centre, extent) = (0.5 * (lo + hi), rest.extent().max(1e-12));
    let mut state = ViewState::new(scene.material()?, scene.scale);
    state.exposure = scene.exposure;
    state.params.lights = scene.lights(centre).iter().map(|l| light_spec(&l.light, centre, extent)).collect();
    if let Some(first) = scene.lights.first() {
        state.params.shadows = light_casts_shadows(first);
    }
    if let Some(env) = &scene.environment {
        state.params.env = env_choice(&env.path).ok_or_else(|| {
            anyhow::anyhow!(
                "{}: the viewer offers the built-in environments courtyard and forest, not {}",
                path.display(),
                env.path
            )
        })?;
        state.params.env_rotation_deg = env.rotation;
        state.params.env_strength = env.intensity;
    }
    Ok(SceneStart { mesh: core_adapter::normalise(rest), state, camera: scene.camera() })
}

/// The UI's form of a core light given in the scene's mesh units: positions mapped to the
/// normalised frame, and radiant intensities divided by `extent^2` so the irradiance at the
/// mesh stays the same.
fn light_spec(light: &Light, centre: Vec3, extent: f32) -> LightSpec {
    let to_view = |p: Vec3| (p - centre) / extent;
    let k = 1.0 / (extent * extent);
    let (kind, position, direction, rgb, cone) = match *light {
        Light::Point { position, intensity } => {
            (LightKind::Point, to_view(position), -to_view(position), intensity * k, 30.0)
        }
        Light::Spot { position, direction, intensity, cone_angle, .. } => {
            (LightKind::Spot, to_view(position), direction, intensity * k, cone_angle.to_degrees())
        }
        Light::Directional { direction, irradiance } => {
            (LightKind::Directional, Vec3::Y, direction, irradiance, 30.0)
        }
    };
    let power = rgb.max_element().max(1e-6);
    LightSpec { kind, position, direction, color: rgb / power, power, spot_angle_deg: cone }
}

fn light_casts_shadows(l: &crate::scene::LightSpec) -> bool {
    use crate::scene::LightSpec as S;
    match l {
        S::Point { shadows, .. } | S::Directional { shadows, .. } | S::Spot { shadows, .. } => *shadows,
    }
}

/// The viewer's choice for a scene's environment: a built-in probe's name, or a file of the
/// same name (`forest.exr`).
fn env_choice(path: &str) -> Option<EnvChoice> {
    let stem = Path::new(path).file_stem()?.to_str()?.to_ascii_lowercase();
    EnvChoice::ALL.into_iter().find(|c| c.path().is_some() && c.label() == stem)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point light converted to normalised units gives the same irradiance at the
    /// corresponding point: `I / d^2` is invariant when `I` scales with `1 / extent^2`.
    #[test]
    fn point_light_keeps_its_irradiance() {
        let (centre, extent) = (Vec3::new(1.0, 2.0, 3.0), 10.0);
        let light = Light::Point { position: Vec3::new(1.0, 2.0, 23.0), intensity: Vec3::splat(400.0) };
        let spec = light_spec(&light, centre, extent);
        assert_eq!(spec.position, Vec3::new(0.0, 0.0, 2.0));
        let e_scene = 400.0 / 20.0f32.powi(2);
        let e_view = spec.power * spec.color.x / spec.position.length_squared();
        assert!((e_scene - e_view).abs() < 1e-5, "{e_scene} vs {e_view}");
    }

    #[test]
    fn environment_files_map_to_the_viewer_choices() {
        assert_eq!(env_choice("forest"), Some(EnvChoice::Forest));
        assert_eq!(env_choice("x/courtyard.exr"), Some(EnvChoice::Courtyard));
        assert_eq!(env_choice("other.hdr"), None);
    }
}
