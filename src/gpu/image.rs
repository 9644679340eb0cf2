//! Images (2D, optionally mipmapped or multisampled) backed by `gpu-allocator`.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// What an image is for.
#[derive(Clone, Debug)]
pub struct ImageDesc<'a> {
    /// Debug name.
    pub name: &'a str,
    /// Texel format.
    pub format: vk::Format,
    /// Width and height in texels (each at least 1).
    pub extent: vk::Extent2D,
    /// Number of mip levels (at least 1).
    pub mip_levels: u32,
    /// Samples per texel.
    pub samples: vk::SampleCountFlags,
    /// Vulkan usage flags.
    pub usage: vk::ImageUsageFlags,
}

/// A 2D image with a view of all mips and one view per mip; freed on drop.
pub struct Image {
    shared: Arc<DeviceShared>,
    handle: vk::Image,
    view: vk::ImageView,
    mip_views: Vec<vk::ImageView>,
    allocation: Option<Allocation>,
    format: vk::Format,
    extent: vk::Extent2D,
    mip_levels: u32,
    samples: vk::SampleCountFlags,
    name: String,
}

/// The aspect of a format: depth, depth+stencil or color.
pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
        vk::Format::D16_UNORM_S8_UINT | vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        vk::Format::S8_UINT => vk::ImageAspectFlags::STENCIL,
        _ => vk::ImageAspectFlags::COLOR,
    }
}

impl Image {
    /// Creates the image, binds memory and creates its views.
    pub fn new(ctx: &GpuContext, desc: &ImageDesc<'_>) -> GpuResult<Self> {
        let shared = ctx.shared.clone();
        let limits = &shared.caps.limits;
        let max_dim = limits.max_image_dimension2_d;
        let bad = |reason: String| GpuError::InvalidResource { name: desc.name.into(), reason };
        if desc.extent.width == 0 || desc.extent.height == 0 {
            return Err(bad(format!("size {}x{} is empty", desc.extent.width, desc.extent.height)));
        }
        if desc.extent.width > max_dim || desc.extent.height > max_dim {
            return Err(bad(format!(
                "size {}x{} exceeds the device limit of {max_dim}",
                desc.extent.width, desc.extent.height
            )));
        }
        let full_chain = 32 - desc.extent.width.max(desc.extent.height).leading_zeros();
        if desc.mip_levels == 0 || desc.mip_levels > full_chain {
            return Err(bad(format!("{} mip levels requested, 1..={full_chain} possible", desc.mip_levels)));
        }
        let device = &shared.device;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.extent.width, height: desc.extent.height, depth: 1 })
            .mip_levels(desc.mip_levels)
            .array_layers(1)
            .samples(desc.samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and create info.
        let handle = unsafe { device.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: handle was just created.
        let requirements = unsafe { device.get_image_memory_requirements(handle) };
        let allocation = shared.allocator().allocate(&AllocationCreateDesc {
            name: desc.name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: not bound, not used.
                unsafe { device.destroy_image(handle, None) };
                return Err(GpuError::Allocation { name: desc.name.into(), source });
            }
        };
        let mut image = Self {
            shared: shared.clone(),
            handle,
            view: vk::ImageView::null(),
            mip_views: Vec::new(),
            allocation: Some(allocation),
            format: desc.format,
            extent: desc.extent,
            mip_levels: desc.mip_levels,
            samples: desc.samples,
            name: desc.name.into(),
        };
        let allocation = image.allocation.as_ref().expect("set above");
        // SAFETY: memory comes from a compatible allocation.
        unsafe { device.bind_image_memory(handle, allocation.memory(), allocation.offset()) }
            .vk("vkBindImageMemory")?;
        image.view = image.create_view(0, desc.mip_levels)?;
        if desc.mip_levels > 1 {
            for level in 0..desc.mip_levels {
                let view = image.create_view(level, 1)?;
                image.mip_views.push(view);
            }
        }
        Ok(image)
    }

    fn create_view(&self, base_mip: u32, count: u32) -> GpuResult<vk::ImageView> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.handle)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(self.format)
            .subresource_range(self.subresource_range_mips(base_mip, count));
        // SAFETY: valid image with bound memory.
        unsafe { self.shared.device.create_image_view(&info, None) }.vk("vkCreateImageView")
    }

    /// The Vulkan handle.
    pub fn handle(&self) -> vk::Image {
        self.handle
    }
    /// View of all mip levels.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }
    /// View of one mip level (the full view when the image has a single level).
    pub fn mip_view(&self, level: u32) -> vk::ImageView {
        self.mip_views.get(level as usize).copied().unwrap_or(self.view)
    }
    /// Texel format.
    pub fn format(&self) -> vk::Format {
        self.format
    }
    /// Size of mip 0.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }
    /// Number of mip levels.
    pub fn mip_levels(&self) -> u32 {
        self.mip_levels
    }
    /// Samples per texel.
    pub fn samples(&self) -> vk::SampleCountFlags {
        self.samples
    }
    /// Debug name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Depth, stencil or color.
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.format)
    }
    /// All mips, the single layer.
    pub fn subresource_range(&self) -> vk::ImageSubresourceRange {
        self.subresource_range_mips(0, self.mip_levels)
    }
    fn subresource_range_mips(&self, base_mip: u32, count: u32) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(self.aspect())
            .base_mip_level(base_mip)
            .level_count(count)
            .base_array_layer(0)
            .layer_count(1)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: the caller guarantees the GPU no longer uses the image.
        unsafe {
            for v in self.mip_views.drain(..) {
                self.shared.device.destroy_image_view(v, None);
            }
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

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Image")
            .field("name", &self.name)
            .field("format", &self.format)
            .field("extent", &(self.extent.width, self.extent.height))
            .field("mips", &self.mip_levels)
            .field("samples", &self.samples)
            .finish()
    }
}
