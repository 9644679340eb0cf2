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
use crate::gpu::{cmd_set_full_viewport, Bind, GraphicsDesc, Pipeline, Sampler, StencilRule};
use crate::graph::executor::PassContext;
use crate::graph::{
    FormatRule, MinBytes, NodeSetup, PassKind, PassKindInfo, PassNode, SettingDecl, SettingDefault, SlotDecl, Stages,
    Usage,
};
use crate::passes::gbuffer::LIST_SLOTS;
use crate::passes::shared::face_cull::FaceCull;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::SceneInputs;
use ash::vk;

/// The kind's name.
pub const KIND: &str = "transparent";

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
        let extent = output.extent();
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(output.view())
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&color);
        let mut binds = vec![
            Bind::Buffer(0, scene.instances.handle()),
            Bind::Buffer(1, list.instance_ids.handle()),
            Bind::Buffer(2, inputs.constants().handle()),
            Bind::Buffer(3, scene.materials.handle()),
            Bind::Buffer(4, inputs.lights().handle()),
            Bind::Sampled(5, depth.sampled_view(), self.sampler.handle(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
        ];
        binds.extend_from_slice(scene.textures.bindings());
        let stride = std::mem::size_of::<DrawIndexedIndirect>() as u32;
        let max_draws = (list.commands.size() / stride as u64).min(list.instance_ids.size() / 4).min(u32::MAX as u64);
        let device = rec.ctx.device();
        // SAFETY: cmd is recording; every handle outlives the command buffer's execution.
        unsafe {
            device.cmd_begin_rendering(rec.cmd, &rendering);
            cmd_set_full_viewport(device, rec.cmd, extent);
            self.pipeline.bind(rec.cmd);
            self.pipeline.push_constant_bytes(rec.cmd, bytemuck::bytes_of(&self.exposure));
            self.pipeline.push_bindings(rec.cmd, &binds);
            // Back faces of one-sided materials are dropped in the shader.
            device.cmd_set_cull_mode(rec.cmd, vk::CullModeFlags::NONE);
            device.cmd_bind_vertex_buffers(rec.cmd, 0, &[scene.vertices.handle()], &[0]);
            device.cmd_bind_index_buffer(rec.cmd, scene.indices.handle(), 0, vk::IndexType::UINT32);
            device.cmd_draw_indexed_indirect_count(
                rec.cmd,
                list.commands.handle(),
                0,
                list.count.handle(),
                0,
                max_draws as u32,
                stride,
            );
            device.cmd_end_rendering(rec.cmd);
        }
        Ok(())
    }
}

/// The `transparent` pass kind.
pub struct TransparentKind;

impl PassKind for TransparentKind {
    fn info(&self) -> PassKindInfo {
        let mut list = draw_list_slots(true);
        // One command per instance, counted by one word (transparent_sort's output).
        list[0].min_bytes = MinBytes::PerBlended(std::mem::size_of::<DrawIndexedIndirect>() as u64);
        list[0].doc = "one VkDrawIndexedIndirectCommand per transparent instance, in drawing order";
        list[1].min_bytes = MinBytes::Fixed(4);
        list[1].doc = "their number";
        list[2].min_bytes = MinBytes::PerBlended(4);
        list[2].usage = Usage::StorageBufferRead(Stages::Vertex);
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
            settings: vec![SettingDecl {
                name: "exposure",
                default: SettingDefault::Float(0.8),
                range: Some((0.0, 1.0e6)),
                doc: "scale applied before tone mapping (the lighting pass's)",
            }],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        let samples = bound_samples(s.plan, s.pass, "depth").to_string();
        let vertex = s.shaders.compile("gbuffer/gbuffer.vert", &[])?;
        let fragment = s.shaders.compile("transparent/transparent.frag", &[("SAMPLES", &samples)])?;
        let pipeline = Pipeline::graphics(
            s.ctx,
            &s.pass.name,
            &GraphicsDesc {
                vertex: &vertex,
                fragment: Some(&fragment),
                vertex_stride: std::mem::size_of::<crate::scene::Vertex>() as u32,
                vertex_attributes: &VERTEX_ATTRIBUTES,
                color_formats: &[LIT_OUTPUT_FORMAT],
                depth_format: vk::Format::UNDEFINED,
                depth_compare: vk::CompareOp::ALWAYS,
                depth_write: false,
                samples: vk::SampleCountFlags::TYPE_1,
                stencil: StencilRule::Off,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                blend: true,
            },
        )?;
        Ok(Box::new(TransparentPass {
            pipeline,
            sampler: Sampler::nearest_clamp(s.ctx)?,
            exposure: s.pass.float_setting("exposure")? as f32,
        }))
    }
}
