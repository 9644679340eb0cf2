//! Colour and depth attachments with one layer per eye: a single-eye pass renders into one
//! layer, a multiview pass into both layers of a 2-layer array at once.

use crate::gpu::barrier::{cmd_barriers, image_barrier_raw, Access};
use crate::gpu::context::DeviceShared;
use crate::gpu::error::{GpuError, GpuResult, VkResultExt};
use crate::gpu::image::aspect_of;
use crate::gpu::GpuContext;
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// The colour format the eyes are drawn in (the normal, as a G-buffer's normal target holds it).
pub const COLOR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The depth format (reversed-Z, cleared to 0).
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// A 2D image of `layers` layers with a view of all of them (a 2D array view when there are
/// several, as multiview needs); freed on drop.
pub struct LayeredImage {
    shared: Arc<DeviceShared>,
    handle: vk::Image,
    view: vk::ImageView,
    allocation: Option<Allocation>,
    format: vk::Format,
    layers: u32,
}

impl LayeredImage {
    /// A `format` image of `extent` and `layers` layers, usable as an attachment and as a copy
    /// source.
    pub fn new(ctx: &GpuContext, name: &str, format: vk::Format, extent: vk::Extent2D, layers: u32) -> GpuResult<Self> {
        let attachment = if aspect_of(format).contains(vk::ImageAspectFlags::DEPTH) {
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        } else {
            vk::ImageUsageFlags::COLOR_ATTACHMENT
        };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })
            .mip_levels(1)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(attachment | vk::ImageUsageFlags::TRANSFER_SRC)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let shared = ctx.shared.clone();
        // SAFETY: valid device and create info.
        let handle = unsafe { shared.device.create_image(&info, None) }.vk("vkCreateImage")?;
        let mut image =
            Self { shared: shared.clone(), handle, view: vk::ImageView::null(), allocation: None, format, layers };
        // SAFETY: the image was just created.
        let requirements = unsafe { shared.device.get_image_memory_requirements(handle) };
        let allocation = shared
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| GpuError::Allocation { name: name.into(), source })?;
        // SAFETY: the allocation is kept in `image` for as long as the image lives.
        let (memory, offset) = (unsafe { allocation.memory() }, allocation.offset());
        image.allocation = Some(allocation);
        // SAFETY: memory from an allocation that honours the image's requirements.
        unsafe { shared.device.bind_image_memory(handle, memory, offset) }.vk("vkBindImageMemory")?;
        let view_type = if layers > 1 { vk::ImageViewType::TYPE_2D_ARRAY } else { vk::ImageViewType::TYPE_2D };
        let view_info = vk::ImageViewCreateInfo::default()
            .image(handle)
            .view_type(view_type)
            .format(format)
            .subresource_range(image.range());
        // SAFETY: a valid image with bound memory.
        image.view = unsafe { shared.device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
        Ok(image)
    }

    /// The Vulkan handle.
    pub fn handle(&self) -> vk::Image {
        self.handle
    }

    /// The view of every layer.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }

    /// Every layer.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(aspect_of(self.format))
            .base_mip_level(0)
            .level_count(1)
            .base_array_layer(0)
            .layer_count(self.layers)
    }

    /// Records a barrier that takes the image from what any earlier command did with it (its
    /// contents discarded) to `after`.
    pub fn discard_to(&self, device: &ash::Device, cmd: vk::CommandBuffer, after: Access) {
        let before = Access {
            stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        cmd_barriers(device, cmd, &[], &[image_barrier_raw(self.handle, self.range(), before, after)]);
    }
}

impl Drop for LayeredImage {
    fn drop(&mut self) {
        // SAFETY: the owner keeps the image until the GPU no longer uses it.
        unsafe {
            if self.view != vk::ImageView::null() {
                self.shared.device.destroy_image_view(self.view, None);
            }
            if let Some(allocation) = self.allocation.take() {
                let _ = self.shared.allocator().free(allocation);
            }
            self.shared.device.destroy_image(self.handle, None);
        }
    }
}
