//! Samplers.

use super::context::{DeviceShared, GpuContext};
use super::error::{GpuResult, VkResultExt};
use ash::vk;
use std::sync::Arc;

/// A sampler; destroyed on drop.
pub struct Sampler {
    shared: Arc<DeviceShared>,
    handle: vk::Sampler,
}

impl Sampler {
    /// Point sampling, clamped: what `texelFetch`-style G-buffer reads need.
    pub fn nearest_clamp(ctx: &GpuContext) -> GpuResult<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        Self::new(ctx, &info)
    }

    /// Bilinear depth comparison, clamped to the edge: a lookup returns the filtered share of
    /// the four nearest texels that the reference depth is at or in front of (reversed-Z:
    /// greater or equal), which is what a shadow map's percentage-closer filter adds up.
    pub fn depth_compare(ctx: &GpuContext) -> GpuResult<Self> {
        let info = Self::linear_clamp_info().compare_enable(true).compare_op(vk::CompareOp::GREATER_OR_EQUAL);
        Self::new(ctx, &info)
    }

    /// Bilinear filtering of mip 0, clamped to the edge.
    pub fn linear_clamp(ctx: &GpuContext) -> GpuResult<Self> {
        Self::new(ctx, &Self::linear_clamp_info())
    }

    fn linear_clamp_info() -> vk::SamplerCreateInfo<'static> {
        vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0)
    }

    /// A sampler from a full create info.
    pub fn new(ctx: &GpuContext, info: &vk::SamplerCreateInfo<'_>) -> GpuResult<Self> {
        // SAFETY: valid device and create info.
        let handle = unsafe { ctx.device().create_sampler(info, None) }.vk("vkCreateSampler")?;
        Ok(Self { shared: ctx.shared.clone(), handle })
    }

    /// The Vulkan handle.
    pub fn handle(&self) -> vk::Sampler {
        self.handle
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the sampler (caller contract).
        unsafe { self.shared.device.destroy_sampler(self.handle, None) };
    }
}
