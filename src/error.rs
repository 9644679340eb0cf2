//! The library's error type.

use crate::gpu::GpuError;
use crate::scene::SceneError;

/// Anything that can go wrong in cullgraph.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Vulkan, memory or shader failure.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Scene loading or validation failure.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A change to a world that was refused (naming the handle).
    #[error(transparent)]
    World(#[from] crate::scene::world::WorldError),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// An argument or setting that cannot work (size 0, NaN camera, ...), with the reason.
    #[error("{0}")]
    Invalid(String),
    /// A failure of something a graph declares (creating a resource's memory, importing it),
    /// at its declaration.
    #[error("{at}: {source}")]
    Declared {
        /// `file:line:col: resource 'name'`.
        at: String,
        /// What went wrong.
        #[source]
        source: Box<Error>,
    },
    /// A failure of one view of a renderer, naming the view.
    #[error("view {view}: {source}")]
    View {
        /// The view's number ([`crate::render::ViewId::number`]).
        view: u32,
        /// What went wrong.
        #[source]
        source: Box<Error>,
    },
}

impl From<crate::gpu::ShaderError> for Error {
    fn from(e: crate::gpu::ShaderError) -> Self {
        Error::Gpu(GpuError::Shader(e))
    }
}

/// Result alias of the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;
