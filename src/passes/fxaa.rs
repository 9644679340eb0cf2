//! FXAA 3.11 (the PC "quality" algorithm) in compute over the lit image (`fxaa`): the post-process
//! anti-aliasing baseline that the MSAA graphs are measured against. Reads the sRGB-encoded RGBA8
//! image through a bilinear sampler and writes the filtered one (`shaders/fxaa/fxaa.comp`).

use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::PlannedPass;
use ash::vk;

/// FXAA's search schedules (`FXAA_QUALITY__PRESET`), the `preset` words; the first
/// is the default (39, "extreme quality": twelve taps per direction, the first five one pixel
/// apart).
pub const PRESETS: &[&str] = &["39", "29", "23", "15", "12", "10"];
use super::slots::{slot, LIT_OUTPUT_FORMAT};
use crate::graph::{
    FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, SettingDecl, SettingDefault, Stages, Usage,
};

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
            subpix: pass.float_setting("subpix")? as f32,
            edge_threshold: pass.float_setting("edge_threshold")? as f32,
            edge_threshold_min: pass.float_setting("edge_threshold_min")? as f32,
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
        // Validation keeps the word to one of PRESETS, each a define fxaa.comp knows.
        let preset = pass.choice_setting("preset")?;
        let spirv = shaders.compile("fxaa/fxaa.comp", &[("PRESET", preset)])?;
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        Ok(Self {
            pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?,
            sampler: Sampler::new(ctx, &info)?,
            settings: FxaaSettings::from_plan(pass)?,
        })
    }
}

impl PassNode for FxaaPass {
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
                SettingDecl { name: "preset", default: SettingDefault::Choice(PRESETS), range: None, doc: "FXAA_QUALITY__PRESET: the edge search schedule (39: extreme quality, 12: FXAA's default)" },
                SettingDecl { name: "subpix", default: SettingDefault::Float(0.75), range: None, doc: "amount of subpixel aliasing removal (0: off, 1: softest)" },
                SettingDecl { name: "edge_threshold", default: SettingDefault::Float(0.166), range: None, doc: "minimum local contrast, relative to the local maximum luma, to process a pixel" },
                SettingDecl { name: "edge_threshold_min", default: SettingDefault::Float(0.0833), range: None, doc: "minimum absolute local contrast (skips dark areas)" },
            ],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(FxaaPass::new(s.ctx, s.shaders, s.pass)?))
    }
}
