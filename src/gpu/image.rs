//! Images (2D, optionally mipmapped or multisampled) backed by `gpu-allocator`.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuError, GpuResult, VkResultExt};
use super::memory::MemoryBlock;
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
    /// Depth aspect alone, for sampling a depth+stencil image (null otherwise).
    depth_view: vk::ImageView,
    allocation: Option<Allocation>,
    format: vk::Format,
    extent: vk::Extent2D,
    mip_levels: u32,
    samples: vk::SampleCountFlags,
    name: String,
    /// Owned by a host engine: never destroyed here.
    external: bool,
    /// The array layer this image is (0 but for a host's layer of an array).
    layer: u32,
}

/// A host engine's image as cullgraph should see it (see [`Image::from_host`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct HostImage {
    /// The image.
    pub image: vk::Image,
    /// A view of all its mips and aspects (2D, the image's format). cullgraph makes any view
    /// of a part it needs (a mip, the depth aspect of a depth+stencil image) itself.
    pub view: vk::ImageView,
    /// Its format.
    pub format: vk::Format,
    /// Size of mip 0.
    pub extent: vk::Extent2D,
    /// Mip levels.
    pub mip_levels: u32,
    /// Samples per texel.
    pub samples: vk::SampleCountFlags,
    /// The array layer `view` shows: 0 for a plain 2D image. Barriers and the views cullgraph
    /// makes of the image's parts cover this layer alone, so that several graphs can each
    /// draw into their own layer of one array (the renderer's shadow maps).
    pub layer: u32,
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
    /// Creates the image, binds memory of its own and creates its views.
    pub fn new(ctx: &GpuContext, desc: &ImageDesc<'_>) -> GpuResult<Self> {
        let mut image = Self::unbound(ctx, desc)?;
        // SAFETY: handle was just created.
        let requirements = unsafe { ctx.device().get_image_memory_requirements(image.handle) };
        let allocation = ctx.shared.allocator().allocate(&AllocationCreateDesc {
            name: desc.name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = allocation.map_err(|source| GpuError::Allocation { name: desc.name.into(), source })?;
        // SAFETY: the allocation stays alive in `image` for as long as the image.
        let (memory, offset) = (unsafe { allocation.memory() }, allocation.offset());
        image.allocation = Some(allocation);
        image.bind(memory, offset)?;
        Ok(image)
    }

    /// Creates the image inside `block` at `offset` (memory shared with other resources whose
    /// lifetimes do not overlap). The block must outlive the image.
    pub fn new_in(ctx: &GpuContext, desc: &ImageDesc<'_>, block: &MemoryBlock, offset: u64) -> GpuResult<Self> {
        let mut image = Self::unbound(ctx, desc)?;
        image.bind(block.memory(), block.offset() + offset)?;
        Ok(image)
    }

    /// What an image of `desc` needs from memory, without creating one (Vulkan 1.3 maintenance4).
    pub fn requirements(ctx: &GpuContext, desc: &ImageDesc<'_>) -> GpuResult<vk::MemoryRequirements> {
        validate_desc(ctx, desc)?;
        let info = create_info(desc);
        let query = vk::DeviceImageMemoryRequirements::default().create_info(&info);
        let mut out = vk::MemoryRequirements2::default();
        // SAFETY: valid create info.
        unsafe { ctx.device().get_device_image_memory_requirements(&query, &mut out) };
        Ok(out.memory_requirements)
    }

    fn unbound(ctx: &GpuContext, desc: &ImageDesc<'_>) -> GpuResult<Self> {
        validate_desc(ctx, desc)?;
        let shared = ctx.shared.clone();
        // SAFETY: valid device and create info.
        let handle = unsafe { shared.device.create_image(&create_info(desc), None) }.vk("vkCreateImage")?;
        Ok(Self {
            shared,
            handle,
            view: vk::ImageView::null(),
            mip_views: Vec::new(),
            depth_view: vk::ImageView::null(),
            allocation: None,
            format: desc.format,
            extent: desc.extent,
            mip_levels: desc.mip_levels,
            samples: desc.samples,
            name: desc.name.into(),
            external: false,
            layer: 0,
        })
    }

    /// Wraps a host engine's image without taking ownership: the image and `host.view` stay the
    /// host's. The views that passes need and the host's does not give (one per mip of a
    /// mipmapped image, the depth aspect alone of a depth+stencil image) are made here and
    /// destroyed with the wrapper, so keep it until the frames that use it have executed.
    pub fn from_host(ctx: &GpuContext, name: &str, host: &HostImage) -> GpuResult<Self> {
        let mut image = Self {
            shared: ctx.shared.clone(),
            handle: host.image,
            view: host.view,
            mip_views: Vec::new(),
            depth_view: vk::ImageView::null(),
            allocation: None,
            format: host.format,
            extent: host.extent,
            mip_levels: host.mip_levels.max(1),
            samples: host.samples,
            name: name.into(),
            external: true,
            layer: host.layer,
        };
        image.create_part_views()?;
        Ok(image)
    }

    /// Binds memory and creates the views.
    fn bind(&mut self, memory: vk::DeviceMemory, offset: u64) -> GpuResult<()> {
        // SAFETY: memory is compatible and large enough (caller contract: requirements honoured).
        unsafe { self.shared.device.bind_image_memory(self.handle, memory, offset) }.vk("vkBindImageMemory")?;
        self.view = self.create_view(0, self.mip_levels)?;
        self.create_part_views()
    }

    /// The views of parts of the image: the depth aspect of a depth+stencil image (a sampled
    /// view may show one aspect only) and each mip of a mipmapped one (storage views show one).
    fn create_part_views(&mut self) -> GpuResult<()> {
        if self.aspect() == vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL {
            let info = vk::ImageViewCreateInfo::default()
                .image(self.handle)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(self.format)
                .subresource_range(
                    self.subresource_range_mips(0, self.mip_levels).aspect_mask(vk::ImageAspectFlags::DEPTH),
                );
            // SAFETY: valid image with bound memory.
            self.depth_view = unsafe { self.shared.device.create_image_view(&info, None) }.vk("vkCreateImageView")?;
        }
        if self.mip_levels > 1 {
            for level in 0..self.mip_levels {
                let view = self.create_view(level, 1)?;
                self.mip_views.push(view);
            }
        }
        Ok(())
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
    /// The view to sample or read in shaders: for a depth+stencil image its depth aspect
    /// (a sampled view may show one aspect only), otherwise [`Image::view`].
    pub fn sampled_view(&self) -> vk::ImageView {
        if self.depth_view == vk::ImageView::null() {
            self.view
        } else {
            self.depth_view
        }
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
            .base_array_layer(self.layer)
            .layer_count(1)
    }
}

fn validate_desc(ctx: &GpuContext, desc: &ImageDesc<'_>) -> GpuResult<()> {
    let max_dim = ctx.caps().limits.max_image_dimension2_d;
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
    Ok(())
}

fn create_info<'a>(desc: &ImageDesc<'_>) -> vk::ImageCreateInfo<'a> {
    vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(desc.format)
        .extent(vk::Extent3D { width: desc.extent.width, height: desc.extent.height, depth: 1 })
        .mip_levels(desc.mip_levels)
        .array_layers(1)
        .samples(desc.samples)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(desc.usage)
        .sharing_mode(vk::SharingMode::EXCLUSIVE)
        .initial_layout(vk::ImageLayout::UNDEFINED)
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: the caller guarantees the GPU no longer uses the image or its views. A host's
        // image and view stay the host's; the views made for its parts are ours.
        unsafe {
            for v in self.mip_views.drain(..) {
                self.shared.device.destroy_image_view(v, None);
            }
            if self.depth_view != vk::ImageView::null() {
                self.shared.device.destroy_image_view(self.depth_view, None);
            }
            if self.external {
                return;
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
