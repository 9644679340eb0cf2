//! Blocks of device memory that several resources share (render-graph transient aliasing).

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A device-local memory block; images and buffers are placed inside it at offsets.
///
/// Resources placed in a block must be dropped before it.
pub struct MemoryBlock {
    shared: Arc<DeviceShared>,
    allocation: Option<Allocation>,
    size: u64,
}

impl MemoryBlock {
    /// Allocates `size` bytes aligned to `alignment` from a memory type in `memory_type_bits`.
    ///
    /// `linear` says whether the block holds buffers (true) or optimally tiled images (false),
    /// which keeps the two apart as `bufferImageGranularity` requires.
    pub fn new(
        ctx: &GpuContext,
        name: &str,
        size: u64,
        alignment: u64,
        memory_type_bits: u32,
        linear: bool,
    ) -> GpuResult<Self> {
        let requirements = vk::MemoryRequirements { size: size.max(1), alignment: alignment.max(1), memory_type_bits };
        let allocation = ctx
            .shared
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| GpuError::Allocation { name: name.into(), source })?;
        Ok(Self { shared: ctx.shared.clone(), allocation: Some(allocation), size })
    }

    /// A block of its own for optimally tiled image `image` (just created, without memory),
    /// bound to it: the block must outlive the image.
    pub fn bound_to_image(ctx: &GpuContext, name: &str, image: vk::Image) -> GpuResult<Self> {
        // SAFETY: a valid image of this device.
        let requirements = unsafe { ctx.device().get_image_memory_requirements(image) };
        let block =
            Self::new(ctx, name, requirements.size, requirements.alignment, requirements.memory_type_bits, false)?;
        // SAFETY: the block fits the requirements; the caller keeps it as long as the image.
        unsafe { ctx.device().bind_image_memory(image, block.memory(), block.offset()) }.vk("vkBindImageMemory")?;
        Ok(block)
    }

    /// The `VkDeviceMemory` the block lives in.
    pub fn memory(&self) -> vk::DeviceMemory {
        // SAFETY: the allocation exists until drop, and resources in it are dropped first.
        self.allocation.as_ref().map_or(vk::DeviceMemory::null(), |a| unsafe { a.memory() })
    }

    /// Offset of the block inside that memory.
    pub fn offset(&self) -> u64 {
        self.allocation.as_ref().map_or(0, |a| a.offset())
    }

    /// Usable size in bytes.
    pub fn size(&self) -> u64 {
        self.size
    }
}

impl Drop for MemoryBlock {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            let _ = self.shared.allocator().free(a);
        }
    }
}
