//! A sampled 2D array image of RGBA8 texels with a full mip chain, seen through two views: as
//! sRGB-encoded colour (decoded to linear when sampled) and as plain linear values. One array
//! holds textures of one size; which view a material samples depends on the use, not on the
//! texture (`scene::texture`).

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use super::memory::MemoryBlock;
use ash::vk;
use std::sync::Arc;

/// The linear and sRGB formats of the same texels.
pub const LINEAR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// See [`LINEAR_FORMAT`].
pub const SRGB_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;

/// See the module documentation; freed on drop.
pub struct TextureArray {
    shared: Arc<DeviceShared>,
    handle: vk::Image,
    linear_view: vk::ImageView,
    srgb_view: vk::ImageView,
    /// Freed after the image (fields drop after `Drop::drop` destroys it).
    memory: Option<MemoryBlock>,
    size: u32,
    layers: u32,
    mip_levels: u32,
    bytes: u64,
}

impl TextureArray {
    /// A `size` x `size` array of `layers` layers with every mip, in `TRANSFER_DST`-ready
    /// (undefined) layout.
    pub fn new(ctx: &GpuContext, name: &str, size: u32, layers: u32) -> GpuResult<Self> {
        let limits = ctx.caps().limits;
        let bad = |reason: String| GpuError::InvalidResource { name: name.into(), reason };
        if size == 0 || size > limits.max_image_dimension2_d {
            return Err(bad(format!("size {size} is beyond the device's {}", limits.max_image_dimension2_d)));
        }
        if layers == 0 || layers > limits.max_image_array_layers {
            return Err(bad(format!("{layers} layers, the device takes 1 to {}", limits.max_image_array_layers)));
        }
        let mip_levels = 32 - size.leading_zeros();
        let formats = [LINEAR_FORMAT, SRGB_FORMAT];
        let mut list = vk::ImageFormatListCreateInfo::default().view_formats(&formats);
        let info = vk::ImageCreateInfo::default()
            .flags(vk::ImageCreateFlags::MUTABLE_FORMAT)
            .image_type(vk::ImageType::TYPE_2D)
            .format(LINEAR_FORMAT)
            .extent(vk::Extent3D { width: size, height: size, depth: 1 })
            .mip_levels(mip_levels)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .push_next(&mut list);
        let shared = ctx.shared.clone();
        // SAFETY: valid device and create info.
        let handle = unsafe { shared.device.create_image(&info, None) }.vk("vkCreateImage")?;
        let mut array = Self {
            shared,
            handle,
            linear_view: vk::ImageView::null(),
            srgb_view: vk::ImageView::null(),
            memory: None,
            size,
            layers,
            mip_levels,
            bytes: 0,
        };
        let memory = MemoryBlock::bound_to_image(ctx, name, handle)?;
        array.bytes = memory.size();
        array.memory = Some(memory);
        array.linear_view = array.view(LINEAR_FORMAT)?;
        array.srgb_view = array.view(SRGB_FORMAT)?;
        Ok(array)
    }

    fn view(&self, format: vk::Format) -> GpuResult<vk::ImageView> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.handle)
            .view_type(vk::ImageViewType::TYPE_2D_ARRAY)
            .format(format)
            .subresource_range(self.range());
        // SAFETY: valid image with bound memory, format in its view format list.
        unsafe { self.shared.device.create_image_view(&info, None) }.vk("vkCreateImageView")
    }

    /// Every mip of every layer.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .base_mip_level(0)
            .level_count(self.mip_levels)
            .base_array_layer(0)
            .layer_count(self.layers)
    }

    /// The copy regions of one layer's whole mip chain (mip 0 first, tightly packed RGBA8)
    /// starting at `offset` of a buffer, into layer `layer`.
    pub fn layer_regions(&self, layer: u32, offset: u64) -> Vec<vk::BufferImageCopy> {
        let (mut offset, mut side) = (offset, self.size);
        (0..self.mip_levels)
            .map(|mip| {
                let region = vk::BufferImageCopy::default()
                    .buffer_offset(offset)
                    .image_subresource(
                        vk::ImageSubresourceLayers::default()
                            .aspect_mask(vk::ImageAspectFlags::COLOR)
                            .mip_level(mip)
                            .base_array_layer(layer)
                            .layer_count(1),
                    )
                    .image_extent(vk::Extent3D { width: side, height: side, depth: 1 });
                offset += side as u64 * side as u64 * 4;
                side = (side / 2).max(1);
                region
            })
            .collect()
    }

    /// The image.
    pub fn handle(&self) -> vk::Image {
        self.handle
    }

    /// The view that samples texels as linear values.
    pub fn linear_view(&self) -> vk::ImageView {
        self.linear_view
    }

    /// The view that decodes sRGB texels when sampling.
    pub fn srgb_view(&self) -> vk::ImageView {
        self.srgb_view
    }

    /// Side of mip 0.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Layers.
    pub fn layers(&self) -> u32 {
        self.layers
    }

    /// Mip levels (the full chain down to 1x1).
    pub fn mip_levels(&self) -> u32 {
        self.mip_levels
    }

    /// Device bytes.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

impl Drop for TextureArray {
    fn drop(&mut self) {
        // SAFETY: the owner keeps the array until the GPU no longer uses it.
        unsafe {
            for view in [self.linear_view, self.srgb_view] {
                if view != vk::ImageView::null() {
                    self.shared.device.destroy_image_view(view, None);
                }
            }
            self.shared.device.destroy_image(self.handle, None);
        }
    }
}
