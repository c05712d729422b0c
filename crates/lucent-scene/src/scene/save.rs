//! Writing a material back to a scene file (the viewer's "save material", issue 18): a TOML
//! scene that `lucent render --scene` and `lucent view --scene` read back to the same
//! coefficients. The material is written as its coefficients (`sigma_s_prime`, `sigma_a`,
//! `eta`, exactly: Rust prints the shortest decimal that reads back to the same `f64`), with
//! its colour and distance in a comment. Nothing is ever overwritten: [`write_new`] refuses an
//! existing path, and [`free_path`] finds the next unused name.

use anyhow::{Context, Result};
use lucent_core::bssrdf::{Material, ProfileKind};
use lucent_core::shading::SingleScattering;
use std::io::Write;
use std::path::{Path, PathBuf};

/// What a saved scene holds besides the material.
#[derive(Clone, Debug, PartialEq)]
pub struct SavedScene<'a> {
    /// The material.
    pub material: &'a Material,
    /// Model scale: the mesh's largest bounding-box side, metres (within
    /// [`crate::ranges::SCALE_M`], checked when the file is read back).
    pub scale_m: f64,
    /// Diffusion profile.
    pub profile: ProfileKind,
    /// Where single scattering is computed.
    pub single_scattering: SingleScattering,
    /// Exposure multiplier before tone mapping (unitless, > 0, within
    /// [`crate::ranges::EXPOSURE`]).
    pub exposure: f32,
    /// The `mesh` key to write (a built-in name or a path relative to the saved file's
    /// folder), if known; else the file renders the default bunny.
    pub mesh: Option<String>,
    /// Times every face of the mesh is split into four before the solve (the `refine` key,
    /// 0..=3): the count the mesh on screen got, not `auto`.
    pub refine: u32,
    /// Bounces of light between parts (the `bounces` key, within [`crate::ranges::BOUNCES`]).
    pub bounces: u32,
}

/// The scene as TOML text.
pub fn scene_toml(s: &SavedScene<'_>) -> String {
    let m = s.material;
    let list = |v: [f64; 3]| format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2]);
    let (albedo, mfp) = m.albedo_mfp();
    let short = |v: [f64; 3]| v.map(|x| format!("{x:.4}")).join(", ");
    let mut out = String::from("# Saved by lucent view: the material as coefficients (mm^-1).\n");
    if let Some(mesh) = &s.mesh {
        out += &format!("mesh = {}\n", toml::Value::String(mesh.clone()));
    }
    out += &format!(
        "# As colour and distance: albedo [{}], mfp [{}] mm.\n\
         material = {{ name = {}, sigma_s_prime = {}, sigma_a = {}, eta = {:?} }}\n\
         scale = {:?}\nprofile = \"{}\"\nsingle_scattering = \"{}\"\nexposure = {:?}\n\
         bounces = {}\nrefine = {}\n",
        short(albedo),
        short(mfp),
        toml::Value::String(m.name.clone()),
        list(m.sigma_s_prime),
        list(m.sigma_a),
        m.eta,
        s.scale_m,
        s.profile.name(),
        s.single_scattering.name(),
        s.exposure,
        s.bounces,
        s.refine
    );
    out
}

/// Writes `text` to `path`, which must not exist yet (created atomically with `create_new`, so
/// a file appearing meanwhile is not overwritten either). Errors name the path.
pub fn write_new(path: &Path, text: &str) -> Result<()> {
    let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(path).with_context(|| {
        match path.exists() {
            true => format!("{} exists; not overwritten (choose another name)", path.display()),
            false => format!("cannot create {}", path.display()),
        }
    })?;
    f.write_all(text.as_bytes()).with_context(|| format!("cannot write {}", path.display()))
}

/// `base` if nothing is there, else `stem_2.ext`, `stem_3.ext`, ... beside it (the first
/// unused one, up to 9999).
pub fn free_path(base: &Path) -> PathBuf {
    if !base.exists() {
        return base.to_path_buf();
    }
    let stem = base.file_stem().and_then(|s| s.to_str()).unwrap_or("material");
    let ext = base.extension().and_then(|s| s.to_str()).unwrap_or("toml");
    (2..10_000)
        .map(|k| base.with_file_name(format!("{stem}_{k}.{ext}")))
        .find(|p| !p.exists())
        .unwrap_or_else(|| base.with_file_name(format!("{stem}_new.{ext}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Overrides, Scene, SceneFile};

    /// Save, load (as `lucent render --scene` does), and the coefficients are the same bits.
    #[test]
    fn saved_material_reads_back_the_same() {
        let dir = std::env::temp_dir().join(format!("lucent-save-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let m =
            Material::from_albedo_mfp("clay \"edited\"", [0.8, 0.6, 0.4], [1.0, 0.5, 0.25], 1.37).unwrap();
        let saved = SavedScene {
            material: &m,
            scale_m: 0.073,
            profile: ProfileKind::Dipole,
            single_scattering: SingleScattering::Profile,
            exposure: 1.5,
            mesh: Some("bunny".into()),
            // Not what `auto` gives this material and scale (once: the bunny's 2.9 mm edges are
            // 11 of its 0.25 mm mean free paths): the count is written, not recomputed.
            refine: 2,
            bounces: 2,
        };
        let path = dir.join("m.toml");
        write_new(&path, &scene_toml(&saved)).unwrap();
        let file = SceneFile::load(&path).unwrap();
        assert_eq!(file.material().unwrap(), m);
        let scene = Scene::resolve(&Overrides { scene: Some(path.clone()), ..Default::default() }).unwrap();
        assert_eq!(scene.material(), &m);
        assert_eq!((scene.scale(), scene.exposure), (0.073, 1.5));
        assert_eq!((scene.refine_levels, scene.settings.bounces), (2, 2));
        assert_eq!(scene.mesh.triangles.len(), 16 * 3674, "the bunny split twice");
        assert_eq!(
            (scene.transport.profile, scene.transport.single_scattering),
            (ProfileKind::Dipole, SingleScattering::Profile)
        );
        // Never overwritten: the second write fails naming the file; free_path finds m_2.toml.
        let e = write_new(&path, "x").unwrap_err().to_string();
        assert!(e.contains("m.toml") && e.contains("not overwritten"), "{e}");
        assert_eq!(SceneFile::load(&path).unwrap().material().unwrap(), m);
        assert_eq!(free_path(&path), dir.join("m_2.toml"));
        assert_eq!(free_path(&dir.join("n.toml")), dir.join("n.toml"));
    }
}
