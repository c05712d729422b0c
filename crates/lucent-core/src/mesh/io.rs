//! Loading meshes from files (stub).
use super::Mesh;
use std::path::Path;

/// Why a mesh could not be loaded; always names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("{path}: {reason}")]
    Invalid { path: String, reason: String },
}

/// Loads a mesh from an OBJ, PLY, OFF, glTF or GLB file.
pub fn load_mesh(path: &Path) -> Result<Mesh, MeshError> {
    Err(MeshError::Invalid { path: path.display().to_string(), reason: "not implemented".into() })
}
