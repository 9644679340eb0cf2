//! The renderer: owns the scene on the GPU and a render graph's runtime, and records a frame
//! either into its own command buffer (headless) or into a host engine's.
//!
//! Every pass is a node of the graph (`graph/default.ron` unless told otherwise); the renderer
//! only provides what all passes share: scene buffers, per-frame constants and lights.

use super::graph_spec::GraphSpec;
use super::observer::FrameObserver;
#[cfg(feature = "images")]
use super::output::{rgba_from_bytes, RgbaImage};
use crate::error::{Error, Result};
use crate::gpu::transfer::record_image_to_buffer;
use crate::gpu::{Access, Buffer, BufferDesc, GpuContext, Image, MemoryLocation, ShaderCompiler, UploadBatch};
use crate::graph::{CompiledGraph, FrameData, GraphRuntime, Imports, FRAMES_IN_FLIGHT};
use crate::passes::shared::gpu_types::{FrameConstants, GpuPointLight};
use crate::passes::shared::{frame_inputs, GpuScene, SceneInputs};
use crate::scene::{Camera, Scene};
use crate::stats::FrameStats;
use ash::vk;
use graphs::{build_runtime, Graphs};
use std::time::Instant;

mod adapt;
mod completed;
mod graphs;
mod readback;
mod world_sync;

pub use super::drawn::DrawnInstances;
pub use readback::OutputF32;

/// Output size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
}

impl RenderSettings {
    /// `width` x `height`.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height }
    }

    fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::Invalid(format!("output size {}x{} is empty", self.width, self.height)));
        }
        Ok(())
    }
}

/// Scene uploads waiting for the next frame, and those recorded into recent frames (kept until
/// those frames have executed).
#[derive(Default)]
struct Uploads {
    pending: Option<UploadBatch>,
    recorded: Vec<(u64, UploadBatch)>,
}

/// Renders a scene through a render graph.
pub struct Renderer {
    ctx: GpuContext,
    settings: RenderSettings,
    scene: Scene,
    /// The scene on the GPU and the per-frame buffers every built-in pass reads.
    inputs: SceneInputs,
    /// Scene inputs a relayout replaced, with the frame they were last used by.
    retired_inputs: Vec<(u64, SceneInputs)>,
    uploads: Uploads,
    /// The graph being run and the ones reloads replaced.
    graphs: Graphs,
    frame_index: u64,
    /// The camera of the last recorded frame.
    previous_camera: Option<Camera>,
    /// The kinds' adaptation policies, when enabled.
    adaptations: Option<adapt::Adaptations>,
    /// What looks at each headless frame once it has completed.
    observers: Vec<Box<dyn FrameObserver>>,
    /// The world this renderer mirrors, when made from one ([`Renderer::from_world`]).
    world: Option<world_sync::WorldMirror>,
}

impl Renderer {
    /// Prepares `scene` for rendering through the default graph. Uploads are recorded into the first frame.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler, scene: Scene, settings: RenderSettings) -> Result<Self> {
        Self::with_graph(ctx, shaders, scene, settings, &GraphSpec::default_graph())
    }

    /// Prepares `scene` for rendering through the graph `spec`.
    pub fn with_graph(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        scene: Scene,
        settings: RenderSettings,
        spec: &GraphSpec,
    ) -> Result<Self> {
        profiling::scope!("cullgraph::Renderer::with_graph");
        settings.validate()?;
        crate::scene::validate::validate_scene(&scene)?;
        let inputs = frame_inputs(&spec.kinds, &scene, settings.width, settings.height)?;
        let runtime = build_runtime(ctx, shaders, &inputs, spec)?;
        let mut uploads = UploadBatch::default();
        let gpu_scene = GpuScene::upload(ctx, &scene, &mut uploads)?;
        let inputs = SceneInputs::new(ctx, gpu_scene, scene.lights.len())?;
        Ok(Self::assemble(ctx, scene, inputs, uploads, runtime, settings, spec))
    }

    /// A renderer of `scene` (as the GPU holds it) with its inputs, first uploads and runtime.
    fn assemble(
        ctx: &GpuContext,
        scene: Scene,
        inputs: SceneInputs,
        uploads: UploadBatch,
        runtime: GraphRuntime,
        settings: RenderSettings,
        spec: &GraphSpec,
    ) -> Self {
        Self {
            ctx: ctx.clone(),
            settings,
            scene,
            inputs,
            retired_inputs: Vec::new(),
            uploads: Uploads { pending: Some(uploads), recorded: Vec::new() },
            graphs: Graphs::new(spec, runtime),
            frame_index: 0,
            previous_camera: None,
            adaptations: None,
            observers: Vec::new(),
            world: None,
        }
    }

    /// Replaces the graph. On error the current graph stays in place and keeps rendering.
    pub fn reload_graph(&mut self, shaders: &ShaderCompiler, spec: &GraphSpec) -> Result<()> {
        let inputs = match &self.world {
            // Compiled for the world's layout with its room to grow, as before.
            Some(world) => world.compiled().clone(),
            None => frame_inputs(&spec.kinds, &self.scene, self.settings.width, self.settings.height)?,
        };
        let runtime = build_runtime(&self.ctx, shaders, &inputs, spec)?;
        self.graphs.reload(spec, runtime, self.frame_index)
    }

    /// Makes `runtime` the one that records from the next frame on (see [`Graphs::install`]).
    fn install_runtime(&mut self, runtime: GraphRuntime) -> Result<()> {
        self.graphs.install(runtime, self.frame_index)
    }

    /// Puts back the graph that the last [`Renderer::reload_graph`] replaced, as it was, when
    /// the new one has not recorded a frame: a graph that loads and compiles can still fail at
    /// its first frame (a pass refusing what is bound to it), and a hot reload then falls back to
    /// the last good graph without rebuilding it from files that may have changed meanwhile.
    pub fn revert_reload(&mut self) -> Result<()> {
        self.graphs.revert(self.frame_index)
    }

    /// Starts or stops timing the steps of multi-dispatch passes separately: each frame's
    /// [`FrameStats::gpu_ms`] then also holds `pass/step` entries (see
    /// [`GraphRuntime::set_step_timing`]).
    pub fn set_step_timing(&mut self, on: bool) {
        self.graphs.runtime.set_step_timing(on);
    }

    /// Attaches `observer`: from now on it looks at every frame [`Renderer::render`] waits for.
    pub fn attach(&mut self, observer: impl FrameObserver) -> Result<()> {
        if observer.needs_draw_lists() {
            self.graphs.runtime.capture_draw_lists(true)?;
        }
        self.observers.push(Box::new(observer));
        Ok(())
    }

    /// The attached observer of type `T`, if any.
    pub fn observer<T: FrameObserver>(&self) -> Option<&T> {
        self.observers.iter().find_map(|o| (&**o as &dyn std::any::Any).downcast_ref::<T>())
    }

    /// Frames recorded so far (the index the next one gets).
    pub fn frames_recorded(&self) -> u64 {
        self.frame_index
    }

    /// The scene being rendered. For a renderer of a world ([`Renderer::from_world`]): its
    /// slots, empty ones included, each with its instance's mesh, material and flags, but with
    /// the transform it had when it was last written whole: moves are applied to the GPU only.
    /// The world's current state is [`crate::scene::world::World::live_scene`].
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Output size.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The compiled graph being executed.
    pub fn plan(&self) -> &CompiledGraph {
        self.graphs.runtime.plan()
    }

    /// The graph's runtime (resources, memory, timings).
    pub fn runtime(&self) -> &GraphRuntime {
        &self.graphs.runtime
    }

    /// What each drawing pass drew in the last completed frame, in pass order (`None` unless an
    /// attached observer asked for the draw lists, [`FrameObserver::needs_draw_lists`]).
    pub fn drawn(&self) -> Result<Option<Vec<DrawnInstances>>> {
        let Some(captured) = self.graphs.runtime.captured()? else { return Ok(None) };
        Ok(Some(super::drawn::drawn(self.plan(), &self.inputs.scene, captured)))
    }

    /// This frame's constants as frame `frame` was given them ([`FrameConstants`]), once it
    /// has completed (the buffer is reused `FRAMES_IN_FLIGHT` frames later).
    pub fn frame_constants_of(&self, frame: u64) -> &Buffer {
        &self.inputs.slot(frame).constants
    }

    /// The GPU device.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The scene as the GPU holds it (buffers of instances, cull bounds, draw lists), for an
    /// engine's own passes and for checks.
    pub fn gpu_scene(&self) -> &GpuScene {
        &self.inputs.scene
    }

    /// The graph's first output image as left by the last recorded frame, and the access it was
    /// last used with. `None` before the first frame or when the first output is a buffer.
    pub fn output(&self) -> Option<(&Image, Access)> {
        self.graphs.runtime.output_image(0)
    }

    /// Records one frame into `cmd` (which must be recording) for `camera`; returns its index.
    ///
    /// This is the embedding entry point: nothing is submitted. At most [`FRAMES_IN_FLIGHT`]
    /// recorded frames may be executing at once.
    pub fn record(&mut self, cmd: vk::CommandBuffer, camera: &Camera) -> Result<u64> {
        self.record_with_imports(cmd, camera, &Imports::new())
    }

    /// Like [`Renderer::record`], with the host resources the graph imports (e.g. the engine's
    /// back buffer as the lighting output).
    pub fn record_with_imports(&mut self, cmd: vk::CommandBuffer, camera: &Camera, imports: &Imports) -> Result<u64> {
        profiling::scope!("cullgraph::Renderer::record");
        camera.validate().map_err(|e| Error::Invalid(format!("camera: {e}")))?;
        let frame = self.frame_index;
        // All or nothing: until the graph has recorded, nothing is consumed, so that a host may
        // discard this command buffer after an error and record the frame again.
        let constants = self.frame_constants(camera);
        self.write_frame_data(frame, &constants, camera)?;
        if let Some(batch) = &self.uploads.pending {
            self.ctx.begin_label(cmd, "upload scene");
            batch.record(&self.ctx, cmd);
            self.ctx.end_label(cmd);
        }
        if let Some(world) = &mut self.world {
            self.ctx.begin_label(cmd, "update scene");
            world.record_updates(&self.ctx, cmd, frame, &self.inputs.scene)?;
            self.ctx.end_label(cmd);
        }
        self.inputs.select(frame);
        let data = FrameData {
            frame,
            extent: vk::Extent2D { width: self.settings.width, height: self.settings.height },
            shared: &self.inputs,
        };
        self.graphs.runtime.record(cmd, &data, imports)?;

        // Uploads and replaced graphs recorded FRAMES_IN_FLIGHT frames ago have executed by now.
        let in_flight = FRAMES_IN_FLIGHT as u64;
        self.uploads.recorded.retain(|(f, _)| frame < f + in_flight);
        self.graphs.recorded(frame);
        self.retired_inputs.retain(|(last, _)| frame < last + in_flight);
        if let Some(world) = &mut self.world {
            world.recorded(frame);
        }
        if let Some(batch) = self.uploads.pending.take() {
            self.uploads.recorded.push((frame, batch));
        }
        self.previous_camera = Some(camera.clone());
        self.frame_index += 1;
        Ok(frame)
    }

    /// Renders one frame headlessly (own command buffer, submit, wait) and returns its stats.
    pub fn render(&mut self, camera: &Camera) -> Result<FrameStats> {
        self.render_inner(camera, None)
    }

    /// Renders one frame headlessly and reads the graph's first output back as an image.
    #[cfg(feature = "images")]
    pub fn render_to_image(&mut self, camera: &Camera) -> Result<(FrameStats, RgbaImage)> {
        let (stats, bytes) = self.render_to_rgba8(camera)?;
        Ok((stats, rgba_from_bytes(self.settings.width, self.settings.height, bytes)?))
    }

    /// Renders one frame headlessly and reads the graph's first output (an `R8G8B8A8_UNORM`
    /// image of the output size) back: tightly packed rows, top to bottom.
    pub fn render_to_rgba8(&mut self, camera: &Camera) -> Result<(FrameStats, Vec<u8>)> {
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
        Ok((stats, readback.read_bytes()?.to_vec()))
    }

    fn render_inner(&mut self, camera: &Camera, readback: Option<&Buffer>) -> Result<FrameStats> {
        let ctx = self.ctx.clone();
        let mut frame = 0;
        let mut record_ms = 0.0;
        if readback.is_some() {
            self.readback_error()?;
        }
        ctx.submit_and_wait(|cmd| {
            let start = Instant::now();
            frame = self.record(cmd, camera)?;
            record_ms = start.elapsed().as_secs_f64() * 1e3;
            if let Some(dst) = readback {
                let (image, state) =
                    self.output().ok_or_else(|| Error::Invalid("the graph's first output is not an image".into()))?;
                record_image_to_buffer(&ctx, cmd, image, state, dst);
                self.graphs.runtime.note_output_use(0, Access { layout: state.layout, ..Access::TRANSFER_READ });
            }
            Ok::<(), Error>(())
        })?;
        let mut stats = self.completed_stats(frame)?;
        stats.cpu_record_ms = record_ms;
        let mut observers = std::mem::take(&mut self.observers);
        let looked = observers.iter_mut().try_for_each(|o| o.completed(self, frame, &mut stats));
        self.observers = observers;
        looked?;
        Ok(stats)
    }

    /// Why the graph's first output cannot be read back as 8-bit RGBA of the output size, at
    /// its declaration.
    fn readback_error(&self) -> Result<()> {
        let plan = self.plan();
        super::graph_spec::shown_image_error(plan, self.settings.width, self.settings.height)?;
        let Some(&first) = plan.outputs.first() else {
            return Err(Error::Invalid("the graph has no output to read back".into()));
        };
        match plan.resources[first].kind {
            crate::graph::ResolvedKind::Image { format: vk::Format::R8G8B8A8_UNORM, .. } => Ok(()),
            _ => Err(plan.error_at(
                first,
                Error::Invalid("must be an R8G8B8A8_UNORM image to be read back as 8-bit RGBA".into()),
            )),
        }
    }

    /// This frame's constants: the camera, and last frame's for passes that test against last
    /// frame's pyramid.
    fn frame_constants(&self, camera: &Camera) -> FrameConstants {
        let previous = self.previous_camera.as_ref().unwrap_or(camera);
        FrameConstants::new(&self.scene, camera, previous, self.settings.width, self.settings.height)
    }

    fn write_frame_data(&mut self, frame: u64, constants: &FrameConstants, camera: &Camera) -> Result<()> {
        let lights: Vec<GpuPointLight> = self.scene.lights.iter().map(|l| GpuPointLight::new(l, camera.eye)).collect();
        let slot = self.inputs.slot_mut(frame);
        slot.constants.write_bytes(0, bytemuck::bytes_of(constants))?;
        if !lights.is_empty() {
            slot.lights.write_bytes(0, bytemuck::cast_slice(&lights))?;
        }
        Ok(())
    }
}

/// An engine records on its render thread: a renderer moves there whole.
const _: () = {
    const fn assert_send<T: Send>() {}
    assert_send::<Renderer>();
};
