//! Deferred lighting in compute: sun, point lights and sky ambient over the G-buffer, tone
//! mapped and written sRGB-encoded into an RGBA8 storage image.

use crate::gpu::{Bind, Buffer, GpuContext, Image, Pipeline, Sampler, ShaderCompiler};
use ash::vk;

/// Format of the lit output (values are sRGB-encoded by the shader).
pub const OUTPUT_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// What the pass reads and writes.
pub struct LightingInputs<'a> {
    /// Depth, in `SHADER_READ_ONLY_OPTIMAL`.
    pub depth: &'a Image,
    /// Albedo/metallic, in `SHADER_READ_ONLY_OPTIMAL`.
    pub albedo: &'a Image,
    /// Normal/roughness, in `SHADER_READ_ONLY_OPTIMAL`.
    pub normal: &'a Image,
    /// Frame constants.
    pub frame: &'a Buffer,
    /// Point lights.
    pub lights: &'a Buffer,
    /// Output, in `GENERAL`.
    pub output: &'a Image,
}

/// The lighting pass.
pub struct LightingPass {
    pipeline: Pipeline,
    sampler: Sampler,
}

impl LightingPass {
    /// Compiles the shader and creates the pipeline.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler) -> crate::Result<Self> {
        let spirv = shaders.compile("lighting/lighting.comp", &[])?;
        Ok(Self { pipeline: Pipeline::compute(ctx, "lighting", &spirv)?, sampler: Sampler::nearest_clamp(ctx)? })
    }

    /// Records one dispatch over the output.
    pub fn record(&self, cmd: vk::CommandBuffer, ctx: &GpuContext, io: &LightingInputs<'_>) {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let s = self.sampler.handle();
        self.pipeline.bind(cmd);
        self.pipeline.push_bindings(
            cmd,
            &[
                Bind::Sampled(0, io.depth.view(), s, read),
                Bind::Sampled(1, io.albedo.view(), s, read),
                Bind::Sampled(2, io.normal.view(), s, read),
                Bind::Buffer(3, io.frame.handle()),
                Bind::Buffer(4, io.lights.handle()),
                Bind::StorageImage(5, io.output.view()),
            ],
        );
        let e = io.output.extent();
        // SAFETY: cmd recording with this pipeline bound.
        unsafe { ctx.device().cmd_dispatch(cmd, e.width.div_ceil(8), e.height.div_ceil(8), 1) };
    }
}
