//! `lucent view`'s start: the resolved [`Scene`] (flags and an optional scene file, as for
//! `lucent render`) turned into the viewer's state. The viewer works in normalised mesh units
//! (centred, bounding-box side 1), so light positions and intensities are converted. The
//! scene's deformations are baked into the mesh the viewer starts from; the panel's tools (dent,
//! twist, noise) then act on top of them.

use super::core_adapter;
use super::state::{EnvChoice, ViewState};
use crate::scene::Scene;
use glam::Vec3;
use lucent_core::irradiance::Light;
use lucent_core::mesh::Mesh;
use std::path::Path;

/// What a scene gives the viewer: the normalised mesh and the state.
pub struct SceneStart {
    /// The scene's mesh, deformed and normalised (see [`core_adapter::normalise`]).
    pub mesh: Mesh,
    /// Material, scale, lights and environment of the scene.
    pub state: ViewState,
    /// The mesh's colour texture (its UVs per triangle corner fit `mesh`), if it has one.
    pub texture: Option<lucent_core::mesh::texture::Texture>,
    /// The `[camera]` table as it is: the viewer frames the mesh's bounding sphere as
    /// `lucent render` does (see [`super::framing`]).
    pub camera: lucent_core::camera::OrbitCamera,
}

/// Converts `scene` (already validated) for the viewer; an environment the viewer does not
/// offer is an error naming it.
pub fn start(scene: &Scene) -> anyhow::Result<SceneStart> {
    let rest = scene.deformed(1.0);
    let (lo, hi) = rest.bounds();
    let (centre, extent) = (0.5 * (lo + hi), rest.extent().max(1e-12));
    let lights = scene.lights.iter().map(|l| normalised_light(&l.light, centre, extent)).collect();
    let mut state = ViewState::new(scene.material().clone(), scene.scale(), lights);
    state.exposure = scene.exposure;
    state.params.transport.profile = scene.transport.profile;
    state.params.transport.single_scattering = scene.transport.single_scattering;
    let settings = &mut state.params.settings;
    settings.environment_shadows = scene.lights.first().is_none_or(|l| l.shadows);
    settings.bounces = scene.settings.bounces;
    if let Some(mode) = scene.mode {
        settings.mode = mode;
    }
    if let Some(env) = &scene.environment {
        state.params.env = env_choice(&env.name).ok_or_else(|| {
            anyhow::anyhow!(
                "the viewer offers the built-in environments courtyard and forest, not {}",
                env.name
            )
        })?;
        state.params.env_rotation_deg = env.environment.rotation_deg;
        state.params.env_strength = env.environment.intensity;
    }
    let texture = scene.texture.clone();
    Ok(SceneStart { mesh: core_adapter::normalise(rest), texture, state, camera: scene.camera })
}

/// Writes the state's material (with scale, profile, single scattering, exposure, bounces and
/// the mesh's splits) to a new
/// scene file: `to` exactly (a scripted `save:PATH`; an existing file is an error), else the
/// next free name at [`super::state::SaveTarget::path`]. Returns the path written.
pub fn save_material(state: &ViewState, to: Option<&Path>) -> anyhow::Result<std::path::PathBuf> {
    use crate::scene::save::{SavedScene, free_path, scene_toml, write_new};
    let path = match to {
        Some(p) => p.to_path_buf(),
        None => free_path(&state.save.path),
    };
    let t = &state.params.transport;
    let text = scene_toml(&SavedScene {
        material: &t.material,
        scale_m: t.scale_m,
        profile: t.profile,
        single_scattering: t.single_scattering,
        exposure: state.exposure,
        mesh: state.save.mesh.clone(),
        refine: state.save.refine,
        bounces: state.params.settings.bounces,
    });
    write_new(&path, &text)?;
    Ok(path)
}

/// Where "save material" writes for a viewer started from `scene` (a scene file) or `mesh`:
/// beside the scene file as `STEM_material.toml` with the scene's mesh key, else
/// `lucent_material.toml` in the working folder with the mesh path if it is relative and
/// stays inside that folder (a scene file may name no other), else `bunny` when no mesh was
/// given.
pub fn save_target(scene: Option<&Path>, mesh: Option<&Path>) -> super::state::SaveTarget {
    let inside = |p: &Path| {
        p.is_relative()
            && p.components()
                .all(|c| matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir))
    };
    let (path, mesh) = match (scene, mesh) {
        (Some(s), m) => {
            let stem = s.file_stem().and_then(|x| x.to_str()).unwrap_or("scene");
            let file_mesh = crate::scene::SceneFile::load(s).ok().map(|f| f.mesh);
            // A --mesh flag overrides the file's, but is relative to the working folder.
            let mesh = match m {
                Some(_) => None,
                None => file_mesh,
            };
            (s.with_file_name(format!("{stem}_material.toml")), mesh)
        }
        (None, Some(m)) => ("lucent_material.toml".into(), inside(m).then(|| m.display().to_string())),
        (None, None) => ("lucent_material.toml".into(), Some("bunny".to_string())),
    };
    super::state::SaveTarget { path, mesh, refine: 0, message: None }
}

/// A light given in the scene's mesh units, in the viewer's normalised frame: positions mapped,
/// and radiant intensities divided by `extent^2` so the irradiance at the mesh stays the same.
fn normalised_light(light: &Light, centre: Vec3, extent: f32) -> Light {
    let mut l = *light;
    if let Some(p) = l.position() {
        l.set_position((p - centre) / extent);
        l.set_power(l.power() / (extent * extent));
    }
    l
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
        let l = normalised_light(&light, centre, extent);
        assert_eq!(l.position(), Some(Vec3::new(0.0, 0.0, 2.0)));
        let e_scene = 400.0 / 20.0f32.powi(2);
        let e_view = l.power().x / 2.0f32.powi(2);
        assert!((e_scene - e_view).abs() < 1e-5, "{e_scene} vs {e_view}");
    }

    #[test]
    fn environment_files_map_to_the_viewer_choices() {
        assert_eq!(env_choice("forest"), Some(EnvChoice::Forest));
        assert_eq!(env_choice("x/courtyard.exr"), Some(EnvChoice::Courtyard));
        assert_eq!(env_choice("other.hdr"), None);
    }
}
