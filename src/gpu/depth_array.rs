//! A square `D32_SFLOAT` 2D array image that graphs draw into layer by layer (each layer handed
//! to a graph as a [`HostImage`]) and shaders sample whole, with depth comparison: the shadow
//! maps of a view.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use super::image::HostImage;
use super::memory::MemoryBlock;
use ash::vk;
use std::sync::Arc;

/// The texel format of a [`DepthArray`].
pub const DEPTH_ARRAY_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// See the module documentation; freed on drop.
pub struct DepthArray {
    shared: Arc<DeviceShared>,
    handle: vk::Image,
    /// Every layer, as a 2D array (what shaders sample).
    array_view: vk::ImageView,
    /// One 2D view per layer (what a graph draws into).
    layer_views: Vec<vk::ImageView>,
    /// Freed after the image (fields drop after `Drop::drop` destroys it).
    memory: Option<MemoryBlock>,
    size: u32,
    bytes: u64,
    /// Distinguishes this array from every other made in the process (Vulkan may give a
    /// destroyed image's handles to a new one).
    id: u64,
}

impl DepthArray {
    /// A `size` x `size` array of `layers` layers, in undefined layout.
    pub fn new(ctx: &GpuContext, name: &str, size: u32, layers: u32) -> GpuResult<Self> {
        let limits = ctx.caps().limits;
        let bad = |reason: String| GpuError::InvalidResource { name: name.into(), reason };
        if size == 0 || size > limits.max_image_dimension2_d {
            return Err(bad(format!("size {size}: the device takes 1 to {}", limits.max_image_dimension2_d)));
        }
        if layers == 0 || layers > limits.max_image_array_layers {
            return Err(bad(format!("{layers} layers: the device takes 1 to {}", limits.max_image_array_layers)));
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(DEPTH_ARRAY_FORMAT)
            .extent(vk::Extent3D { width: size, height: size, depth: 1 })
            .mip_levels(1)
            .array_layers(layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let shared = ctx.shared.clone();
        // SAFETY: valid device and create info.
        let handle = unsafe { shared.device.create_image(&info, None) }.vk("vkCreateImage")?;
        let mut array = Self {
            shared,
            handle,
            array_view: vk::ImageView::null(),
            layer_views: Vec::new(),
            memory: None,
            size,
            bytes: 0,
            id: {
                static MADE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
                MADE.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            },
        };
        let memory = MemoryBlock::bound_to_image(ctx, name, handle)?;
        array.bytes = memory.size();
        array.memory = Some(memory);
        array.array_view = array.view(vk::ImageViewType::TYPE_2D_ARRAY, 0, layers)?;
        for layer in 0..layers {
            let view = array.view(vk::ImageViewType::TYPE_2D, layer, 1)?;
            array.layer_views.push(view);
        }
        Ok(array)
    }

    fn view(&self, kind: vk::ImageViewType, base: u32, count: u32) -> GpuResult<vk::ImageView> {
        let range = self.range().base_array_layer(base).layer_count(count);
        let info = vk::ImageViewCreateInfo::default()
            .image(self.handle)
            .view_type(kind)
            .format(DEPTH_ARRAY_FORMAT)
            .subresource_range(range);
        // SAFETY: valid image with bound memory.
        unsafe { self.shared.device.create_image_view(&info, None) }.vk("vkCreateImageView")
    }

    /// Every layer.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::DEPTH)
            .level_count(1)
            .layer_count(self.layer_views.len().max(1) as u32)
    }

    /// The Vulkan handle.
    pub fn handle(&self) -> vk::Image {
        self.handle
    }

    /// What distinguishes this array from every other made in the process, even one that
    /// Vulkan gave the same handles.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Every layer as a 2D array view, for sampling.
    pub fn array_view(&self) -> vk::ImageView {
        self.array_view
    }

    /// Layer `layer` as an image a graph can import (`Imported(Image(format: D32_SFLOAT))`).
    pub fn layer(&self, layer: u32) -> HostImage {
        HostImage {
            image: self.handle,
            view: self.layer_views[layer as usize],
            format: DEPTH_ARRAY_FORMAT,
            extent: vk::Extent2D { width: self.size, height: self.size },
            mip_levels: 1,
            samples: vk::SampleCountFlags::TYPE_1,
            layer,
        }
    }

    /// Width and height of a layer.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Layers.
    pub fn layers(&self) -> u32 {
        self.layer_views.len() as u32
    }

    /// Device memory it takes.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }
}

impl Drop for DepthArray {
    fn drop(&mut self) {
        // SAFETY: the caller guarantees the GPU no longer uses the image or its views.
        unsafe {
            for view in self.layer_views.drain(..) {
                self.shared.device.destroy_image_view(view, None);
            }
            self.shared.device.destroy_image_view(self.array_view, None);
            self.shared.device.destroy_image(self.handle, None);
        }
    }
}
