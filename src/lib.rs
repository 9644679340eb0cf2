//! # cullgraph
//!
//! GPU-driven culling and deferred rendering of huge scenes through Vulkan (`ash`), scheduled by a
//! declarative render graph. See `README.md` for the quick start and the design notes in `docs/`.
//!
//! Layers, each using only those below it (`tests/layers.rs` checks it):
//! - [`gpu`]: Vulkan context, memory, shaders, pipelines, timestamps;
//! - [`graph`]: the render graph (RON, validation, compiler, executor), which knows no pass kind:
//!   kinds are [`graph::PassKind`]s in a [`graph::KindRegistry`];
//! - [`cull`], [`scene`], [`stats`]: the culling math on the CPU, the scene model, plain figures;
//! - [`passes`]: the built-in pass kinds ([`passes::builtin_kinds`]);
//! - [`render`]: the renderer, headless or recording into an engine's command buffer;
//! - `oracle` and `bench`: verification (exact visibility, image metrics) and benchmarks.
//!
//! Cargo features: `cli` (the default: the `cullgraph` command line, `bench`, and all below),
//! `verify` (`oracle`, `Renderer::enable_verification`, reference renders) and `images` (frames
//! as `image::RgbaImage`, PNG output). An engine depends with `default-features = false` and
//! links none of the command line's crates.
#![warn(missing_docs)]

#[cfg(feature = "cli")]
pub mod bench;
pub mod cull;
pub mod error;
pub mod gpu;
pub mod graph;
#[cfg(feature = "verify")]
pub mod oracle;
pub mod passes;
pub mod render;
pub mod scene;
pub mod stats;

pub use error::{Error, Result};
