//! FXAA 3.11 (the PC "quality" algorithm) in compute over the lit image (`fxaa`): the post-process
//! anti-aliasing baseline that the MSAA graphs are measured against. Reads the sRGB-encoded RGBA8
//! image through a bilinear sampler and writes the filtered one (`shaders/fxaa/fxaa.comp`).

use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::PlannedPass;
use ash::vk;

crate::choice! {
    /// FXAA 3.11's search schedules (`FXAA_QUALITY__PRESET`, setting `preset`); the first is the
    /// default (39, "extreme quality": twelve taps per direction, the first five one pixel
    /// apart).
    pub enum Preset {
        /// 39: extreme quality.
        Extreme = "39",
        /// 29.
        High = "29",
        /// 23.
        Medium = "23",
        /// 15.
        Low = "15",
        /// 12: FXAA's default.
        Default = "12",
        /// 10: the fastest.
        Fastest = "10",
    }
}
use super::slots::{slot, LIT_OUTPUT_FORMAT};
use crate::graph::{Choice, FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, SettingDecl, Stages, Usage};

/// Push constants of `fxaa.comp`: FXAA's three tunables.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FxaaSettings {
    /// Amount of subpixel aliasing removal (`fxaaQualitySubpix`, 0.75).
    pub subpix: f32,
    /// Minimum contrast relative to the local maximum luma (`fxaaQualityEdgeThreshold`, 0.166).
    pub edge_threshold: f32,
    /// Minimum absolute contrast (`fxaaQualityEdgeThresholdMin`, 0.0833).
    pub edge_threshold_min: f32,
}

impl FxaaSettings {
    /// From the pass's graph settings (`subpix`, `edge_threshold`, `edge_threshold_min`).
    pub fn from_plan(pass: &PlannedPass) -> crate::Result<Self> {
        Ok(Self {
            subpix: pass.real("subpix")? as f32,
            edge_threshold: pass.real("edge_threshold")? as f32,
            edge_threshold_min: pass.real("edge_threshold_min")? as f32,
        })
    }
}

/// The `fxaa` pass.
pub struct FxaaPass {
    pipeline: Pipeline,
    sampler: Sampler,
    settings: FxaaSettings,
}

impl FxaaPass {
    /// Compiles the shader for the pass's `preset` and creates a bilinear clamp-to-edge sampler.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler, pass: &PlannedPass) -> crate::Result<Self> {
        // Each preset's word is a define fxaa.comp knows.
        let preset = pass.choice::<Preset>("preset")?.word();
        let spirv = shaders.compile("fxaa/fxaa.comp", &[("PRESET", preset)])?;
        Ok(Self {
            pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?,
            sampler: Sampler::linear_clamp(ctx)?,
            settings: FxaaSettings::from_plan(pass)?,
        })
    }
}

impl PassNode for FxaaPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
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

/// The `fxaa` pass kind.
pub struct FxaaKind;

impl PassKind for FxaaKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "fxaa",
            doc: "FXAA 3.11 (PC quality) in compute over the lit image: luma from the sRGB-encoded value, edge search along the local edge, subpixel blend (the post-process AA baseline)",
            reads: vec![slot("input", Usage::Sampled(Stages::Compute), true, FormatRule::Exact(LIT_OUTPUT_FORMAT), "the lit image (sRGB-encoded), sampled bilinearly")],
            writes: vec![slot("output", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(LIT_OUTPUT_FORMAT), "the anti-aliased image (same size as the input)")],
            settings: vec![
                SettingDecl::choice::<Preset>("preset", "FXAA_QUALITY__PRESET: the edge search schedule (39: extreme quality, 12: FXAA's default)"),
                SettingDecl::real("subpix", 0.75, (0.0, 1.0), "amount of subpixel aliasing removal (0: off, 1: softest)"),
                SettingDecl::real("edge_threshold", 0.166, (0.0, 1.0e6), "minimum local contrast, relative to the local maximum luma, to process a pixel"),
                SettingDecl::real("edge_threshold_min", 0.0833, (0.0, 1.0e6), "minimum absolute local contrast (skips dark areas)"),
            ],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(FxaaPass::new(s.ctx, s.shaders, s.pass)?))
    }
}
