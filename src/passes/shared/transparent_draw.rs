//! Drawing transparent instances over an image: the pipeline of `transparent.frag` and the
//! recording of an indirect draw of them, shared by the `transparent` kind (which shades and
//! blends them) and the visibility oracle (which marks the ones it sees, so that it sees
//! exactly what the kind draws).

use super::gpu_types::DrawIndexedIndirect;
use super::scene_buffers::GpuScene;
use super::vertex_streams::{VertexFetch, VERTEX_STRIDES};
use crate::gpu::{
    cmd_set_full_viewport, Bind, Buffer, GpuContext, GraphicsDesc, Pipeline, ShaderCompiler, StencilRule,
};
use crate::passes::slots::LIT_OUTPUT_FORMAT;
use ash::vk;

/// What `transparent.frag` is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransparentShading {
    /// Shade and blend over one color attachment (the pass).
    Blend,
    /// Mark each instance with a fragment in front of the opaque depth, and draw nothing
    /// (`VISIBILITY_ORACLE`: the visibility oracle, so that it sees exactly what the pass draws).
    MarkSeen,
}

/// The pipeline of `transparent.frag` over `gbuffer.vert` for an opaque depth of `samples`
/// samples: no depth attachment (the shader tests depth), the cull mode set per draw.
pub fn transparent_pipeline(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    name: &str,
    samples: u32,
    shading: TransparentShading,
) -> crate::Result<Pipeline> {
    let samples = samples.max(1).to_string();
    let mut defines = vec![("SAMPLES", samples.as_str())];
    if shading == TransparentShading::MarkSeen {
        defines.push(("VISIBILITY_ORACLE", "1"));
    } else {
        // Transparent surfaces are few: they always take the shadow lookups (a view without
        // shadows binds an array that is never read), rather than a second pipeline.
        defines.push(("SHADOWS", "1"));
    }
    let vertex = shaders.compile("gbuffer/gbuffer.vert", &[])?;
    let fragment = shaders.compile("transparent/transparent.frag", &defines)?;
    let blend = shading == TransparentShading::Blend;
    Ok(Pipeline::graphics(
        ctx,
        name,
        &GraphicsDesc {
            vertex: &vertex,
            fragment: Some(&fragment),
            vertex_strides: &VERTEX_STRIDES,
            vertex_attributes: &VertexFetch::ALL.attributes(),
            color_formats: if blend { &[LIT_OUTPUT_FORMAT] } else { &[] },
            depth_format: vk::Format::UNDEFINED,
            depth_compare: vk::CompareOp::ALWAYS,
            depth_write: false,
            samples: vk::SampleCountFlags::TYPE_1,
            stencil: StencilRule::Off,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            blend,
        },
    )?)
}

/// Where a draw of transparent instances takes its commands: `max` commands from `offset` bytes
/// into `commands`, counted by the word at `count_offset` of `count`.
pub struct TransparentDraws<'a> {
    /// The commands.
    pub commands: &'a Buffer,
    /// Where in `commands` the first is.
    pub offset: u64,
    /// The count.
    pub count: &'a Buffer,
    /// Where in `count` the count is.
    pub count_offset: u64,
    /// Most commands drawn.
    pub max: u32,
}

/// Records `draws` with `pipeline` (from [`transparent_pipeline`]) in a rendering scope over
/// `colors` covering `extent`: bindings `binds` and push constants `push`, every face drawn
/// (the shader drops one-sided materials' back faces).
#[allow(clippy::too_many_arguments)]
pub fn record_transparent(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    pipeline: &Pipeline,
    scene: &GpuScene,
    colors: &[vk::RenderingAttachmentInfo<'_>],
    extent: vk::Extent2D,
    binds: &[Bind],
    push: &[u8],
    draws: &TransparentDraws<'_>,
) {
    let device = ctx.device();
    let rendering = vk::RenderingInfo::default()
        .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
        .layer_count(1)
        .color_attachments(colors);
    let stride = std::mem::size_of::<DrawIndexedIndirect>() as u32;
    // SAFETY: cmd is recording; every handle outlives the command buffer's execution.
    unsafe {
        device.cmd_begin_rendering(cmd, &rendering);
        cmd_set_full_viewport(device, cmd, extent);
        pipeline.bind(cmd);
        pipeline.push_constant_bytes(cmd, push);
        pipeline.push_bindings(cmd, binds);
        device.cmd_set_cull_mode(cmd, vk::CullModeFlags::NONE);
        scene.vertices.bind(device, cmd);
        device.cmd_bind_index_buffer(cmd, scene.indices.handle(), 0, vk::IndexType::UINT32);
        device.cmd_draw_indexed_indirect_count(
            cmd,
            draws.commands.handle(),
            draws.offset,
            draws.count.handle(),
            draws.count_offset,
            draws.max,
            stride,
        );
        device.cmd_end_rendering(cmd);
    }
}
