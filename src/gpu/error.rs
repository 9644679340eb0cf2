//! Errors of the GPU layer.

use ash::vk;

/// Everything that can go wrong while talking to Vulkan.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// The Vulkan loader (`libvulkan.so.1`) could not be opened.
    #[error("cannot load the Vulkan loader (libvulkan.so.1): {0}; run scripts/install-deps")]
    Loader(String),
    /// A Vulkan call failed.
    #[error("{call} failed: {result}")]
    Vk {
        /// The Vulkan function that failed.
        call: &'static str,
        /// The result it returned.
        result: vk::Result,
    },
    /// Validation was requested but the Khronos validation layer is not installed.
    #[error("validation requested but VK_LAYER_KHRONOS_validation is not installed (Debian: apt-get install vulkan-validationlayers)")]
    ValidationLayerMissing,
    /// No physical device matched, or none has what cullgraph needs.
    #[error("no usable Vulkan device: {0}")]
    NoDevice(String),
    /// The chosen device lacks features or extensions cullgraph needs.
    #[error("device '{device}' lacks what cullgraph needs: {missing}")]
    MissingFeatures {
        /// Device name.
        device: String,
        /// Comma-separated missing features and extensions.
        missing: String,
    },
    /// gpu-allocator failed to allocate memory.
    #[error("memory allocation for '{name}' failed: {source}")]
    Allocation {
        /// Debug name of the resource.
        name: String,
        /// Allocator error.
        #[source]
        source: gpu_allocator::AllocationError,
    },
    /// A resource request that cannot be satisfied (absurd size, unsupported format, ...).
    #[error("invalid resource '{name}': {reason}")]
    InvalidResource {
        /// Debug name of the resource.
        name: String,
        /// Why it was refused.
        reason: String,
    },
    /// Shader compilation failed.
    #[error(transparent)]
    Shader(#[from] crate::gpu::shader::ShaderError),
}

/// Result alias of the GPU layer.
pub type GpuResult<T> = Result<T, GpuError>;

/// Attaches the name of the failing Vulkan call to a `vk::Result` (for a host's own calls too).
pub trait VkResultExt<T> {
    /// Maps the error to [`GpuError::Vk`] naming `call`.
    fn vk(self, call: &'static str) -> GpuResult<T>;
}

impl<T> VkResultExt<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> GpuResult<T> {
        self.map_err(|result| GpuError::Vk { call, result })
    }
}
