//! # cullgraph
//!
//! GPU-driven culling and deferred rendering of huge scenes through Vulkan (`ash`), scheduled by a
//! declarative render graph. See `README.md` for the quick start and `DESIGN` notes in `docs/`.
#![warn(missing_docs)]

pub mod bench;
pub mod error;
pub mod gpu;
pub mod graph;
pub mod oracle;
pub mod passes;
pub mod render;
pub mod scene;
pub mod stats;

pub use error::{Error, Result};
