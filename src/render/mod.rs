//! The frame: scene buffers on the GPU, render targets, and the renderer that records a frame
//! headlessly or into a host engine's command buffer.

pub mod cull_data;
pub mod face_cull;
pub mod frame_pipeline;
pub mod gpu_types;
pub mod graph_spec;
pub mod output;
pub mod pool_adapt;
pub mod reference;
pub mod renderer;
pub mod scene_buffers;

pub use crate::graph::executor::FRAMES_IN_FLIGHT;
pub use frame_pipeline::FramePipeline;
pub use graph_spec::GraphSpec;
pub use reference::{reference_error, render_reference, DEFAULT_REFERENCE_SCALE};
pub use renderer::{RenderSettings, Renderer};
