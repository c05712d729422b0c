//! Why a mesh could not be loaded, and the guard that turns a third-party parser's panic into
//! that error (shared by every loader: `io`, `io_gltf`, `texture`, `validate`).

/// Why a mesh could not be loaded. Its `Display` is one line: the file, then the reason.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be loaded or its content is not an acceptable mesh.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file (or source name, for in-memory data) as given by the caller.
        path: String,
        /// What is wrong, in words (no trailing period).
        reason: String,
    },
}

impl MeshError {
    /// An [`MeshError::Invalid`] for `path` with `reason`.
    /// Line breaks in the reason (some parsers' messages have them) become spaces.
    pub fn invalid(path: impl Into<String>, reason: impl Into<String>) -> Self {
        let reason: String = reason.into();
        MeshError::Invalid {
            path: path.into(),
            reason: reason.split_whitespace().collect::<Vec<_>>().join(" "),
        }
    }

    /// The reason alone, without the file name.
    pub fn reason(&self) -> &str {
        match self {
            MeshError::Invalid { reason, .. } => reason,
        }
    }
}

/// Runs a third-party parser and turns a panic into an error naming the file.
pub(super) fn guard<T>(name: &str, f: impl FnOnce() -> T) -> Result<T, MeshError> {
    crate::limits::catch_quietly(f)
        .map_err(|what| MeshError::invalid(name, format!("malformed file (parser failed: {what})")))
}
