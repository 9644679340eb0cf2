//! Shading from a visibility buffer in compute (`lighting_visibility`, seed `003`): the geometry
//! pass stored only (instance id, triangle id) per sample; this pass rebuilds each distinct
//! triangle of a pixel from the scene's pools and shades it once, like the compressed G-buffer
//! shades each distinct surface once.

use super::gbuffer::{bound_image, bound_samples, packed_id_bits, visibility_defines};
use super::lighting::LightingSettings;
use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::{PassContext, PassNode};
use crate::graph::plan::{CompiledGraph, PlannedPass};
use ash::vk;

/// The `lighting_visibility` pass.
pub struct LightingVisibilityPass {
    /// The pass's name in the graph, for messages.
    name: String,
    pipeline: Pipeline,
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
        let spirv = shaders.compile("lighting/lighting_visibility.comp", &defines)?;
        Ok(Self {
            name: pass.name.clone(),
            pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?,
            sampler: Sampler::nearest_clamp(ctx)?,
            settings: LightingSettings::from_plan(pass),
            packed_ids: format == Some(crate::graph::kinds::VISIBILITY_PACKED),
        })
    }
}

impl PassNode for LightingVisibilityPass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let slots = &rec.slots;
        let (depth, ids, output) =
            (slots.required_image("depth")?, slots.required_image("ids")?, slots.required_image("output")?);
        let scene = rec.frame.scene;
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        self.pipeline.bind(rec.cmd);
        self.pipeline.push_bindings(
            rec.cmd,
            &[
                Bind::Sampled(0, depth.sampled_view(), self.sampler.handle(), read),
                Bind::Sampled(1, ids.sampled_view(), self.sampler.handle(), read),
                Bind::Buffer(2, rec.frame.constants.handle()),
                Bind::Buffer(3, rec.frame.lights.handle()),
                Bind::StorageImage(4, output.view()),
                Bind::Buffer(5, scene.instances.handle()),
                Bind::Buffer(6, scene.materials.handle()),
                Bind::Buffer(7, scene.vertices.handle()),
                Bind::Buffer(8, scene.indices.handle()),
                Bind::Buffer(9, scene.instance_triangles.handle()),
            ],
        );
        let triangle_bits = if self.packed_ids { packed_id_bits(&self.name, scene)? } else { 0 };
        let push = [bytemuck::bytes_of(&self.settings), &triangle_bits.to_ne_bytes()].concat();
        self.pipeline.push_constant_bytes(rec.cmd, &push);
        let e = output.extent();
        // SAFETY: cmd recording with this pipeline bound.
        unsafe { rec.ctx.device().cmd_dispatch(rec.cmd, e.width.div_ceil(16), e.height.div_ceil(16), 1) };
        Ok(())
    }
}
