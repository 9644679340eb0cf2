//! How a pass uses a resource: the Vulkan stage, access and layout that follow from it, and the
//! usage flags the resource must be created with.

use crate::gpu::Access;
use ash::vk;

/// Shader stages that touch a resource.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stages {
    /// A compute shader.
    Compute,
    /// The vertex shader.
    Vertex,
    /// The fragment shader.
    Fragment,
    /// Vertex and fragment shaders.
    Graphics,
    /// A compute dispatch and the fragment shader of the same pass (a clear, then a draw).
    ComputeFragment,
}

impl Stages {
    fn flags(self) -> vk::PipelineStageFlags2 {
        match self {
            Stages::Compute => vk::PipelineStageFlags2::COMPUTE_SHADER,
            Stages::Vertex => vk::PipelineStageFlags2::VERTEX_SHADER,
            Stages::Fragment => vk::PipelineStageFlags2::FRAGMENT_SHADER,
            Stages::Graphics => vk::PipelineStageFlags2::VERTEX_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER,
            Stages::ComputeFragment => {
                vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER
            }
        }
    }
}

/// One way a pass uses a resource bound to one of its slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Usage {
    /// Color attachment, cleared or overwritten (previous contents not read).
    ColorAttachment,
    /// Color attachment whose previous contents are loaded and blended or overwritten.
    ColorAttachmentLoad,
    /// Depth attachment cleared and written.
    DepthAttachment,
    /// Depth attachment loaded, tested and written (a second geometry pass).
    DepthAttachmentLoad,
    /// Depth attachment loaded and tested only (e.g. depth EQUAL).
    DepthAttachmentReadOnly,
    /// Image read through a sampler (`texture`/`texelFetch`).
    Sampled(Stages),
    /// Storage image read.
    StorageImageRead(Stages),
    /// Storage image written without reading previous contents.
    StorageImageWrite(Stages),
    /// Storage image read and written.
    StorageImageReadWrite(Stages),
    /// Storage buffer read.
    StorageBufferRead(Stages),
    /// Storage buffer written without reading previous contents.
    StorageBufferWrite(Stages),
    /// Storage buffer read and written (counters, accumulators).
    StorageBufferReadWrite(Stages),
    /// Uniform buffer.
    Uniform(Stages),
    /// Indirect draw or dispatch arguments and counts.
    Indirect,
    /// Source of a transfer (copy, blit).
    TransferSrc,
    /// Destination of a transfer (copy, fill, clear).
    TransferDst,
}

impl Usage {
    /// Whether the resource is an image (false: a buffer).
    pub fn is_image(self) -> bool {
        use Usage::*;
        matches!(
            self,
            ColorAttachment
                | ColorAttachmentLoad
                | DepthAttachment
                | DepthAttachmentLoad
                | DepthAttachmentReadOnly
                | Sampled(_)
                | StorageImageRead(_)
                | StorageImageWrite(_)
                | StorageImageReadWrite(_)
        )
    }

    /// Whether the usage could be either (transfers).
    pub fn is_image_or_buffer(self) -> bool {
        matches!(self, Usage::TransferSrc | Usage::TransferDst)
    }

    /// Whether the pass writes the resource.
    pub fn writes(self) -> bool {
        use Usage::*;
        matches!(
            self,
            ColorAttachment
                | ColorAttachmentLoad
                | DepthAttachment
                | DepthAttachmentLoad
                | StorageImageWrite(_)
                | StorageImageReadWrite(_)
                | StorageBufferWrite(_)
                | StorageBufferReadWrite(_)
                | TransferDst
        )
    }

    /// Whether the pass reads the contents that were there before it ran.
    pub fn reads(self) -> bool {
        use Usage::*;
        !matches!(self, ColorAttachment | DepthAttachment | StorageImageWrite(_) | StorageBufferWrite(_) | TransferDst)
    }

    /// Whether the usage is a render-target attachment (whose sample count is the pass's).
    pub fn is_attachment(self) -> bool {
        use Usage::*;
        matches!(
            self,
            ColorAttachment | ColorAttachmentLoad | DepthAttachment | DepthAttachmentLoad | DepthAttachmentReadOnly
        )
    }

    /// Whether the usage needs a depth format.
    pub fn needs_depth_format(self) -> bool {
        matches!(self, Usage::DepthAttachment | Usage::DepthAttachmentLoad | Usage::DepthAttachmentReadOnly)
    }

    /// Stage, access mask and image layout of this use.
    pub fn access(self) -> Access {
        use Usage::*;
        let a = |stage: vk::PipelineStageFlags2, access: vk::AccessFlags2, layout: vk::ImageLayout| Access {
            stage,
            access,
            layout,
        };
        let depth_stages = vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
        match self {
            ColorAttachment => a(
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            ),
            ColorAttachmentLoad => a(
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            ),
            DepthAttachment | DepthAttachmentLoad => a(
                depth_stages,
                vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            ),
            DepthAttachmentReadOnly => a(
                depth_stages,
                vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
                vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
            ),
            Sampled(s) => {
                a(s.flags(), vk::AccessFlags2::SHADER_SAMPLED_READ, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            }
            StorageImageRead(s) => a(s.flags(), vk::AccessFlags2::SHADER_STORAGE_READ, vk::ImageLayout::GENERAL),
            StorageImageWrite(s) => a(s.flags(), vk::AccessFlags2::SHADER_STORAGE_WRITE, vk::ImageLayout::GENERAL),
            StorageImageReadWrite(s) => a(
                s.flags(),
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
                vk::ImageLayout::GENERAL,
            ),
            StorageBufferRead(s) => a(s.flags(), vk::AccessFlags2::SHADER_STORAGE_READ, vk::ImageLayout::UNDEFINED),
            StorageBufferWrite(s) => a(s.flags(), vk::AccessFlags2::SHADER_STORAGE_WRITE, vk::ImageLayout::UNDEFINED),
            StorageBufferReadWrite(s) => a(
                s.flags(),
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
                vk::ImageLayout::UNDEFINED,
            ),
            Uniform(s) => a(s.flags(), vk::AccessFlags2::UNIFORM_READ, vk::ImageLayout::UNDEFINED),
            Indirect => a(
                vk::PipelineStageFlags2::DRAW_INDIRECT,
                vk::AccessFlags2::INDIRECT_COMMAND_READ,
                vk::ImageLayout::UNDEFINED,
            ),
            TransferSrc => a(
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_READ,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            ),
            TransferDst => a(
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            ),
        }
    }

    /// Image usage flags this use requires.
    pub fn image_usage(self) -> vk::ImageUsageFlags {
        use Usage::*;
        match self {
            ColorAttachment | ColorAttachmentLoad => vk::ImageUsageFlags::COLOR_ATTACHMENT,
            DepthAttachment | DepthAttachmentLoad | DepthAttachmentReadOnly => {
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
            }
            Sampled(_) => vk::ImageUsageFlags::SAMPLED,
            StorageImageRead(_) | StorageImageWrite(_) | StorageImageReadWrite(_) => vk::ImageUsageFlags::STORAGE,
            TransferSrc => vk::ImageUsageFlags::TRANSFER_SRC,
            TransferDst => vk::ImageUsageFlags::TRANSFER_DST,
            _ => vk::ImageUsageFlags::empty(),
        }
    }

    /// Buffer usage flags this use requires.
    pub fn buffer_usage(self) -> vk::BufferUsageFlags {
        use Usage::*;
        match self {
            StorageBufferRead(_) | StorageBufferWrite(_) | StorageBufferReadWrite(_) => {
                vk::BufferUsageFlags::STORAGE_BUFFER
            }
            Uniform(_) => vk::BufferUsageFlags::UNIFORM_BUFFER,
            Indirect => vk::BufferUsageFlags::INDIRECT_BUFFER,
            TransferSrc => vk::BufferUsageFlags::TRANSFER_SRC,
            TransferDst => vk::BufferUsageFlags::TRANSFER_DST,
            _ => vk::BufferUsageFlags::empty(),
        }
    }
}
