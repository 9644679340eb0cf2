//! One depth per pixel for an engine's post-processing (`depth_resolve`): the nearest sample of
//! each pixel of a (multisampled) depth image, which with reversed-Z is the largest value,
//! written into an R32_SFLOAT image (`shaders/depth_resolve/depth_resolve.comp`). Single-sample
//! graphs export their depth image as it is.

use super::gbuffer::bound_samples;
use super::slots::{ms, slot, RESOLVED_DEPTH_FORMAT};
use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::{FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, Stages, Usage};
use ash::vk;

/// The `depth_resolve` pass.
pub struct DepthResolvePass {
    pipeline: Pipeline,
    sampler: Sampler,
}

impl DepthResolvePass {
    /// Compiles the shader for the sample count of the depth bound to `pass`.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let samples = bound_samples(plan, pass, "depth").to_string();
        let spirv = shaders.compile("depth_resolve/depth_resolve.comp", &[("SAMPLES", samples.as_str())])?;
        Ok(Self { pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?, sampler: Sampler::nearest_clamp(ctx)? })
    }
}

impl PassNode for DepthResolvePass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let depth = rec.slots.required_image("depth")?;
        let output = rec.slots.required_image("output")?;
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let binds =
            [Bind::Sampled(0, depth.sampled_view(), self.sampler.handle(), read), Bind::StorageImage(1, output.view())];
        self.pipeline.dispatch_over(rec.cmd, &binds, &[], output.extent());
        Ok(())
    }
}

/// The `depth_resolve` pass kind.
pub struct DepthResolveKind;

impl PassKind for DepthResolveKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "depth_resolve",
            doc: "one depth per pixel in compute: the nearest sample (reversed-Z: the largest value), for an engine's post-processing",
            reads: vec![ms(slot(
                "depth",
                Usage::Sampled(Stages::Compute),
                true,
                FormatRule::Depth,
                "reversed-Z depth, any sample count",
            ))],
            writes: vec![slot(
                "output",
                Usage::StorageImageWrite(Stages::Compute),
                true,
                FormatRule::Exact(RESOLVED_DEPTH_FORMAT),
                "the nearest sample's depth per pixel (0: every sample is background)",
            )],
            settings: vec![],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(DepthResolvePass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }
}
