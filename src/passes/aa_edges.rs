//! Selective AA by depth-edge detection (`aa_edges`, paper `002` §5): a compute pass over the
//! finished MSAA depth that marks the pixels whose samples mix background and surface or span
//! more than a relative depth difference. `gbuffer_compressed` reads the mask (`aa_mask`) and
//! keeps one block on the unmarked pixels, so interior triangle edges of a continuous surface
//! cost no pool blocks.

use super::gbuffer::bound_samples;
use super::slots::{ms, slot, AA_MASK_FORMAT};
use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::{
    Creates, Extent, FormatRule, MipChain, NodeSetup, PassKind, PassKindInfo, PassNode, SettingDecl, Stages, Usage,
};
use ash::vk;

/// The `aa_edges` pass.
pub struct AaEdgesPass {
    pipeline: Pipeline,
    sampler: Sampler,
    threshold: f32,
}

impl AaEdgesPass {
    /// Compiles the shader for the sample count of the depth bound to `pass`.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let samples = bound_samples(plan, pass, "depth").to_string();
        let spirv = shaders.compile("aa/aa_edges.comp", &[("SAMPLES", &samples)])?;
        let threshold = pass.real("threshold")? as f32;
        Ok(Self {
            pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?,
            sampler: Sampler::nearest_clamp(ctx)?,
            threshold,
        })
    }
}

impl PassNode for AaEdgesPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let depth = rec.slots.required_image("depth")?;
        let mask = rec.slots.required_image("mask")?;
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let binds =
            [Bind::Sampled(0, depth.sampled_view(), self.sampler.handle(), read), Bind::StorageImage(1, mask.view())];
        self.pipeline.dispatch_over(rec.cmd, &binds, bytemuck::bytes_of(&self.threshold), mask.extent());
        Ok(())
    }
}

/// The `aa_edges` pass kind.
pub struct AaEdgesKind;

impl PassKind for AaEdgesKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "aa_edges",
            doc: "selective AA by depth-edge detection: marks the pixels whose depth samples mix background and surface or differ by more than a relative threshold",
            reads: vec![ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "the finished MSAA depth"))],
            writes: vec![slot("mask", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(AA_MASK_FORMAT), "1 on depth edges, 0 elsewhere (created at the depth's size when the graph declares none)").creates(Creates::image(AA_MASK_FORMAT, Extent::Of { slot: "depth", divisor: 1 }, MipChain::One))],
            settings: vec![SettingDecl::real("threshold", 0.01, (0.0, 1.0e6), "relative view-depth difference between a pixel's samples that makes it an edge")],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(AaEdgesPass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }
}
