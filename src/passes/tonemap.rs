//! Tone mapping (`tonemap`): the lighting passes write linear HDR colour into an
//! [`HDR_FORMAT`] image, scene radiance before exposure, that an engine may export for its own
//! post-processing; this pass scales it by the exposure, applies the ACES fit and writes the
//! sRGB-encoded 8-bit image (`shaders/tonemap/tonemap.comp`, curve in
//! `shaders/common/tonemap.glsl`).

use super::slots::{slot, HDR_FORMAT, LIT_OUTPUT_FORMAT};
use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::PlannedPass;
use crate::graph::{FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, SettingDecl, Stages, Usage};
use ash::vk;

/// Push constants of `tonemap.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TonemapSettings {
    /// Scale applied to the HDR colour before the tone curve.
    pub exposure: f32,
}

/// The `tonemap` pass.
pub struct TonemapPass {
    pipeline: Pipeline,
    sampler: Sampler,
    settings: TonemapSettings,
}

impl TonemapPass {
    /// Compiles the shader and reads the pass's `exposure`.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler, pass: &PlannedPass) -> crate::Result<Self> {
        let spirv = shaders.compile("tonemap/tonemap.comp", &[])?;
        Ok(Self {
            pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?,
            sampler: Sampler::nearest_clamp(ctx)?,
            settings: TonemapSettings { exposure: pass.real("exposure")? as f32 },
        })
    }
}

impl PassNode for TonemapPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn live_settings(&self) -> &'static [&'static str] {
        &["exposure"]
    }

    fn apply_settings(&mut self, pass: &PlannedPass) -> crate::Result<()> {
        self.settings.exposure = pass.real("exposure")? as f32;
        Ok(())
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let input = rec.slots.required_image("input")?;
        let output = rec.slots.required_image("output")?;
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let binds =
            [Bind::Sampled(0, input.sampled_view(), self.sampler.handle(), read), Bind::StorageImage(1, output.view())];
        self.pipeline.dispatch_over(rec.cmd, &binds, bytemuck::bytes_of(&self.settings), output.extent());
        Ok(())
    }
}

/// The `tonemap` pass kind.
pub struct TonemapKind;

impl PassKind for TonemapKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "tonemap",
            doc: "tone mapping in compute: linear HDR colour times the exposure, ACES fit, sRGB-encoded into the 8-bit image",
            reads: vec![slot(
                "input",
                Usage::Sampled(Stages::Compute),
                true,
                FormatRule::Exact(HDR_FORMAT),
                "linear HDR colour (scene radiance before exposure), as the lighting passes write it",
            )],
            writes: vec![slot(
                "output",
                Usage::StorageImageWrite(Stages::Compute),
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "the tone-mapped, sRGB-encoded image (same size as the input)",
            )],
            settings: vec![SettingDecl::real(
                "exposure",
                0.8,
                (0.0, 1.0e6),
                "scale applied before the tone curve (give the lighting pass the same: it resolves MSAA edges with it)",
            )],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(TonemapPass::new(s.ctx, s.shaders, s.pass)?))
    }
}
