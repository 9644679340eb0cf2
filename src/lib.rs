//! # cullgraph
//!
//! GPU-driven culling and deferred rendering of huge scenes through Vulkan (`ash`), scheduled by a
//! declarative render graph. See `README.md` for the quick start and the design notes in `docs/`.
//!
//! # Embedding, in short
//!
//! ```no_run
//! use cullgraph::prelude::*;
//! use cullgraph::scene::source::LoadOptions;
//!
//! # fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
//! // An engine that owns the device passes its handles: GpuContext::from_host(HostHandles { .. }).
//! let ctx = GpuContext::new(&ContextOptions::default())?;
//! let shaders = ShaderCompiler::new(ShaderRoot::Embedded)?;
//! let scene = "builtin:city".parse::<SceneSource>()?.load(&LoadOptions::default())?;
//! let camera = scene.default_camera(16.0 / 9.0);
//! let mut renderer = Renderer::new(&ctx, &shaders, scene, RenderSettings::new(1280, 720))?;
//! # let cmd = ash::vk::CommandBuffer::null();
//! // Every frame, into the engine's command buffer (cullgraph never submits or waits there):
//! let frame = renderer.record(cmd, &camera)?;
//! // Once the engine's fence says that frame has executed:
//! let stats = renderer.completed_stats(frame)?;
//! println!("{} of {} instances drawn", stats.drawn, stats.instances);
//! # Ok(())
//! # }
//! ```
//!
//! `examples/embed.rs` embeds into an engine's own device, and `examples/custom_pass.rs` adds a
//! pass kind of the engine's own.
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

/// The command line's benchmarks: public only so that the `cullgraph` binary reaches them; not
/// part of the library's API.
#[cfg(feature = "cli")]
#[doc(hidden)]
pub mod bench;
pub mod cull;
pub mod error;
/// Bounded reading of the files a user names: public only so that the `cullgraph` binary's
/// fuzzer reads its inputs with the library's limits; not part of the library's API (the
/// limits themselves are stated in the README).
#[doc(hidden)]
pub mod files;
pub mod gpu;
pub mod graph;
#[cfg(feature = "verify")]
pub mod oracle;
pub(crate) mod parallel;
pub mod passes;
pub mod prelude;
pub mod render;
pub mod scene;
pub mod stats;

pub use error::{Error, Result};

#[cfg(test)]
mod readme_limits {
    use crate::files;

    /// The limits the README states are the ones enforced.
    #[test]
    fn the_readme_states_the_enforced_limits() {
        let readme = include_str!("../README.md").split_whitespace().collect::<Vec<_>>().join(" ");
        let files = format!(
            "a graph {} MiB, a shader {} MiB, a scene {} GiB",
            files::GRAPH_LIMIT >> 20,
            files::SHADER_LIMIT >> 20,
            files::SCENE_LIMIT >> 30
        );
        let expressions = format!(
            "nest at most {} deep and have at most {} tokens",
            crate::graph::expr::MAX_NESTING,
            crate::graph::expr::MAX_TOKENS
        );
        let buffers = format!("a scene's buffers {} GiB together", files::BUFFERS_LIMIT >> 30);
        let world = format!("up to 2^{} (about", crate::scene::MAX_COORDINATE.log2());
        let max = crate::graph::compile::resolve::MAX_IMAGE_DIMENSION;
        let size = format!("up to {max}x{max}");
        use crate::scene::validate::{MAX_INDICES, MAX_INSTANCES, MAX_TEXTURES, MAX_VERTICES};
        let scene = format!(
            "A scene holds at most {MAX_INSTANCES} instances, {MAX_VERTICES} vertices, {MAX_INDICES} indices and \
             {MAX_TEXTURES} textures"
        );
        let image_side = format!("at most {} texels a side", crate::scene::gltf_import::MAX_IMAGE_SIDE);
        use crate::graph::compile::resolve::{MAX_DISPATCH_GROUPS, MAX_GROUPS};
        let dispatch = format!("at most {MAX_GROUPS} workgroups per dimension and {MAX_DISPATCH_GROUPS} in all");
        let includes = format!(
            "`#include`s nest at most {} deep, bring in at most {} MiB together",
            crate::gpu::shader::MAX_INCLUDE_DEPTH,
            crate::gpu::shader::MAX_INCLUDED_BYTES >> 20
        );
        let views = format!("at most `MAX_VIEWS` ({}) views", crate::render::MAX_VIEWS);
        for stated in [files, buffers, expressions, world, size, scene, image_side, dispatch, includes, views] {
            assert!(readme.contains(&stated), "the README does not say \"{stated}\"");
        }
    }
}
