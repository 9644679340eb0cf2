//! The renderer: owns the scene on the GPU and a render graph's runtime, and records a frame
//! either into its own command buffer (headless) or into a host engine's.
//!
//! Every pass is a node of the graph (`graph/default.ron` unless told otherwise); the renderer
//! only provides what all passes share: scene buffers, per-frame constants and lights.

use super::graph_spec::GraphSpec;
#[cfg(feature = "images")]
use super::output::{rgba_from_bytes, RgbaImage};
use crate::error::{Error, Result};
use crate::gpu::transfer::record_image_to_buffer;
use crate::gpu::{
    Access, Buffer, BufferDesc, GpuContext, Image, MemoryLocation, PassTiming, ShaderCompiler, UploadBatch,
};
use crate::graph::{CompiledGraph, FrameData, GraphRuntime, Imports, FRAMES_IN_FLIGHT};
#[cfg(feature = "verify")]
use crate::oracle::visibility::VisibilityOracle;
use crate::passes::overlay::GpuPassTimes;
use crate::passes::shared::gpu_types::{DrawIndexedIndirect, FrameConstants, GpuPointLight};
use crate::passes::shared::{GpuScene, SceneInputs};
use crate::scene::{Camera, Scene};
use crate::stats::FrameStats;
#[cfg(feature = "verify")]
use crate::stats::VerifyStats;
use ash::vk;
#[cfg(feature = "verify")]
use std::collections::BTreeSet;
use std::time::Instant;

mod world_sync;

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

/// Renders a scene through a render graph.
pub struct Renderer {
    ctx: GpuContext,
    scene: Scene,
    /// The scene on the GPU and the per-frame buffers every built-in pass reads.
    inputs: SceneInputs,
    runtime: GraphRuntime,
    /// Renderer frame at which `runtime` recorded its first frame.
    runtime_start: u64,
    /// Runtimes replaced by a reload: (first frame, first frame of the next runtime, runtime),
    /// kept until their last frame can no longer be executing.
    retired: Vec<(u64, u64, GraphRuntime)>,
    frame_index: u64,
    pending_uploads: Option<UploadBatch>,
    /// Upload batches recorded into frame N, kept until frame N + FRAMES_IN_FLIGHT is recorded.
    retiring_uploads: Vec<(u64, UploadBatch)>,
    settings: RenderSettings,
    /// The camera of the last recorded frame.
    previous_camera: Option<Camera>,
    /// Exact-visibility oracle, when verification is on.
    #[cfg(feature = "verify")]
    oracle: Option<VisibilityOracle>,
    /// What the oracle saw in the last verified frame.
    #[cfg(feature = "verify")]
    exactly_visible: BTreeSet<u32>,
    /// The graph being run, for re-planning it with another pool size.
    spec: GraphSpec,
    /// The kinds' adaptation policies, per pass name, when enabled.
    adaptations: Option<Vec<(String, Box<dyn crate::graph::Adaptation>)>>,
    /// The spec the last reload replaced (for [`Renderer::revert_reload`]).
    replaced_spec: Option<GraphSpec>,
    /// The world this renderer mirrors, when made from one ([`Renderer::from_world`]).
    world: Option<world_sync::WorldMirror>,
    /// Scene inputs a relayout replaced, with the frame they were last used by.
    retired_inputs: Vec<(u64, SceneInputs)>,
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
        let runtime = build_runtime(ctx, shaders, &scene, &settings, spec)?;
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
            scene,
            inputs,
            runtime,
            runtime_start: 0,
            retired: Vec::new(),
            frame_index: 0,
            pending_uploads: Some(uploads),
            retiring_uploads: Vec::new(),
            settings,
            previous_camera: None,
            #[cfg(feature = "verify")]
            oracle: None,
            #[cfg(feature = "verify")]
            exactly_visible: BTreeSet::new(),
            spec: spec.clone(),
            adaptations: None,
            replaced_spec: None,
            world: None,
            retired_inputs: Vec::new(),
        }
    }

    /// Replaces the graph. On error the current graph stays in place and keeps rendering.
    pub fn reload_graph(&mut self, shaders: &ShaderCompiler, spec: &GraphSpec) -> Result<()> {
        let mut runtime = match &self.world {
            // Compiled for the world's layout with its room to grow, as before.
            Some(world) => build_runtime_for(&self.ctx, shaders, world.compiled(), spec)?,
            None => build_runtime(&self.ctx, shaders, &self.scene, &self.settings, spec)?,
        };
        runtime.set_step_timing(self.runtime.step_timing());
        self.install_runtime(runtime)?;
        self.replaced_spec = Some(std::mem::replace(&mut self.spec, spec.clone()));
        Ok(())
    }

    /// Makes `runtime` the one that records from the next frame on, with what the current one
    /// was asked for (step timing, the captures verification reads); the current one is kept
    /// until its frames can no longer be executing.
    fn install_runtime(&mut self, mut runtime: GraphRuntime) -> Result<()> {
        runtime.set_step_timing(self.runtime.step_timing());
        #[cfg(feature = "verify")]
        if self.oracle.is_some() {
            runtime.set_capture(&DRAW_LIST_SLOTS)?;
        }
        let old = std::mem::replace(&mut self.runtime, runtime);
        self.retired.push((self.runtime_start, self.frame_index, old));
        self.runtime_start = self.frame_index;
        Ok(())
    }

    /// Puts back the graph that the last [`Renderer::reload_graph`] replaced, as it was, when
    /// the new one has not recorded a frame: a graph that loads and compiles can still fail at
    /// its first frame (a pass refusing what is bound to it), and a hot reload then falls back to
    /// the last good graph without rebuilding it from files that may have changed meanwhile.
    pub fn revert_reload(&mut self) -> Result<()> {
        let recorded_none = self.runtime_start == self.frame_index;
        match (self.retired.pop(), self.replaced_spec.take()) {
            (Some((start, end, old)), Some(spec)) if recorded_none && end == self.frame_index => {
                self.runtime = old;
                self.runtime_start = start;
                self.spec = spec;
                Ok(())
            }
            (retired, spec) => {
                self.retired.extend(retired);
                self.replaced_spec = spec;
                Err(Error::Invalid(
                    "no reload to revert: nothing was reloaded, or the new graph has recorded frames".into(),
                ))
            }
        }
    }

    /// Lets the passes' kinds change the graph's settings from what the frames' counters say
    /// (for example the compressed G-buffer's pool, which grows when it overflows and shrinks
    /// when it stays mostly empty; [`crate::graph::Adaptation`]). Call [`Renderer::adapt`]
    /// with each completed frame.
    pub fn enable_adaptation(&mut self) {
        self.adaptations = Some(Vec::new());
    }

    /// Feeds a completed frame's counters to the kinds' adaptations; when they ask for new
    /// settings, compiles the graph again with them (frames in flight finish on the old one)
    /// and returns what changed.
    pub fn adapt(
        &mut self,
        shaders: &ShaderCompiler,
        stats: &FrameStats,
    ) -> Result<Vec<crate::graph::SettingOverride>> {
        let plan = self.runtime.plan();
        let Some(adaptations) = self.adaptations.as_mut() else { return Ok(Vec::new()) };
        let mut changes = Vec::new();
        for (name, entry) in &stats.counters {
            // A frame of a replaced plan names its passes as this one does.
            let Some(now) = plan.passes.iter().position(|p| p.name == *name) else { continue };
            let at = match adaptations.iter().position(|(n, _)| n == name) {
                Some(at) => at,
                None => match plan.kinds.get(&plan.passes[now].kind).and_then(|k| k.kind.adaptation()) {
                    Some(a) => {
                        adaptations.push((name.clone(), a));
                        adaptations.len() - 1
                    }
                    None => continue,
                },
            };
            changes.extend(adaptations[at].1.observe(entry, plan, now));
        }
        if !changes.is_empty() {
            let spec = self.spec.clone().with_settings(changes.clone());
            self.reload_graph(shaders, &spec)?;
        }
        Ok(changes)
    }

    /// Starts or stops timing the steps of multi-dispatch passes separately: each frame's
    /// [`FrameStats::gpu_ms`] then also holds `pass/step` entries (see
    /// [`GraphRuntime::set_step_timing`]).
    pub fn set_step_timing(&mut self, on: bool) {
        self.runtime.set_step_timing(on);
    }

    /// Checks every headless frame against exact visibility (an unculled instance-id render
    /// at the frame's sample count): [`FrameStats::verify`] then reports false negatives and
    /// false positives. Costs an extra render and readbacks per frame.
    #[cfg(feature = "verify")]
    pub fn enable_verification(&mut self, shaders: &ShaderCompiler) -> Result<()> {
        let samples = depth_samples(self.runtime.plan());
        self.oracle =
            Some(VisibilityOracle::new(&self.ctx, shaders, self.settings.width, self.settings.height, samples)?);
        self.runtime.set_capture(&DRAW_LIST_SLOTS)
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
        self.runtime.plan()
    }

    /// The graph's runtime (resources, memory, timings).
    pub fn runtime(&self) -> &GraphRuntime {
        &self.runtime
    }

    /// The instances seen by some sample of the last frame rendered with verification on (the
    /// unculled instance-id render; empty before).
    #[cfg(feature = "verify")]
    pub fn exactly_visible(&self) -> &BTreeSet<u32> {
        &self.exactly_visible
    }

    /// What each draw pass drew in the last completed frame (`None` unless verification is
    /// on), from the draw lists captured through [`GraphRuntime::set_capture`].
    pub fn drawn(&self) -> Result<Option<Vec<DrawnInstances>>> {
        let Some(captured) = self.runtime.captured()? else { return Ok(None) };
        let plan = self.runtime.plan();
        Ok(Some(
            captured
                .into_iter()
                .map(|(pass, lists)| {
                    let sorted = plan.passes.get(pass).is_some_and(|p| p.kind == crate::passes::transparent::KIND);
                    drawn_instances(&self.inputs.scene, lists, sorted)
                })
                .collect(),
        ))
    }

    /// The scene as the GPU holds it (buffers of instances, cull bounds, draw lists), for an
    /// engine's own passes and for checks.
    pub fn gpu_scene(&self) -> &GpuScene {
        &self.inputs.scene
    }

    /// The graph's first output image as left by the last recorded frame, and the access it was
    /// last used with. `None` before the first frame or when the first output is a buffer.
    pub fn output(&self) -> Option<(&Image, Access)> {
        self.runtime.output_image(0)
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
        self.write_pass_times(frame)?;
        if let Some(batch) = &self.pending_uploads {
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
        self.runtime.record(cmd, &data, imports)?;

        // Uploads and replaced graphs recorded FRAMES_IN_FLIGHT frames ago have executed by now.
        let in_flight = FRAMES_IN_FLIGHT as u64;
        self.retiring_uploads.retain(|(f, _)| frame < f + in_flight);
        self.retired.retain(|(_, end, _)| frame < end + in_flight);
        self.retired_inputs.retain(|(last, _)| frame < last + in_flight);
        if let Some(world) = &mut self.world {
            world.recorded(frame);
        }
        if let Some(batch) = self.pending_uploads.take() {
            self.retiring_uploads.push((frame, batch));
        }
        self.previous_camera = Some(camera.clone());
        self.frame_index += 1;
        Ok(frame)
    }

    /// The runtime that recorded `frame` and the frame's index within it: the current one, or a
    /// runtime a reload retired (it keeps its frames' timestamps and counters until they can no
    /// longer be executing). `None` once that runtime is gone.
    fn runtime_of(&self, frame: u64) -> Option<(&GraphRuntime, u64)> {
        if frame >= self.runtime_start {
            return Some((&self.runtime, frame - self.runtime_start));
        }
        self.retired
            .iter()
            .find(|(start, end, _)| (*start..*end).contains(&frame))
            .map(|(start, _, old)| (old, frame - start))
    }

    /// GPU timings of a recorded frame if it has completed and its timestamps were not reused.
    pub fn completed_timings(&self, frame: u64) -> Result<Vec<PassTiming>> {
        match self.runtime_of(frame) {
            Some((runtime, index)) => runtime.timings(index),
            None => Ok(Vec::new()),
        }
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
        ctx.submit_and_wait(|cmd| {
            let start = Instant::now();
            frame = self.record(cmd, camera)?;
            record_ms = start.elapsed().as_secs_f64() * 1e3;
            if let Some(dst) = readback {
                let (image, state) =
                    self.output().ok_or_else(|| Error::Invalid("the graph's first output is not an image".into()))?;
                let extent = image.extent();
                if (extent.width, extent.height) != (self.settings.width, self.settings.height)
                    || image.format() != vk::Format::R8G8B8A8_UNORM
                {
                    return Err(Error::Invalid(format!(
                        "the graph's first output '{}' must be an R8G8B8A8_UNORM image of the output size to be saved",
                        image.name()
                    )));
                }
                record_image_to_buffer(&ctx, cmd, image, state, dst);
                self.runtime.note_output_use(0, Access { layout: state.layout, ..Access::TRANSFER_READ });
            }
            Ok::<(), Error>(())
        })?;
        let mut stats = self.completed_stats(frame)?;
        stats.cpu_record_ms = record_ms;
        #[cfg(feature = "verify")]
        if self.oracle.is_some() {
            let (verify, visible) = self.verify(frame)?;
            stats.verify = Some(verify);
            self.exactly_visible = visible;
        }
        Ok(stats)
    }

    /// Compares what `frame` (just completed) drew with exact visibility; also returns the
    /// exactly visible instances.
    #[cfg(feature = "verify")]
    fn verify(&self, frame: u64) -> Result<(VerifyStats, BTreeSet<u32>)> {
        let Some(oracle) = &self.oracle else { return Ok(Default::default()) };
        let constants = &self.inputs.slot(frame).constants;
        let visible = oracle.render(&self.ctx, &self.inputs.scene, constants)?.visible;
        let lists = self.drawn()?.unwrap_or_default();
        let drawn: BTreeSet<u32> = if lists.contains(&DrawnInstances::All) {
            (0..self.inputs.scene.instance_count).collect()
        } else {
            lists
                .into_iter()
                .flat_map(|l| match l {
                    DrawnInstances::Some(ids) => ids,
                    DrawnInstances::All => Vec::new(),
                })
                .collect()
        };
        // An empty slot of a changing world (an instance just removed, still on last frame's
        // visible list) has an all-zero record: drawing it puts nothing on screen.
        let empty = |id: &u32| {
            self.scene.instances.get(*id as usize).is_some_and(|i| i.flags & crate::scene::FLAG_EMPTY_SLOT != 0)
        };
        let drawn: BTreeSet<u32> = drawn.into_iter().filter(|id| !empty(id)).collect();
        let missed: Vec<u32> = visible.difference(&drawn).copied().collect();
        let stats = VerifyStats {
            visible: visible.len() as u32,
            drawn: drawn.len() as u32,
            false_negatives: missed.len() as u32,
            false_positives: drawn.difference(&visible).count() as u32,
            missed: missed.into_iter().take(16).collect(),
        };
        Ok((stats, visible))
    }

    /// The figures of a recorded frame once it has completed on the GPU (counters and
    /// timestamps come back through per-frame host buffers, a few frames late, never waited
    /// on). Without culling passes everything is drawn.
    pub fn completed_stats(&self, frame: u64) -> Result<FrameStats> {
        let timings = self.completed_timings(frame)?;
        let total = timings.iter().find(|t| t.name == "frame").map_or(0.0, |t| t.ms);
        let entries = match self.runtime_of(frame) {
            Some((runtime, index)) => runtime.counter_entries(index)?,
            None => Vec::new(),
        };
        // A world renderer's empty slots are no instances.
        let instances = self.world.as_ref().map_or(self.inputs.scene.instance_count, |w| w.instances());
        let mut stats = FrameStats {
            frame,
            instances,
            drawn: instances,
            draws: self.inputs.scene.regions.groups(),
            triangles: self.inputs.scene.triangles,
            gpu_ms: timings.into_iter().filter(|t| t.name != "frame").collect(),
            gpu_total_ms: total,
            ..Default::default()
        };
        stats.add_counters(entries);
        stats.update = match &self.world {
            Some(world) => world.update_of(frame)?,
            None => None,
        };
        Ok(stats)
    }

    /// For a graph with an overlay pass: the newest completed frame's GPU times (of this graph),
    /// without waiting (a frame still executing has no results yet and is skipped).
    fn write_pass_times(&mut self, frame: u64) -> Result<()> {
        let plan = self.runtime.plan();
        if !plan.passes.iter().any(|p| p.kind == "overlay") {
            return Ok(());
        }
        let newest = (1..=FRAMES_IN_FLIGHT as u64)
            .filter_map(|back| frame.checked_sub(back))
            .filter(|&f| f >= self.runtime_start)
            .find_map(|f| match self.runtime.timings(f - self.runtime_start) {
                Ok(t) if !t.is_empty() => Some((f, t)),
                _ => None,
            });
        let times = match newest {
            Some((f, timings)) => GpuPassTimes::from_timings(plan, f, &timings),
            None => GpuPassTimes::none(),
        };
        self.inputs.slot_mut(frame).pass_times.write_bytes(0, bytemuck::bytes_of(&times))?;
        Ok(())
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

/// The slots through which a draw pass reads its draw list; `--verify` copies them to the host.
#[cfg(feature = "verify")]
const DRAW_LIST_SLOTS: [&str; 3] = ["draw_commands", "draw_count", "draw_instance_ids"];

/// What one draw pass drew.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DrawnInstances {
    /// The scene's unculled list: every instance.
    All,
    /// These instance ids (in draw order).
    Some(Vec<u32>),
}

/// The instances a draw pass's captured list (commands, counts, ids) drew; `None`: the pass
/// binds no list and draws the scene's unculled one. A geometry pass draws its list's opaque
/// regions; the `transparent` pass (`sorted`) draws the first `count` commands of its list.
fn drawn_instances(scene: &GpuScene, lists: Option<Vec<Vec<u8>>>, sorted: bool) -> DrawnInstances {
    let Some([commands, counts, ids]) = lists.and_then(|l| <[Vec<u8>; 3]>::try_from(l).ok()) else {
        return DrawnInstances::All;
    };
    // Whole elements only: a graph may size a buffer to any number of bytes.
    let commands: Vec<DrawIndexedIndirect> = whole(&commands);
    let counts: Vec<u32> = whole(&counts);
    let ids: Vec<u32> = whole(&ids);
    let mut out = Vec::new();
    let drawn: Box<dyn Iterator<Item = &DrawIndexedIndirect>> = if sorted {
        Box::new(commands.iter().take(counts.first().copied().unwrap_or(0) as usize))
    } else {
        Box::new(scene.regions.drawn(&commands, &counts))
    };
    for c in drawn {
        let start = c.first_instance as usize;
        let end = (start + c.instance_count as usize).min(ids.len());
        out.extend_from_slice(&ids[start.min(end)..end]);
    }
    DrawnInstances::Some(out)
}

/// The whole `T`s at the start of `bytes` (a trailing partial one is left out).
fn whole<T: bytemuck::Pod>(bytes: &[u8]) -> Vec<T> {
    bytes.chunks_exact(std::mem::size_of::<T>()).map(bytemuck::pod_read_unaligned).collect()
}

#[cfg(feature = "verify")]
/// Samples of the graph's first depth image (what the oracle must match); 1 if none.
fn depth_samples(plan: &CompiledGraph) -> vk::SampleCountFlags {
    plan.resources
        .iter()
        .find_map(|r| match r.kind {
            crate::graph::ResolvedKind::Image { format, samples, .. } if crate::graph::formats::is_depth(format) => {
                Some(samples)
            }
            _ => None,
        })
        .unwrap_or(vk::SampleCountFlags::TYPE_1)
}

/// Loads, validates and compiles `spec` for this scene and size, and instantiates it.
fn build_runtime(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Scene,
    settings: &RenderSettings,
    spec: &GraphSpec,
) -> Result<GraphRuntime> {
    profiling::scope!("cullgraph::build_graph");
    let plan = spec.compile(ctx, shaders, scene, settings.width, settings.height)?;
    GraphRuntime::new(ctx, shaders, plan, spec.dir.as_deref())
}

/// Compiles `spec` for `inputs` and instantiates it.
fn build_runtime_for(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    inputs: &crate::graph::FrameInputs,
    spec: &GraphSpec,
) -> Result<GraphRuntime> {
    profiling::scope!("cullgraph::build_graph");
    let plan = spec.compile_for(ctx, shaders, inputs)?;
    GraphRuntime::new(ctx, shaders, plan, spec.dir.as_deref())
}

/// An engine records on its render thread: a renderer moves there whole.
const _: () = {
    const fn assert_send<T: Send>() {}
    assert_send::<Renderer>();
};
