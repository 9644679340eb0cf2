//! `transparent`: draws the sorted transparent (alphaMode BLEND) instances of
//! `transparent_sort` over the lit image, back to front, forward-shaded and blended
//! (`shaders/transparent/transparent.frag`).
//!
//! The pass draws into the lighting's single-sample output and tests depth in its fragment
//! shader against every sample of the opaque depth: a fragment's alpha is scaled by the share of
//! samples it is in front of, so with any MSAA method an opaque edge crossing a transparent
//! surface is resolved as the lighting resolved the opaque image. Transparent surfaces write no
//! depth, so they hide nothing, from each other or from the culling.

use super::gbuffer::{bound_samples, DrawSource};
use super::slots::{draw_list_slots, ms, slot, LIT_OUTPUT_FORMAT};
use crate::gpu::{Bind, Pipeline, Sampler};
use crate::graph::executor::PassContext;
use crate::graph::{
    DrawList, DrawOrder, FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, Quantity, SettingDecl, SlotDecl,
    Stages, Usage,
};
use crate::passes::gbuffer::LIST_SLOTS;
use crate::passes::shared::face_cull::FaceCull;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::transparent_draw::{
    record_transparent, transparent_pipeline, TransparentDraws, TransparentShading,
};
use crate::passes::shared::SceneInputs;
use crate::passes::transparent_sort::{BLENDED, SORTED_COMMANDS_BYTES, SORTED_IDS_BYTES};
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
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn samples_shadow_maps(&self) -> bool {
        true
    }

    fn live_settings(&self) -> &'static [&'static str] {
        &["exposure"]
    }

    fn apply_settings(&mut self, pass: &crate::graph::plan::PlannedPass) -> crate::Result<()> {
        self.exposure = pass.real("exposure")? as f32;
        Ok(())
    }

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
            clusters: None,
            masked_clusters: None,
        };
        let depth = slots.required_image("depth")?;
        let output = slots.required_image("output")?;
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(output.view())
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let mut binds = vec![
            Bind::Buffer(1, list.instance_ids.handle()),
            Bind::Buffer(2, inputs.constants().handle()),
            Bind::Buffer(3, scene.materials.handle()),
            Bind::Buffer(4, inputs.lights().handle()),
            Bind::Sampled(5, depth.sampled_view(), self.sampler.handle(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
        ];
        binds.extend(scene.instance_binds(0));
        binds.extend(inputs.shadow_maps().binds());
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

    fn draw_list(&self) -> Option<DrawList> {
        Some(DrawList { slots: LIST_SLOTS, order: DrawOrder::Sorted, cluster_slots: &[] })
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
