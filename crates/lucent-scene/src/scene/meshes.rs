//! Meshes by name: the built-in ones (the embedded bunny and the generated candle, cube and
//! sphere) and mesh files, loaded with their texture and with one warning line per repair.

use anyhow::{Result, bail};
use lucent_core::mesh::texture::Texture;
use lucent_core::mesh::{Mesh, MeshFormat, embedded, generate};
use std::path::{Path, PathBuf};

/// Names accepted by [`super::SceneFile::load_mesh`] for built-in meshes.
pub const BUILTIN_MESHES: &[&str] = &["bunny", "candle", "cube", "sphere"];

/// Where the mesh comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MeshSource {
    /// A built-in mesh or generator, by name.
    Builtin(String),
    /// A mesh file (resolved against the scene file's folder).
    File(PathBuf),
}

/// A mesh named on the command line: a built-in name, or a file path (any path: the user chose
/// it, unlike a path inside a scene file).
pub fn load_named_mesh(name: &str) -> Result<Mesh> {
    let p = Path::new(name);
    if p.extension().is_some() || name.contains(['/', '\\']) {
        load_mesh_file(p)
    } else {
        builtin_mesh(&name.trim().to_ascii_lowercase())
    }
}

/// Whether `path` names a glTF or GLB file (by its extension, as the mesh loader decides).
pub fn is_gltf(path: &Path) -> bool {
    matches!(MeshFormat::from_path(path), Ok(MeshFormat::Gltf))
}

/// How messages name the built-in mesh `name` (lower case): the bunny is the "embedded bunny"
/// wherever it comes from (the default or a scene's `mesh = "bunny"`), the generated ones are
/// "built-in candle" and so on.
pub(super) fn builtin_mesh_label(name: &str) -> String {
    match name {
        "bunny" => "embedded bunny".to_string(),
        other => format!("built-in {other}"),
    }
}

/// A built-in mesh by its lower-case name: `bunny` (embedded Stanford bunny), `candle`, `cube`
/// (32 x 32 squares per side), `sphere` (icosphere, 5 subdivisions).
pub(super) fn builtin_mesh(name: &str) -> Result<Mesh> {
    Ok(match name {
        "bunny" => embedded::bunny(),
        // Finer than the generator's default, so Gouraud shading shows no bands along the side
        // and a twist bends the side visibly.
        "candle" => {
            generate::candle(&generate::CandleParams { segments: 64, side_rings: 32, ..Default::default() })
        }
        "cube" => generate::cube(32),
        "sphere" | "icosphere" => generate::icosphere(5),
        other => bail!(
            "unknown built-in mesh {other:?} (known: {}); a file path needs an extension",
            BUILTIN_MESHES.join(", ")
        ),
    })
}

/// Loads a mesh file and prints one warning line per repair or problem the loader found
/// (degenerate faces dropped, vertices welded, an open or non-manifold surface, a cut-short
/// last line), naming the file.
pub fn load_mesh_file(path: &Path) -> Result<Mesh> {
    let (mesh, report) = lucent_core::mesh::load_mesh_with_report(path)?;
    for warning in report.warnings() {
        eprintln!("lucent: warning: {}: {warning}", path.display());
    }
    Ok(mesh)
}

/// A mesh with its texture, if it has one.
pub type TexturedMesh = (Mesh, Option<Texture>);

/// Loads a mesh file like [`load_mesh_file`] with its texture (UVs and the decoded colour
/// image its material names), if it has one. A missing, corrupt or oversized image is an
/// error naming the image file.
pub fn load_textured_mesh_file(path: &Path) -> Result<TexturedMesh> {
    let (mesh, report, texture) = lucent_core::mesh::load_textured_mesh(path)?;
    for warning in report.warnings() {
        eprintln!("lucent: warning: {}: {warning}", path.display());
    }
    let texture = texture.map(|t| t.load()).transpose()?.flatten();
    Ok((mesh, texture))
}
