//! Shading from a visibility buffer in compute (`lighting_visibility`, seed `003`): the geometry
//! pass stored only (instance id, triangle id) per sample; this pass rebuilds each distinct
//! triangle of a pixel from the scene's pools and shades it once, like the compressed G-buffer
//! shades each distinct surface once.

use super::gbuffer::{bound_image, bound_samples, packed_id_bits, visibility_defines};
use super::lighting::LightingSettings;
use super::slots::{
    lighting_output_defines, lighting_settings, ms, slot, LIGHTING_OUTPUT_DOC, LIGHTING_OUTPUT_FORMATS,
    VISIBILITY_FORMATS,
};
use crate::gpu::{Bind, GpuContext, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::{FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, Stages, Usage};
use crate::passes::shared::shadow_variants::ShadowVariants;
use crate::passes::shared::SceneInputs;
use crate::passes::shared::ShadowMaps;
use ash::vk;

/// The `lighting_visibility` pass.
pub struct LightingVisibilityPass {
    /// The pass's name in the graph, for messages.
    name: String,
    pipeline: ShadowVariants,
    sampler: Sampler,
    settings: LightingSettings,
    /// Ids packed in one word: the scene's triangle bits are pushed after the settings.
    packed_ids: bool,
}

impl LightingVisibilityPass {
    /// Compiles the shader for the sample count of the ids bound to `pass`.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let samples = bound_samples(plan, pass, "ids").to_string();
        let format = bound_image(plan, pass, "ids").map(|(f, _)| f);
        let mut defines = vec![("SAMPLES", samples.as_str())];
        defines.extend_from_slice(visibility_defines(format));
        defines.extend_from_slice(lighting_output_defines(plan, pass));
        let mut pipeline = ShadowVariants::compute(&pass.name, shaders, "lighting/lighting_visibility.comp", &defines)?;
        // Made now: a pipeline the device refuses fails the graph's build, not its first frame.
        pipeline.pick(ctx, ShadowMaps::default(), &mut Vec::new())?;
        Ok(Self {
            name: pass.name.clone(),
            pipeline,
            sampler: Sampler::nearest_clamp(ctx)?,
            settings: LightingSettings::from_plan(pass)?,
            packed_ids: format == Some(crate::passes::slots::VISIBILITY_PACKED),
        })
    }
}

impl PassNode for LightingVisibilityPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn samples_shadow_maps(&self) -> bool {
        true
    }

    fn live_settings(&self) -> &'static [&'static str] {
        LightingSettings::LIVE
    }

    fn apply_settings(&mut self, pass: &PlannedPass) -> crate::Result<()> {
        self.settings = LightingSettings::from_plan(pass)?;
        Ok(())
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let slots = &rec.slots;
        let (depth, ids, output) =
            (slots.required_image("depth")?, slots.required_image("ids")?, slots.required_image("output")?);
        let inputs = SceneInputs::of(rec)?;
        let scene = &inputs.scene;
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let mut binds = vec![
            Bind::Sampled(0, depth.sampled_view(), self.sampler.handle(), read),
            Bind::Sampled(1, ids.sampled_view(), self.sampler.handle(), read),
            Bind::Buffer(2, inputs.constants().handle()),
            Bind::Buffer(3, inputs.lights().handle()),
            Bind::StorageImage(4, output.view()),
            Bind::Buffer(6, scene.materials.handle()),
            Bind::Buffer(7, scene.vertices.positions.handle()),
            Bind::Buffer(8, scene.indices.handle()),
            Bind::Buffer(9, scene.instance_triangles.handle()),
            Bind::Buffer(10, scene.vertices.normals.handle()),
            Bind::Buffer(11, scene.vertices.surface.handle()),
        ];
        binds.extend(scene.instance_binds(5));
        binds.extend_from_slice(scene.textures.bindings());
        let triangle_bits = if self.packed_ids { packed_id_bits(&self.name, scene)? } else { 0 };
        let push = [bytemuck::bytes_of(&self.settings), &triangle_bits.to_ne_bytes()].concat();
        let pipeline = self.pipeline.pick(rec.ctx, inputs.shadow_maps(), &mut binds)?;
        pipeline.dispatch_over(rec.cmd, &binds, &push, output.extent());
        Ok(())
    }
}

/// The `lighting_visibility` pass kind.
pub struct LightingVisibilityKind;

impl PassKind for LightingVisibilityKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "lighting_visibility",
            doc: "shades from a visibility buffer in compute (seed 003): each distinct (instance, triangle) id of a pixel's samples is rebuilt from the shared pools (barycentrics of the pixel-center ray) and shaded once, weighted by its samples",
            reads: vec![
                ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "the depth the ids were drawn with")),
                ms(slot("ids", Usage::Sampled(Stages::Compute), true, FormatRule::OneOf(VISIBILITY_FORMATS), "instance id and triangle id per sample (packed R32_UINT or R32G32_UINT)")),
            ],
            writes: vec![slot("output", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::OneOf(LIGHTING_OUTPUT_FORMATS), LIGHTING_OUTPUT_DOC)],
            settings: lighting_settings(),
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(LightingVisibilityPass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }
}
