//! FXAA 3.11 (the PC "quality" algorithm) in compute over the lit image (`fxaa`): the post-process
//! anti-aliasing baseline that the MSAA graphs are measured against. Reads the sRGB-encoded RGBA8
//! image through a bilinear sampler and writes the filtered one (`shaders/fxaa/fxaa.comp`).

use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::{PassContext, PassNode};
use crate::graph::plan::{PlannedPass, SettingValue};
use ash::vk;

pub use crate::graph::kinds::FXAA_PRESETS as PRESETS;

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

impl Default for FxaaSettings {
    fn default() -> Self {
        Self { subpix: 0.75, edge_threshold: 0.166, edge_threshold_min: 0.0833 }
    }
}

impl FxaaSettings {
    /// From the pass's graph settings (`subpix`, `edge_threshold`, `edge_threshold_min`).
    pub fn from_plan(pass: &PlannedPass) -> Self {
        let d = Self::default();
        let float = |name: &str, default: f32| pass.float_setting(name, default as f64) as f32;
        Self {
            subpix: float("subpix", d.subpix),
            edge_threshold: float("edge_threshold", d.edge_threshold),
            edge_threshold_min: float("edge_threshold_min", d.edge_threshold_min),
        }
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
        let preset = match pass.settings.get("preset") {
            Some(SettingValue::Choice(c)) if PRESETS.contains(&c.as_str()) => c.clone(),
            Some(other) => {
                return Err(crate::Error::Invalid(format!(
                    "pass '{}': FXAA preset {other:?} is not one of {}",
                    pass.name,
                    PRESETS.join(", ")
                )))
            }
            None => PRESETS[0].to_string(),
        };
        let spirv = shaders.compile("fxaa/fxaa.comp", &[("PRESET", &preset)])?;
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
            settings: FxaaSettings::from_plan(pass),
        })
    }
}

impl PassNode for FxaaPass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let input = rec.slots.required_image("input")?;
        let output = rec.slots.required_image("output")?;
        self.pipeline.bind(rec.cmd);
        self.pipeline.push_bindings(
            rec.cmd,
            &[
                Bind::Sampled(
                    0,
                    input.sampled_view(),
                    self.sampler.handle(),
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                ),
                Bind::StorageImage(1, output.view()),
            ],
        );
        self.pipeline.push_constants(rec.cmd, &self.settings);
        let e = output.extent();
        // SAFETY: cmd recording with this pipeline bound.
        unsafe { rec.ctx.device().cmd_dispatch(rec.cmd, e.width.div_ceil(16), e.height.div_ceil(16), 1) };
        Ok(())
    }
}
