//! The renderer: owns the scene on the GPU, the passes and the render targets, and records a
//! frame either into its own command buffer (headless) or into a host engine's.
//!
//! Until the render graph drives the frame, the sequence is fixed: G-buffer geometry pass
//! (indirect-count draws), then compute lighting into the output image.

use super::gpu_types::{DebugView, FrameConstants, GpuPointLight};
use super::output::{rgba_from_bytes, RgbaImage};
use super::scene_buffers::GpuScene;
use crate::error::{Error, Result};
use crate::gpu::barrier::{cmd_barriers, image_barrier};
use crate::gpu::transfer::record_image_to_buffer;
use crate::gpu::{
    Access, Buffer, BufferDesc, GpuContext, GpuTimer, Image, ImageDesc, MemoryLocation, ShaderCompiler, UploadBatch,
};
use crate::passes::gbuffer::{self, GbufferPass, GbufferTargets};
use crate::passes::lighting::{self, LightingInputs, LightingPass};
use crate::scene::{Camera, Scene};
use crate::stats::FrameStats;
use ash::vk;
use std::time::Instant;

/// How many frames of one renderer may execute on the GPU at once (host-visible per-frame data
/// is ringed this many times).
pub const FRAMES_IN_FLIGHT: usize = 3;

/// Output size and other per-renderer settings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Lit image or a G-buffer channel.
    pub debug_view: DebugView,
}

impl RenderSettings {
    /// The lit image at `width` x `height`.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, debug_view: DebugView::None }
    }
}

impl RenderSettings {
    fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::Invalid(format!("output size {}x{} is empty", self.width, self.height)));
        }
        Ok(())
    }
}

/// Host-visible data of one frame in flight.
struct FrameSlot {
    constants: Buffer,
    lights: Buffer,
    timer: GpuTimer,
}

/// Render targets with the access each was last used with.
struct Target {
    image: Image,
    state: Access,
}

impl Target {
    fn new(
        ctx: &GpuContext,
        name: &str,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        s: &RenderSettings,
    ) -> Result<Self> {
        let image = Image::new(
            ctx,
            &ImageDesc {
                name,
                format,
                extent: vk::Extent2D { width: s.width, height: s.height },
                mip_levels: 1,
                samples: vk::SampleCountFlags::TYPE_1,
                usage,
            },
        )?;
        Ok(Self { image, state: Access::NONE })
    }

    /// A barrier to `next` (contents discarded when `discard`), updating the tracked state.
    fn transition(&mut self, next: Access, discard: bool) -> vk::ImageMemoryBarrier2<'static> {
        let mut before = self.state;
        if discard {
            before.layout = vk::ImageLayout::UNDEFINED;
        }
        self.state = next;
        image_barrier(&self.image, before, next)
    }
}

/// Depth read by compute as a sampled image.
const DEPTH_READ: Access = Access {
    stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
    access: vk::AccessFlags2::SHADER_SAMPLED_READ,
    layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
};

/// Renders a scene: G-buffer, lighting, output.
pub struct Renderer {
    ctx: GpuContext,
    scene: Scene,
    gpu_scene: GpuScene,
    gbuffer: GbufferPass,
    lighting: LightingPass,
    albedo: Target,
    normal: Target,
    depth: Target,
    output: Target,
    slots: Vec<FrameSlot>,
    frame_index: u64,
    pending_uploads: Option<UploadBatch>,
    /// Upload batches recorded into frame N, kept until frame N + FRAMES_IN_FLIGHT is recorded.
    retiring_uploads: Vec<(u64, UploadBatch)>,
    settings: RenderSettings,
}

impl Renderer {
    /// Prepares `scene` for rendering at `settings`' size. Uploads are recorded into the first frame.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler, scene: Scene, settings: RenderSettings) -> Result<Self> {
        settings.validate()?;
        crate::scene::validate::validate_scene(&scene)?;
        let mut uploads = UploadBatch::default();
        let gpu_scene = GpuScene::upload(ctx, &scene, &mut uploads)?;
        let attachment = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let albedo = Target::new(ctx, "gbuffer albedo", gbuffer::ALBEDO_FORMAT, attachment, &settings)?;
        let normal = Target::new(ctx, "gbuffer normal", gbuffer::NORMAL_FORMAT, attachment, &settings)?;
        let depth_usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let depth = Target::new(ctx, "depth", gbuffer::DEPTH_FORMAT, depth_usage, &settings)?;
        let output_usage =
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
        let output = Target::new(ctx, "output", lighting::OUTPUT_FORMAT, output_usage, &settings)?;
        let light_bytes = (scene.lights.len().max(1) * std::mem::size_of::<GpuPointLight>()) as u64;
        let slots = (0..FRAMES_IN_FLIGHT)
            .map(|i| -> Result<FrameSlot> {
                let host = |name: &str, size| {
                    Buffer::new(
                        ctx,
                        &BufferDesc {
                            name,
                            size,
                            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                            location: MemoryLocation::CpuToGpu,
                        },
                    )
                };
                Ok(FrameSlot {
                    constants: host(&format!("frame constants {i}"), std::mem::size_of::<FrameConstants>() as u64)?,
                    lights: host(&format!("lights {i}"), light_bytes)?,
                    timer: GpuTimer::new(ctx, 16)?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            ctx: ctx.clone(),
            gbuffer: GbufferPass::new(ctx, shaders)?,
            lighting: LightingPass::new(ctx, shaders)?,
            scene,
            gpu_scene,
            albedo,
            normal,
            depth,
            output,
            slots,
            frame_index: 0,
            pending_uploads: Some(uploads),
            retiring_uploads: Vec::new(),
            settings,
        })
    }

    /// The scene being rendered.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Output size.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The lit output image (RGBA8, sRGB-encoded values) and the access it was left in
    /// (`GENERAL`, written by the compute stage) after the last recorded frame.
    pub fn output(&self) -> (&Image, Access) {
        (&self.output.image, self.output.state)
    }

    /// Records one frame into `cmd` (which must be recording) for `camera`; returns its index.
    ///
    /// This is the embedding entry point: nothing is submitted. At most [`FRAMES_IN_FLIGHT`]
    /// recorded frames may be executing at once.
    pub fn record(&mut self, cmd: vk::CommandBuffer, camera: &Camera) -> Result<u64> {
        camera.validate().map_err(|e| Error::Invalid(format!("camera: {e}")))?;
        let frame = self.frame_index;
        let slot_index = (frame % FRAMES_IN_FLIGHT as u64) as usize;
        self.write_frame_data(slot_index, camera)?;
        let device = self.ctx.device().clone();

        // Uploads recorded FRAMES_IN_FLIGHT frames ago have executed by now.
        self.retiring_uploads.retain(|(f, _)| frame < f + FRAMES_IN_FLIGHT as u64);
        if let Some(batch) = self.pending_uploads.take() {
            self.ctx.begin_label(cmd, "upload scene");
            batch.record(&self.ctx, cmd);
            self.ctx.end_label(cmd);
            self.retiring_uploads.push((frame, batch));
        }

        let slot = &mut self.slots[slot_index];
        slot.timer.reset(cmd);
        slot.timer.begin(cmd, "frame");

        // G-buffer: previous contents are not needed.
        let barriers = [
            self.albedo.transition(Access::COLOR_ATTACHMENT, true),
            self.normal.transition(Access::COLOR_ATTACHMENT, true),
            self.depth.transition(Access::DEPTH_ATTACHMENT, true),
        ];
        cmd_barriers(&device, cmd, &[], &barriers);
        self.ctx.begin_label(cmd, "gbuffer");
        slot.timer.begin(cmd, "gbuffer");
        let targets =
            GbufferTargets { albedo: &self.albedo.image, normal: &self.normal.image, depth: &self.depth.image };
        self.gbuffer.record(&self.ctx, cmd, &self.gpu_scene, &slot.constants, &targets);
        slot.timer.end(cmd);
        self.ctx.end_label(cmd);

        let sampled = Access { access: vk::AccessFlags2::SHADER_SAMPLED_READ, ..Access::COMPUTE_READ };
        let barriers = [
            self.albedo.transition(sampled, false),
            self.normal.transition(sampled, false),
            self.depth.transition(DEPTH_READ, false),
            self.output.transition(Access::COMPUTE_WRITE, true),
        ];
        cmd_barriers(&device, cmd, &[], &barriers);
        self.ctx.begin_label(cmd, "lighting");
        slot.timer.begin(cmd, "lighting");
        let inputs = LightingInputs {
            depth: &self.depth.image,
            albedo: &self.albedo.image,
            normal: &self.normal.image,
            frame: &slot.constants,
            lights: &slot.lights,
            output: &self.output.image,
        };
        self.lighting.record(cmd, &self.ctx, &inputs);
        slot.timer.end(cmd);
        self.ctx.end_label(cmd);
        slot.timer.end(cmd);

        self.frame_index += 1;
        Ok(frame)
    }

    /// GPU timings of `frame` if it has completed and its slot was not reused since.
    pub fn completed_timings(&self, frame: u64) -> Result<Vec<crate::gpu::PassTiming>> {
        // The slot of `frame` is rewritten when frame + FRAMES_IN_FLIGHT is recorded.
        if frame >= self.frame_index || self.frame_index - frame > FRAMES_IN_FLIGHT as u64 {
            return Ok(Vec::new());
        }
        Ok(self.slots[(frame % FRAMES_IN_FLIGHT as u64) as usize].timer.results()?)
    }

    /// Renders one frame headlessly (own command buffer, submit, wait) and returns its stats.
    pub fn render(&mut self, camera: &Camera) -> Result<FrameStats> {
        self.render_inner(camera, None)
    }

    /// Renders one frame headlessly and reads the output back.
    pub fn render_to_image(&mut self, camera: &Camera) -> Result<(FrameStats, RgbaImage)> {
        let (w, h) = (self.settings.width, self.settings.height);
        let readback = Buffer::new(
            &self.ctx,
            &BufferDesc {
                name: "output readback",
                size: w as u64 * h as u64 * 4,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuToCpu,
            },
        )?;
        let stats = self.render_inner(camera, Some(&readback))?;
        let image = rgba_from_bytes(w, h, readback.read_bytes()?.to_vec())?;
        Ok((stats, image))
    }

    fn render_inner(&mut self, camera: &Camera, readback: Option<&Buffer>) -> Result<FrameStats> {
        let ctx = self.ctx.clone();
        let mut frame = 0;
        let mut record_ms = 0.0;
        ctx.submit_and_wait(|cmd| {
            let start = Instant::now();
            frame = self.record(cmd, camera)?;
            record_ms = start.elapsed().as_secs_f64() * 1e3;
            if let Some(dst) = readback {
                record_image_to_buffer(&ctx, cmd, &self.output.image, self.output.state, dst);
            }
            Ok::<(), Error>(())
        })?;
        let timings = self.slots[(frame % FRAMES_IN_FLIGHT as u64) as usize].timer.results()?;
        let total = timings.iter().find(|t| t.name == "frame").map_or(0.0, |t| t.ms);
        let stats = FrameStats {
            frame,
            instances: self.gpu_scene.instance_count,
            draws: self.gpu_scene.max_draws,
            triangles: self.gpu_scene.triangles,
            gpu_ms: timings.into_iter().filter(|t| t.name != "frame").collect(),
            gpu_total_ms: total,
            cpu_record_ms: record_ms,
        };
        Ok(stats)
    }

    fn write_frame_data(&mut self, slot: usize, camera: &Camera) -> Result<()> {
        let constants = FrameConstants::new(
            &self.scene,
            camera,
            self.settings.width,
            self.settings.height,
            self.settings.debug_view,
        );
        let lights: Vec<GpuPointLight> = self.scene.lights.iter().map(|l| GpuPointLight::new(l, camera.eye)).collect();
        let slot = &mut self.slots[slot];
        slot.constants.write_bytes(0, bytemuck::bytes_of(&constants))?;
        if !lights.is_empty() {
            slot.lights.write_bytes(0, bytemuck::cast_slice(&lights))?;
        }
        Ok(())
    }
}
