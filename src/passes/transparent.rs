//! `transparent`: draws the sorted transparent (alphaMode BLEND) instances of
//! `transparent_sort` over the lit image, back to front, forward-shaded and blended
//! (`shaders/transparent/transparent.frag`).
//!
//! The pass draws into the lighting's single-sample output and tests depth in its fragment
//! shader against every sample of the opaque depth: a fragment's alpha is scaled by the share of
//! samples it is in front of, so with any MSAA method an opaque edge crossing a transparent
//! surface is resolved as the lighting resolved the opaque image. Transparent surfaces write no
//! depth, so they hide nothing, from each other or from the culling.

use super::gbuffer::{bound_samples, DrawSource, VERTEX_ATTRIBUTES};
use super::slots::{draw_list_slots, ms, slot, LIT_OUTPUT_FORMAT};
use crate::gpu::{
    cmd_set_full_viewport, Bind, Buffer, GpuContext, GraphicsDesc, Pipeline, Sampler, ShaderCompiler, StencilRule,
};
use crate::graph::executor::PassContext;
use crate::graph::{
    FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, Quantity, SettingDecl, SlotDecl, Stages, Usage,
};
use crate::passes::gbuffer::LIST_SLOTS;
use crate::passes::shared::face_cull::FaceCull;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::scene_buffers::GpuScene;
use crate::passes::shared::SceneInputs;
use crate::passes::transparent_sort::{BLENDED, SORTED_COMMANDS_BYTES, SORTED_IDS_BYTES};
use ash::vk;

/// The kind's name.
pub const KIND: &str = "transparent";

/// What `transparent.frag` is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TransparentShading {
    /// Shade and blend over one color attachment (the pass).
    Blend,
    /// Mark each instance with a fragment in front of the opaque depth, and draw nothing
    /// (`VISIBILITY_ORACLE`: the visibility oracle, so that it sees exactly what the pass draws).
    MarkSeen,
}

/// The pipeline of `transparent.frag` over `gbuffer.vert` for an opaque depth of `samples`
/// samples: no depth attachment (the shader tests depth), the cull mode set per draw.
pub(crate) fn transparent_pipeline(
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
            vertex_stride: std::mem::size_of::<crate::scene::Vertex>() as u32,
            vertex_attributes: &VERTEX_ATTRIBUTES,
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
pub(crate) struct TransparentDraws<'a> {
    pub commands: &'a Buffer,
    pub offset: u64,
    pub count: &'a Buffer,
    pub count_offset: u64,
    pub max: u32,
}

/// Records `draws` with `pipeline` (from [`transparent_pipeline`]) in a rendering scope over
/// `colors` covering `extent`: bindings `binds` and push constants `push`, every face drawn
/// (the shader drops one-sided materials' back faces).
#[allow(clippy::too_many_arguments)]
pub(crate) fn record_transparent(
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
        device.cmd_bind_vertex_buffers(cmd, 0, &[scene.vertices.handle()], &[0]);
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

/// The `transparent` pass.
pub struct TransparentPass {
    pipeline: Pipeline,
    sampler: Sampler,
    exposure: f32,
}

impl PassNode for TransparentPass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let inputs = SceneInputs::of(rec)?;
        let scene = &inputs.scene;
        if scene.regions.len[FaceCull::Blended as usize] == 0 {
            // Nothing transparent in the scene: no need to load and store the lit image.
            return Ok(());
        }
        let slots = &rec.slots;
        let list = DrawSource {
            commands: slots.required_buffer(LIST_SLOTS[0])?,
            count: slots.required_buffer(LIST_SLOTS[1])?,
            instance_ids: slots.required_buffer(LIST_SLOTS[2])?,
        };
        let depth = slots.required_image("depth")?;
        let output = slots.required_image("output")?;
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(output.view())
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let mut binds = vec![
            Bind::Buffer(0, scene.instances.handle()),
            Bind::Buffer(1, list.instance_ids.handle()),
            Bind::Buffer(2, inputs.constants().handle()),
            Bind::Buffer(3, scene.materials.handle()),
            Bind::Buffer(4, inputs.lights().handle()),
            Bind::Sampled(5, depth.sampled_view(), self.sampler.handle(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
        ];
        binds.extend_from_slice(scene.textures.bindings());
        let stride = std::mem::size_of::<DrawIndexedIndirect>() as u64;
        let max = (list.commands.size() / stride).min(list.instance_ids.size() / 4).min(u32::MAX as u64) as u32;
        let draws = TransparentDraws { commands: list.commands, offset: 0, count: list.count, count_offset: 0, max };
        let push = bytemuck::bytes_of(&self.exposure);
        record_transparent(rec.ctx, rec.cmd, &self.pipeline, scene, &color, output.extent(), &binds, push, &draws);
        Ok(())
    }
}

/// The `transparent` pass kind.
pub struct TransparentKind;

impl PassKind for TransparentKind {
    fn info(&self) -> PassKindInfo {
        let mut list = draw_list_slots(true);
        // One command per instance, counted by one word (transparent_sort's output).
        list[0] = list[0].at_least(SORTED_COMMANDS_BYTES);
        list[0].doc = "one VkDrawIndexedIndirectCommand per transparent instance, in drawing order";
        list[1] = list[1].at_least("4");
        list[1].doc = "their number";
        list[2] = list[2].at_least(SORTED_IDS_BYTES);
        let depth: SlotDecl = ms(slot(
            "depth",
            Usage::Sampled(Stages::Fragment),
            true,
            FormatRule::Depth,
            "the opaque reversed-Z depth (multisampled: tested at every sample)",
        ));
        let mut reads = list;
        reads.push(depth);
        PassKindInfo {
            name: KIND,
            doc: "draws transparent (alphaMode BLEND) instances in the given order over the lit image, forward-shaded and alpha-blended, depth-tested against every sample of the opaque depth",
            reads,
            writes: vec![slot(
                "output",
                Usage::ColorAttachmentLoad,
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "the lit image, blended over",
            )],
            settings: vec![SettingDecl::real(
                "exposure",
                0.8,
                (0.0, 1.0e6),
                "scale applied before tone mapping (the lighting pass's)",
            )],
            slots_from_shader: false,
        }
    }

    fn quantities(&self) -> Vec<Quantity> {
        vec![BLENDED]
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        let samples = bound_samples(s.plan, s.pass, "depth");
        let pipeline = transparent_pipeline(s.ctx, s.shaders, &s.pass.name, samples, TransparentShading::Blend)?;
        Ok(Box::new(TransparentPass {
            pipeline,
            sampler: Sampler::nearest_clamp(s.ctx)?,
            exposure: s.pass.real("exposure")? as f32,
        }))
    }
}
