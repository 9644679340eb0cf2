//! Errors of scene loading and generation; each names the place (file, node, accessor).

/// Why a scene could not be loaded or generated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or parsed as glTF.
    #[error("{file}: {message}")]
    Import {
        /// The file.
        file: String,
        /// What went wrong.
        message: String,
    },
    /// Content that cullgraph refuses (NaN transform, out-of-range index, zero-area mesh, ...).
    #[error("{place}: {message}")]
    Invalid {
        /// Where: file plus node, mesh, primitive or accessor.
        place: String,
        /// What is wrong with it.
        message: String,
    },
    /// A `builtin:` name that does not exist, or bad generator parameters.
    #[error("{0}")]
    Builtin(String),
}

impl SceneError {
    /// An [`SceneError::Invalid`] at `place`.
    pub fn invalid(place: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError::Invalid { place: place.into(), message: message.into() }
    }

    pub(crate) fn too_large(place: &str, what: &str) -> Self {
        Self::invalid(place, format!("the {what} exceeds 2^32 entries"))
    }
}
