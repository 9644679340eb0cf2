//! synchronization2 barrier helpers: one place that knows how to spell a layout transition.

use super::image::Image;
use ash::vk;

/// A pipeline stage plus the accesses a use of a resource makes there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Access {
    /// Stages that touch the resource.
    pub stage: vk::PipelineStageFlags2,
    /// How they touch it.
    pub access: vk::AccessFlags2,
    /// Image layout during the use (ignored for buffers).
    pub layout: vk::ImageLayout,
}

impl Access {
    /// Nothing happened yet: contents are undefined.
    pub const NONE: Access = Access {
        stage: vk::PipelineStageFlags2::NONE,
        access: vk::AccessFlags2::NONE,
        layout: vk::ImageLayout::UNDEFINED,
    };
    /// Transfer destination.
    pub const TRANSFER_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::ALL_TRANSFER,
        access: vk::AccessFlags2::TRANSFER_WRITE,
        layout: vk::ImageLayout::TRANSFER_DST_OPTIMAL,
    };
    /// Transfer source.
    pub const TRANSFER_READ: Access = Access {
        stage: vk::PipelineStageFlags2::ALL_TRANSFER,
        access: vk::AccessFlags2::TRANSFER_READ,
        layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    };
    /// Color attachment written by a draw.
    pub const COLOR_ATTACHMENT: Access = Access {
        stage: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw() | vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw(),
        ),
        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    };
    /// Depth attachment tested and written by a draw.
    pub const DEPTH_ATTACHMENT: Access = Access {
        stage: vk::PipelineStageFlags2::from_raw(
            vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
                | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
        ),
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw(),
        ),
        layout: vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
    };
    /// Sampled or storage-read by a compute shader.
    pub const COMPUTE_READ: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::SHADER_READ,
        layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    };
    /// Storage image or buffer written (and possibly read) by a compute shader.
    pub const COMPUTE_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw() | vk::AccessFlags2::SHADER_STORAGE_READ.as_raw(),
        ),
        layout: vk::ImageLayout::GENERAL,
    };
    /// Read by the vertex or fragment stage of a draw (storage buffers, sampled images).
    pub const GRAPHICS_READ: Access = Access {
        stage: vk::PipelineStageFlags2::from_raw(
            vk::PipelineStageFlags2::VERTEX_SHADER.as_raw() | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw(),
        ),
        access: vk::AccessFlags2::SHADER_READ,
        layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    };
    /// Indirect draw commands and counts.
    pub const INDIRECT: Access = Access {
        stage: vk::PipelineStageFlags2::DRAW_INDIRECT,
        access: vk::AccessFlags2::INDIRECT_COMMAND_READ,
        layout: vk::ImageLayout::UNDEFINED,
    };
    /// Vertex and index fetch.
    pub const VERTEX_INPUT: Access = Access {
        stage: vk::PipelineStageFlags2::VERTEX_INPUT,
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ.as_raw() | vk::AccessFlags2::INDEX_READ.as_raw(),
        ),
        layout: vk::ImageLayout::UNDEFINED,
    };
    /// Read by the host after the GPU is done.
    pub const HOST_READ: Access = Access {
        stage: vk::PipelineStageFlags2::HOST,
        access: vk::AccessFlags2::HOST_READ,
        layout: vk::ImageLayout::UNDEFINED,
    };
}

/// An image barrier moving `image` (all mips) from `before` to `after`.
pub fn image_barrier(image: &Image, before: Access, after: Access) -> vk::ImageMemoryBarrier2<'static> {
    let format = image.format();
    let before = Access { layout: layout_for_format(before.layout, format), ..before };
    let after = Access { layout: layout_for_format(after.layout, format), ..after };
    image_barrier_raw(image.handle(), image.subresource_range(), before, after)
}

/// The layout to use for an image of `format`: the depth-only attachment layouts become their
/// depth+stencil forms for formats with stencil, so one layout covers both aspects (passes
/// and the graph name layouts without knowing whether the depth image has stencil).
pub fn layout_for_format(layout: vk::ImageLayout, format: vk::Format) -> vk::ImageLayout {
    if !crate::gpu::image::aspect_of(format).contains(vk::ImageAspectFlags::STENCIL) {
        return layout;
    }
    match layout {
        vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL => vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL => vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
        other => other,
    }
}

/// An image barrier on a raw handle and subresource range.
pub fn image_barrier_raw(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    before: Access,
    after: Access,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(before.stage)
        .src_access_mask(before.access)
        .dst_stage_mask(after.stage)
        .dst_access_mask(after.access)
        .old_layout(before.layout)
        .new_layout(after.layout)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range)
}

/// A global memory barrier (buffers) from `before` to `after`.
pub fn memory_barrier(before: Access, after: Access) -> vk::MemoryBarrier2<'static> {
    vk::MemoryBarrier2::default()
        .src_stage_mask(before.stage)
        .src_access_mask(before.access)
        .dst_stage_mask(after.stage)
        .dst_access_mask(after.access)
}

/// Records one `vkCmdPipelineBarrier2` with the given barriers (nothing when both lists are empty).
pub fn cmd_barriers(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    memory: &[vk::MemoryBarrier2<'_>],
    images: &[vk::ImageMemoryBarrier2<'_>],
) {
    if memory.is_empty() && images.is_empty() {
        return;
    }
    let dep = vk::DependencyInfo::default().memory_barriers(memory).image_memory_barriers(images);
    // SAFETY: cmd is recording (caller contract); the barriers reference live resources.
    unsafe { device.cmd_pipeline_barrier2(cmd, &dep) };
}
