//! Any named output image read back as `f32` values: linear HDR colour, motion vectors, depth,
//! for an engine's or a tool's post-processing and for checks. Writing files is the command
//! line's job; this only returns the values.

use super::{Renderer, ViewId};
use crate::error::{Error, Result};
use crate::gpu::transfer::record_image_to_buffer;
use crate::gpu::{Access, Buffer, BufferDesc, MemoryLocation};
use crate::graph::ResolvedKind;
use ash::vk;

/// An output image's values as `f32`, rows top to bottom, `channels` values per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputF32 {
    /// The output's resource name in the graph.
    pub name: String,
    /// The image's format.
    pub format: vk::Format,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Values per pixel: 4 for RGBA, 2 for motion vectors (RG), 1 for depth.
    pub channels: u32,
    /// `width * height * channels` values (8-bit UNORM channels as 0..=1).
    pub data: Vec<f32>,
}

impl OutputF32 {
    /// The values of pixel (`x`, `y`), `channels` of them.
    pub fn pixel(&self, x: u32, y: u32) -> &[f32] {
        let c = self.channels as usize;
        let at = (y as usize * self.width as usize + x as usize) * c;
        &self.data[at..at + c]
    }
}

/// How a format's texels become `f32`s: bytes per texel and channels.
fn layout(format: vk::Format) -> Option<(u64, u32)> {
    use vk::Format as F;
    Some(match format {
        F::R16G16B16A16_SFLOAT => (8, 4),
        F::R16G16_SFLOAT => (4, 2),
        F::R16_SFLOAT => (2, 1),
        F::R32G32B32A32_SFLOAT => (16, 4),
        F::R32G32_SFLOAT => (8, 2),
        // A copy of a depth-stencil image's depth aspect packs 4 bytes per texel.
        F::R32_SFLOAT | F::D32_SFLOAT | F::D32_SFLOAT_S8_UINT => (4, 1),
        F::R8G8B8A8_UNORM | F::R8G8B8A8_SRGB => (4, 4),
        // Object ids: read as integers by `Renderer::pick`.
        F::R32_UINT => (4, 1),
        _ => return None,
    })
}

fn decode(format: vk::Format, bytes: &[u8]) -> Vec<f32> {
    use vk::Format as F;
    match format {
        F::R16G16B16A16_SFLOAT | F::R16G16_SFLOAT | F::R16_SFLOAT => {
            bytes.chunks_exact(2).map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32()).collect()
        }
        F::R8G8B8A8_UNORM | F::R8G8B8A8_SRGB => bytes.iter().map(|&b| b as f32 / 255.0).collect(),
        _ => bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
    }
}

impl Renderer {
    /// The output named `name` (one of the graph's `outputs`) as the last frame left it, read
    /// back as `f32`: RGBA16F/RGBA32F colour, RG16F/RG32F motion vectors, R32_SFLOAT or a depth
    /// format's depth, RGBA8 as 0..=1. Submits a copy and waits for it: call it after the frame
    /// was submitted (headless: after [`Renderer::render`]). Errors name the output and the graph:
    /// an unknown name (listing the outputs), a buffer, a multisampled image (resolve it first:
    /// a `depth_resolve` pass for depth) or an unsupported format; and before the first frame.
    pub fn read_output_f32(&mut self, name: &str) -> Result<OutputF32> {
        self.read_view_output_f32(ViewId::MAIN, name).map_err(super::unwrap_main)
    }

    /// [`Renderer::read_output_f32`] of `view`.
    pub fn read_view_output_f32(&mut self, view: ViewId, name: &str) -> Result<OutputF32> {
        self.read_output_of(view, name).map_err(|e| view.error(e))
    }

    /// What `view` showed at pixel (`x`, `y`) of its last frame: the instance id drawn there
    /// (the slot of a world renderer's instance, see [`Renderer::pick_handle`]), `None` for the
    /// background. The graph writes ids where its geometry passes bind an `object_id` image
    /// (R32_UINT, one sample) that it lists as an output, as `builtin:post` does; errors name
    /// the view, the output and the pixel. Submits a copy and waits for it, as
    /// [`Renderer::read_output_f32`] does.
    pub fn pick(&mut self, view: ViewId, x: u32, y: u32) -> Result<Option<u32>> {
        let (out, bytes) = self.read_output_bytes(view, "object_id").map_err(|e| view.error(e))?;
        if out.format != vk::Format::R32_UINT {
            let why = format!("output 'object_id' is {:?}; object ids are R32_UINT", out.format);
            return Err(view.error(Error::Invalid(why)));
        }
        if x >= out.width || y >= out.height {
            let why = format!("pixel ({x}, {y}) is outside the {}x{} output", out.width, out.height);
            return Err(view.error(Error::Invalid(why)));
        }
        let at = ((y * out.width + x) * 4) as usize;
        let id = u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        Ok(id.checked_sub(1))
    }

    fn read_output_of(&mut self, view: ViewId, name: &str) -> Result<OutputF32> {
        let (mut out, bytes) = self.read_output_bytes(view, name)?;
        out.data = decode(out.format, &bytes);
        Ok(out)
    }

    /// Output `name` of `view` copied back: its description (no data) and its bytes.
    fn read_output_bytes(&mut self, view: ViewId, name: &str) -> Result<(OutputF32, Vec<u8>)> {
        let ctx = self.ctx.clone();
        let state = self.view_state_mut(view)?;
        let plan = state.plan();
        let graph = plan.name.clone();
        let index = plan.outputs.iter().position(|&id| plan.resources[id].name == name).ok_or_else(|| {
            let names: Vec<&str> = plan.outputs.iter().map(|&id| plan.resources[id].name.as_str()).collect();
            Error::Invalid(format!("graph '{graph}' has no output '{name}' (its outputs: {})", names.join(", ")))
        })?;
        let id = plan.outputs[index];
        let (format, samples) = match plan.resources[id].kind {
            ResolvedKind::Image { format, samples, .. } => (format, samples),
            ResolvedKind::Buffer { .. } => {
                return Err(plan.error_at(id, Error::Invalid(format!("output '{name}' is a buffer, not an image"))))
            }
        };
        if samples != vk::SampleCountFlags::TYPE_1 {
            let why = format!("output '{name}' is multisampled: resolve it to one sample per pixel first (depth: a depth_resolve pass)");
            return Err(plan.error_at(id, Error::Invalid(why)));
        }
        let Some((texel, channels)) = layout(format) else {
            let why = format!("output '{name}' has format {format:?}, which cannot be read back as f32");
            return Err(plan.error_at(id, Error::Invalid(why)));
        };
        let (image, access) = state
            .graphs
            .runtime
            .output_image(index)
            .ok_or_else(|| Error::Invalid(format!("output '{name}' of graph '{graph}': no frame rendered yet")))?;
        let (width, height) = (image.extent().width, image.extent().height);
        let buffer = Buffer::new(
            &ctx,
            &BufferDesc {
                name: "output f32 readback",
                size: width as u64 * height as u64 * texel,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        ctx.submit_and_wait(|cmd| {
            record_image_to_buffer(&ctx, cmd, image, access, &buffer);
            Ok::<(), Error>(())
        })?;
        // The copy's barriers leave the image in `state`; the next frame also waits for the read.
        state.graphs.runtime.note_output_use(index, Access { layout: access.layout, ..Access::TRANSFER_READ });
        let bytes = buffer.read_bytes()?.to_vec();
        Ok((OutputF32 { name: name.to_string(), format, width, height, channels, data: Vec::new() }, bytes))
    }
}
