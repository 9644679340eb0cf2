//! The Vulkan layer: context (owned or from a host engine), memory, resources, shaders,
//! pipelines, barriers, timestamps and validation.

pub mod barrier;
pub mod buffer;
pub mod context;
pub mod depth_array;
pub mod device_select;
pub mod edits;
pub mod error;
pub mod features;
pub mod image;
pub mod line_dispatch;
pub mod memory;
pub mod pipeline;
pub mod reflect;
pub mod sampler;
pub mod shader;
pub mod texture_array;
pub mod timestamps;
pub mod transfer;
pub mod validation;
pub mod workgroup_memory;

pub use barrier::Access;
pub use buffer::{Buffer, BufferDesc};
pub use context::{ContextOptions, DeviceCaps, GpuContext, HostHandles};
pub use depth_array::DepthArray;
pub use device_select::DeviceSelector;
pub use edits::Edits;
pub use error::{GpuError, GpuResult};
pub use features::{RequiredFeatures, OPTIONAL_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS};
pub use gpu_allocator::MemoryLocation;
pub use image::{HostImage, Image, ImageDesc};
pub use memory::MemoryBlock;
pub use pipeline::{cmd_set_full_viewport, Bind, GraphicsDesc, Pipeline, StencilRule, VertexAttribute};
pub use sampler::Sampler;
pub use shader::{ShaderCompiler, ShaderError, ShaderRoot, Spirv};
pub use texture_array::TextureArray;
pub use timestamps::{GpuTimer, PassTiming};
pub use transfer::UploadBatch;
pub use validation::ValidationLog;
