//! The renderer: owns a scene on the GPU and a render graph's runtime, and records a frame
//! headlessly or into a host engine's command buffer.

mod drawn;
pub mod frame_pipeline;
pub mod graph_spec;
pub mod observer;
#[cfg(feature = "images")]
pub mod output;
pub mod renderer;

pub use crate::graph::FRAMES_IN_FLIGHT;
pub use frame_pipeline::FramePipeline;
pub use graph_spec::GraphSpec;
pub use observer::FrameObserver;
pub use renderer::{
    DrawnInstances, OutputF32, ParamsApplied, RenderSettings, Renderer, ShadowSettings, ViewFrame, ViewId,
    MAX_SHADOWED_LIGHTS, MAX_VIEWS, USER_DATA_IMPORT,
};
