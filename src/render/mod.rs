//! The renderer: owns a scene on the GPU and a render graph's runtime, and records a frame
//! headlessly or into a host engine's command buffer.

pub mod frame_pipeline;
pub mod graph_spec;
#[cfg(feature = "images")]
pub mod output;
#[cfg(feature = "verify")]
pub mod reference;
pub mod renderer;

pub use crate::graph::FRAMES_IN_FLIGHT;
pub use frame_pipeline::FramePipeline;
pub use graph_spec::GraphSpec;
#[cfg(feature = "verify")]
pub use reference::{reference_error, render_reference, DEFAULT_REFERENCE_SCALE};
pub use renderer::{DrawnInstances, RenderSettings, Renderer};
