//! Records a compiled graph: creates its resources and passes once, then per frame emits each
//! pass's planned barriers (filling first-use sources from what last touched the memory),
//! a debug label and a timestamp pair, and the pass's commands.

mod capture;
mod imports;
mod node;
pub(crate) mod replay;
mod resources;
mod tracker;

pub use capture::Captured;
pub use imports::{Import, Imports};
pub use node::{CompletedTimings, FrameData, PassContext, PassNode, SlotBindings, StepTimer};
pub use resources::{Physical, RuntimeResources};

/// Device bytes of one resource of a graph (both copies of a history resource).
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ResourceBytes {
    /// Resource name in the graph.
    pub name: String,
    /// Bytes (both copies of a history resource).
    pub bytes: u64,
}

use crate::gpu::barrier::{cmd_barriers, image_barrier, memory_barrier};
use crate::gpu::{Access, Buffer, BufferDesc, GpuContext, GpuTimer, Image, MemoryLocation, PassTiming, ShaderCompiler};
use crate::graph::kinds::{CounterEntry, Counters, NodeSetup};
use crate::graph::plan::{CompiledGraph, MemoryPlan, ResourceClass, ResourceId, Version};
use ash::vk;
use std::cell::RefCell;
use std::path::Path;
use tracker::Tracker;

/// Counters copied to the host every frame: whose they are and where they come from.
struct CounterSource {
    /// The pass whose binding is copied (after it has run).
    pass: usize,
    /// That binding, with the version whose contents are this frame's figures.
    binding: crate::graph::plan::Binding,
    /// The name reported with them.
    label: String,
    /// Where they go in the readback buffer, and how many bytes.
    offset: u64,
    bytes: u64,
}

/// The counters a frame reports, in pass order: each slot a kind declares as counters
/// ([`crate::graph::Counters`]). A list a pass writes for the next frame is reported as that
/// frame drew it (the `.prev` copy), under the name of the pass that draws it and placed at that
/// pass.
fn counter_sources(plan: &CompiledGraph) -> Vec<CounterSource> {
    let mut sources: Vec<(usize, CounterSource)> = Vec::new();
    for (index, pass) in plan.passes.iter().enumerate() {
        let Some(kind) = plan.kinds.info(&pass.kind) else { continue };
        for b in &pass.bindings {
            let Some(counters) = kind.slot(&b.slot).and_then(|s| s.counters) else { continue };
            let bytes = match plan.resources[b.resource].kind {
                crate::graph::plan::ResolvedKind::Buffer { size, .. } => size,
                _ => continue,
            };
            let (at, binding, label) = match counters {
                Counters::ThisFrame => (index, b.clone(), pass.name.clone()),
                Counters::NextFramesList { count_slot } => {
                    let count = pass.bindings.iter().find(|c| c.slot == count_slot);
                    let drawer = plan.passes.iter().position(|p| {
                        p.bindings
                            .iter()
                            .any(|d| Some(d.resource) == count.map(|c| c.resource) && d.version == Version::Previous)
                    });
                    let label = drawer
                        .map_or_else(|| format!("{} (last frame's list)", pass.name), |d| plan.passes[d].name.clone());
                    let binding = crate::graph::plan::Binding { version: Version::Previous, ..b.clone() };
                    (drawer.unwrap_or(index), binding, label)
                }
            };
            sources.push((at, CounterSource { pass: index, binding, label, offset: 0, bytes }));
        }
    }
    sources.sort_by_key(|(at, _)| *at);
    let mut offset = 0;
    sources
        .into_iter()
        .map(|(_, mut s)| {
            s.offset = offset;
            offset += s.bytes.next_multiple_of(16);
            s
        })
        .collect()
}

/// The counters one pass wrote in a frame, as read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct PassCounters {
    /// The name they are reported under (the pass, or the pass that drew a list).
    pub label: String,
    /// The kind of the pass that wrote them.
    pub kind: String,
    /// The slot they were bound to.
    pub slot: String,
    /// Their bytes.
    pub bytes: Vec<u8>,
}

/// Copies the buffer bound by `binding` in `frame` (at most `max_bytes` of it) into the host
/// buffer `dst` at `offset`, after
/// whatever last touched it, and records the read so later writes wait for the copy. The caller
/// makes the copy visible to the host (one barrier for all copies of a frame).
#[allow(clippy::too_many_arguments)]
pub(crate) fn copy_to_host(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    resources: &RuntimeResources,
    tracker: &mut Tracker,
    frame: u64,
    binding: &crate::graph::plan::Binding,
    dst: &Buffer,
    offset: u64,
    max_bytes: u64,
    wait: bool,
) {
    let Some(phys) = resources.index(binding.resource, binding.version, frame) else { return };
    let Physical::Buffer(src) = resources.get(phys) else { return };
    let device = ctx.device();
    if wait {
        cmd_barriers(device, cmd, &[memory_barrier(tracker.pending(&[phys]), Access::TRANSFER_READ)], &[]);
    }
    let size = src.size().min(max_bytes).min(dst.size().saturating_sub(offset));
    if size > 0 {
        let region = vk::BufferCopy { src_offset: 0, dst_offset: offset, size };
        // SAFETY: both buffers live and large enough; cmd recording.
        unsafe { device.cmd_copy_buffer(cmd, src.handle(), dst.handle(), &[region]) };
    }
    tracker.apply(phys, Access::TRANSFER_READ, false);
}

/// One global memory barrier with every stage and access of `barriers` (none if empty).
fn merge_memory_barriers(
    barriers: impl IntoIterator<Item = vk::MemoryBarrier2<'static>>,
) -> Vec<vk::MemoryBarrier2<'static>> {
    barriers
        .into_iter()
        .reduce(|a, b| {
            a.src_stage_mask(a.src_stage_mask | b.src_stage_mask)
                .src_access_mask(a.src_access_mask | b.src_access_mask)
                .dst_stage_mask(a.dst_stage_mask | b.dst_stage_mask)
                .dst_access_mask(a.dst_access_mask | b.dst_access_mask)
        })
        .into_iter()
        .collect()
}

/// Frames of one runtime that may execute at once (timestamp pools are ringed this many times).
pub const FRAMES_IN_FLIGHT: usize = 3;

/// Room per pass in the timestamp pool for the steps [`GraphRuntime::set_step_timing`] times.
pub const MAX_TIMED_STEPS: u32 = 4;

/// The most wrappers of one imported image resource kept for a host that vouches for its images
/// ([`FrameData::import_key`]): as many as frames are kept for replay, so that a host rotating
/// through that many images (a swapchain's) replays every one.
const KEPT_IMPORTS: usize = replay::SLOTS;

/// A frame of one runtime being recorded pass by pass ([`GraphRuntime::begin_frame`]).
pub struct FrameRecording {
    /// What the executor knew of each resource before the frame, restored if it is abandoned.
    before: Tracker,
    /// The newest completed frame's times, for kinds that read them.
    completed: Option<CompletedTimings>,
}

/// Stands in for a node while another records on its behalf.
struct Placeholder;

impl PassNode for Placeholder {
    fn record(&mut self, _: &PassContext<'_>) -> crate::Result<()> {
        Err(crate::Error::Invalid("a pass node was recorded while another recorded for it".into()))
    }
}

/// A compiled graph with its resources and pass instances, ready to record frames.
pub struct GraphRuntime {
    ctx: GpuContext,
    plan: CompiledGraph,
    nodes: Vec<Box<dyn PassNode>>,
    resources: RuntimeResources,
    tracker: Tracker,
    timers: Vec<RefCell<GpuTimer>>,
    /// Whether passes time their steps separately.
    step_timing: bool,
    /// Whether a pass reads the newest completed frame's times.
    reads_timings: bool,
    /// Whether a pass reads the previous frame's instance records (asked of every frame).
    reads_previous_instances: bool,
    /// Bindings of counters slots, and per frame in flight a host buffer they are copied into
    /// (read a few frames later, never waited on).
    counter_sources: Vec<CounterSource>,
    counter_ring: Vec<Buffer>,
    /// Host copies of named slots, when a checking tool asked for them.
    capture: Option<capture::SlotCapture>,
    /// The wrappers of host resources used by earlier frames, with the frame: kept until that
    /// frame has executed, because the views made for their mips and aspects go with them.
    retired_imports: Vec<(u64, Physical)>,
    frame: u64,
    /// Clear the history resources at the start of the next frame, as before the first.
    history_reset: bool,
    /// History buffers to start from instead of cleared ones ([`Self::inherit_history`]): per
    /// history resource, a buffer of the runtime this one replaces and the bytes to take.
    inherited: Vec<(ResourceId, vk::Buffer, u64)>,
    /// Frames recorded for replay ([`replay`]), made at the first frame that may be replayed.
    replays: Option<replay::Replays<replay::Recorded>>,
    /// Counts the settings taken live ([`Self::update_settings`]): part of the replay key.
    settings_taken: u64,
    /// Frames that replayed a recording.
    replayed: u64,
    /// Whether frames may replay ([`Self::set_replay`]).
    replay_on: bool,
    /// Wrappers of imported images the host vouched for ([`FrameData::import_key`]), kept from
    /// frame to frame while it vouches, so that a replayed frame's commands name views that
    /// still exist: (physical resource, image, key, wrapper), the most recently given last. A
    /// host may rotate through several images (a swapchain's), so each resource keeps up to
    /// [`KEPT_IMPORTS`] of them.
    kept_imports: Vec<(usize, crate::gpu::HostImage, u64, Physical)>,
    /// The host's key of the frame being recorded, and the images it imports (kept at its end).
    frame_key: Option<u64>,
    frame_images: Vec<(usize, crate::gpu::HostImage)>,
    /// Counts the kept wrappers made and retired: part of the replay key, so that no frame
    /// replays commands that name the views of a wrapper made or retired since (a host giving
    /// several images under one key, or a frame that failed halfway through binding them).
    wrappers_changed: u64,
    /// Distinguishes this runtime from every other made in the process: a host keeping frames
    /// of several runtimes ([`GraphRuntime::recorded_frame`]) never replays one that named a
    /// replaced runtime's resources.
    id: u64,
}

impl GraphRuntime {
    /// Instantiates every pass of `plan` and allocates its resources. User shaders of compute
    /// passes resolve against `graph_dir` (the RON file's folder).
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        plan: CompiledGraph,
        graph_dir: Option<&Path>,
    ) -> crate::Result<Self> {
        let resources = RuntimeResources::new(ctx, &plan)?;
        let nodes = plan
            .passes
            .iter()
            .map(|pass| {
                let kind = plan.kinds.get(&pass.kind).ok_or_else(|| {
                    crate::Error::Invalid(format!("pass '{}': no pass kind '{}' is registered", pass.name, pass.kind))
                })?;
                kind.kind.create_node(&NodeSetup { ctx, shaders, pass, plan: &plan, graph_dir })
            })
            .collect::<crate::Result<Vec<_>>>()?;
        // The frame, each pass, and room for each pass's steps when step timing is on.
        let scopes = plan.passes.len() as u32 * (1 + MAX_TIMED_STEPS) + 1;
        let timers = (0..FRAMES_IN_FLIGHT)
            .map(|_| GpuTimer::new(ctx, scopes).map(RefCell::new))
            .collect::<Result<Vec<_>, _>>()?;
        let counter_sources = counter_sources(&plan);
        let reads_timings = plan.passes.iter().any(|p| plan.kinds.get(&p.kind).is_some_and(|k| k.kind.reads_timings()));
        let reads_previous_instances = nodes.iter().any(|node| node.reads_previous_instances());
        let ring_bytes = counter_sources.last().map_or(16, |s| s.offset + s.bytes.next_multiple_of(16));
        let counter_ring = (0..FRAMES_IN_FLIGHT)
            .map(|i| {
                Buffer::new(
                    ctx,
                    &BufferDesc {
                        name: &format!("pass counters readback {i}"),
                        size: ring_bytes,
                        usage: vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuToCpu,
                    },
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            ctx: ctx.clone(),
            tracker: Tracker::new(resources.len()),
            plan,
            nodes,
            resources,
            timers,
            step_timing: false,
            reads_timings,
            reads_previous_instances,
            counter_sources,
            counter_ring,
            capture: None,
            retired_imports: Vec::new(),
            frame: 0,
            history_reset: false,
            inherited: Vec::new(),
            replays: None,
            settings_taken: 0,
            replayed: 0,
            replay_on: true,
            kept_imports: Vec::new(),
            frame_key: None,
            frame_images: Vec::new(),
            wrappers_changed: 0,
            id: {
                static MADE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
                MADE.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            },
        })
    }

    /// Takes `plan`, the same graph compiled again with other params, without making anything
    /// again, when it differs from the running plan only in settings that the passes' nodes take
    /// live ([`PassNode::live_settings`]): exposure, say. Returns whether it did; `false` leaves
    /// everything as it was (the graph must then be rebuilt for `plan`).
    pub fn update_settings(&mut self, plan: CompiledGraph) -> crate::Result<bool> {
        let without_settings = |p: &CompiledGraph| {
            let mut p = p.clone();
            for pass in &mut p.passes {
                pass.settings.clear();
            }
            p
        };
        if without_settings(&self.plan) != without_settings(&plan) {
            return Ok(false);
        }
        let mut changed = Vec::new();
        for (index, (old, new)) in self.plan.passes.iter().zip(&plan.passes).enumerate() {
            let live = self.nodes[index].live_settings();
            let names: std::collections::BTreeSet<&String> = new.settings.keys().chain(old.settings.keys()).collect();
            let differ: Vec<&String> =
                names.into_iter().filter(|n| old.settings.get(*n) != new.settings.get(*n)).collect();
            if differ.iter().any(|n| !live.contains(&n.as_str())) {
                return Ok(false);
            }
            if !differ.is_empty() {
                changed.push(index);
            }
        }
        self.settings_taken += 1;
        for index in changed {
            self.nodes[index].apply_settings(&plan.passes[index])?;
        }
        self.plan = plan;
        Ok(true)
    }

    /// The plan being executed.
    pub fn plan(&self) -> &CompiledGraph {
        &self.plan
    }

    /// Transient memory as placed with the device's real requirements.
    pub fn memory(&self) -> &MemoryPlan {
        self.resources.memory()
    }

    /// Device bytes of every resource the graph allocated (both copies of history resources),
    /// in declaration order; aliasing is not subtracted.
    pub fn resource_bytes(&self) -> Vec<ResourceBytes> {
        self.plan
            .resources
            .iter()
            .zip(self.resources.bytes_per_resource(&self.ctx))
            .filter(|(_, bytes)| *bytes > 0)
            .map(|(r, bytes)| ResourceBytes { name: r.name.clone(), bytes })
            .collect()
    }

    /// Records one frame into `cmd`; returns the frame number. `imports` must hold every
    /// resource the graph declares `Imported(..)` (and a kept pass uses); they are left in the
    /// access each import asks for.
    ///
    /// All or nothing: on an error nothing is consumed (the frame number, what the executor
    /// knows of each resource's state), so the host may discard `cmd` and record again.
    ///
    /// A frame whose commands would be those of the frame recorded in its slot of frames in
    /// flight is not recorded again: that recording is executed in `cmd` (`replay`).
    pub fn record(&mut self, cmd: vk::CommandBuffer, inputs: &FrameData<'_>, imports: &Imports) -> crate::Result<u64> {
        profiling::scope!("cullgraph::record_graph", self.plan.name.as_str());
        let Some(key) = self.replay_key(inputs, imports) else { return self.record_commands(cmd, inputs, imports) };
        let slot = self.replay_slot();
        let mut replays = match self.replays.take() {
            Some(replays) => replays,
            None => replay::Replays::new(&self.ctx)?,
        };
        if let Some(recorded) = replays.get(slot).filter(|r| r.key == key) {
            replays.execute(cmd, slot);
            let frame = self.replayed_frame(&recorded.frame);
            self.replays = Some(replays);
            return Ok(frame);
        }
        let recorded = replays.begin(slot).and_then(|secondary| {
            let frame = self.record_commands(secondary, inputs, imports);
            let recorded = frame.is_ok().then(|| replay::Recorded { key, frame: self.recorded_frame() });
            let ended = replays.end(slot, recorded);
            let frame = frame?;
            ended?;
            Ok(frame)
        });
        if recorded.is_ok() {
            replays.execute(cmd, slot);
        }
        self.replays = Some(replays);
        recorded
    }

    /// What distinguishes this runtime from every other made in the process.
    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    /// Which of [`replay::SLOTS`] recordings the next frame's commands would be kept as.
    pub(crate) fn replay_slot(&self) -> usize {
        (self.frame % replay::SLOTS as u64) as usize
    }

    /// What the frame just recorded left behind, for a host that keeps its commands to replay
    /// them ([`GraphRuntime::replayed_frame`]).
    pub(crate) fn recorded_frame(&self) -> replay::RecordedFrame {
        let timer = (self.frame.wrapping_sub(1) % FRAMES_IN_FLIGHT as u64) as usize;
        replay::RecordedFrame { after: self.tracker.clone(), scopes: self.timers[timer].borrow().scopes().to_vec() }
    }

    /// Takes the next frame as executed by replaying the commands `recorded` was left by (the
    /// caller executes them); returns its number.
    pub(crate) fn replayed_frame(&mut self, recorded: &replay::RecordedFrame) -> u64 {
        let timer = (self.frame % FRAMES_IN_FLIGHT as u64) as usize;
        self.tracker = recorded.after.clone();
        self.timers[timer].borrow_mut().replayed(&recorded.scopes);
        self.replayed += 1;
        let frame = self.frame;
        self.frame += 1;
        frame
    }

    /// How many of the frames recorded so far replayed an earlier frame's recording instead
    /// of recording their passes ([`GraphRuntime::record`]).
    pub fn frames_replayed(&self) -> u64 {
        self.replayed
    }

    /// Lets frames replay earlier recordings (on, the default) or has every frame record
    /// every pass (to measure what replay saves, or to rule it out while debugging).
    pub fn set_replay(&mut self, on: bool) {
        self.replay_on = on;
    }

    /// Whether frames may replay ([`GraphRuntime::set_replay`]).
    pub fn replays(&self) -> bool {
        self.replay_on
    }

    /// What decides this frame's commands, when it may replay a recording ([`replay`]).
    pub(crate) fn replay_key(&self, inputs: &FrameData<'_>, imports: &Imports) -> Option<replay::ReplayKey> {
        let shared = inputs.replay_key.filter(|_| self.replay_on)?;
        let clears = self.frame == 0 || self.history_reset || !self.inherited.is_empty();
        // Imported images only where the host vouches for them: their wrappers are then kept
        // (`bind_imports`), and a replayed frame's commands name views that still exist.
        let fresh_images = imports.has_images() && inputs.import_key.is_none();
        if clears || fresh_images || self.capture.is_some() || self.reads_timings {
            return None;
        }
        Some(replay::ReplayKey {
            shared,
            imports: inputs.import_key,
            wrappers: self.wrappers_changed,
            extent: (inputs.extent.width, inputs.extent.height),
            settings: self.settings_taken,
            step_timing: self.step_timing,
            nodes: self.nodes.iter().map(|node| node.replay_state()).collect::<Option<_>>()?,
            before: self.tracker.clone(),
        })
    }

    /// Records one frame's commands into `cmd` ([`GraphRuntime::record`] without replay).
    fn record_commands(
        &mut self,
        cmd: vk::CommandBuffer,
        inputs: &FrameData<'_>,
        imports: &Imports,
    ) -> crate::Result<u64> {
        let recording = self.begin_frame_keyed(cmd, imports, inputs.import_key)?;
        for index in 0..self.plan.passes.len() {
            if let Err(e) = self.record_pass(&recording, cmd, index, inputs) {
                self.abandon_frame(recording);
                return Err(e);
            }
        }
        Ok(self.end_frame(recording, cmd, imports))
    }

    /// Starts recording a frame pass by pass ([`GraphRuntime::record_pass`], then
    /// [`GraphRuntime::end_frame`], or [`GraphRuntime::abandon_frame`] after an error), for a
    /// host that interleaves the passes of several runtimes (the views of one renderer) so that
    /// passes of the same kind can be recorded together ([`GraphRuntime::record_passes_together`]).
    /// [`GraphRuntime::record`] does all of it for one runtime.
    pub fn begin_frame(&mut self, cmd: vk::CommandBuffer, imports: &Imports) -> crate::Result<FrameRecording> {
        self.begin_frame_keyed(cmd, imports, None)
    }

    /// [`GraphRuntime::begin_frame`] for a frame whose host vouches for its imported images
    /// under `key` ([`FrameData::import_key`]): their wrappers are kept while it gives them again
    /// under that key, so that the frame's commands can be replayed.
    pub(crate) fn begin_frame_keyed(
        &mut self,
        cmd: vk::CommandBuffer,
        imports: &Imports,
        key: Option<u64>,
    ) -> crate::Result<FrameRecording> {
        self.frame_key = key;
        self.bind_imports(imports)?;
        let before = self.tracker.clone();
        let frame = self.frame;
        if frame == 0 || self.history_reset {
            self.clear_history(cmd);
            self.history_reset = false;
        }
        if frame == 0 {
            self.copy_inherited(cmd, frame);
        }
        let completed = if self.reads_timings { self.newest_timings(frame) } else { None };
        let mut timer = self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize].borrow_mut();
        timer.reset(cmd);
        timer.begin(cmd, "frame");
        Ok(FrameRecording { before, completed })
    }

    /// Records pass `index` of the frame `recording` began (passes in plan order).
    pub fn record_pass(
        &mut self,
        recording: &FrameRecording,
        cmd: vk::CommandBuffer,
        index: usize,
        inputs: &FrameData<'_>,
    ) -> crate::Result<()> {
        profiling::scope!("cullgraph::record_pass", self.plan.passes[index].name.as_str());
        self.open_pass(cmd, index);
        let frame = self.frame;
        let timer = &self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize];
        let pass = &self.plan.passes[index];
        let rec = PassContext {
            ctx: &self.ctx,
            cmd,
            frame: inputs,
            slots: SlotBindings { pass, resources: &self.resources, frame },
            steps: StepTimer::new(self.step_timing.then_some(timer), &pass.name),
            timings: recording.completed.as_ref(),
        };
        self.nodes[index].record(&rec)?;
        rec.steps.finish(cmd);
        self.close_pass(cmd, index);
        Ok(())
    }

    /// Whether a pass reads the previous frame's instance records
    /// ([`PassNode::reads_previous_instances`]).
    pub fn reads_previous_instances(&self) -> bool {
        self.reads_previous_instances
    }

    /// The first pass that samples the renderer's shadow maps
    /// ([`PassNode::samples_shadow_maps`]), if any.
    pub fn first_pass_sampling_shadows(&self) -> Option<usize> {
        self.nodes.iter().position(|node| node.samples_shadow_maps())
    }

    /// What decides whether pass `index` can be recorded together with passes of other
    /// runtimes ([`GraphRuntime::record_passes_together`]): its kind and its node's key
    /// ([`PassNode::together_key`]); `None` when it cannot be.
    pub fn together_key(&self, index: usize) -> Option<(String, u64)> {
        let pass = self.plan.passes.get(index)?;
        Some((pass.kind.clone(), self.nodes[index].together_key()?))
    }

    /// Records pass `index` of several runtimes' frames at once (equal
    /// [`GraphRuntime::together_key`]s): each runtime's barriers, labels and timestamps as
    /// for its own pass, the commands by the first runtime's node for all of them. Every
    /// runtime's pass scope covers the shared commands, so each reports their whole time.
    pub fn record_passes_together(
        runtimes: &mut [&mut GraphRuntime],
        recordings: &[&FrameRecording],
        cmd: vk::CommandBuffer,
        index: usize,
        inputs: &[FrameData<'_>],
    ) -> crate::Result<()> {
        // Every view's barriers in one call, then every view's scope: a barrier per view would
        // drain the queue once per view.
        let (mut memory, mut images) = (Vec::new(), Vec::new());
        for runtime in runtimes.iter_mut() {
            let (m, i) = runtime.pass_barriers(index);
            memory.extend(m);
            images.extend(i);
        }
        if let Some(lead) = runtimes.first() {
            cmd_barriers(lead.ctx.device(), cmd, &merge_memory_barriers(memory), &images);
        }
        for runtime in runtimes.iter() {
            runtime.begin_scope(cmd, index);
        }
        let mut lead_node = std::mem::replace(&mut runtimes[0].nodes[index], Box::new(Placeholder));
        let recorded = {
            let mut others: Vec<Box<dyn PassNode>> = runtimes[1..]
                .iter_mut()
                .map(|r| std::mem::replace(&mut r.nodes[index], Box::new(Placeholder)))
                .collect();
            let contexts: Vec<PassContext<'_>> = runtimes
                .iter()
                .zip(inputs)
                .zip(recordings)
                .enumerate()
                .map(|(i, ((r, inputs), recording))| {
                    let pass = &r.plan.passes[index];
                    // The lead's timer times the shared steps.
                    let timer = &r.timers[(r.frame % FRAMES_IN_FLIGHT as u64) as usize];
                    PassContext {
                        ctx: &r.ctx,
                        cmd,
                        frame: inputs,
                        slots: SlotBindings { pass, resources: &r.resources, frame: r.frame },
                        steps: StepTimer::new((i == 0 && r.step_timing).then_some(timer), &pass.name),
                        timings: recording.completed.as_ref(),
                    }
                })
                .collect();
            let mut other_refs: Vec<&mut (dyn PassNode + 'static)> = others.iter_mut().map(|n| &mut **n).collect();
            let recorded = lead_node.record_together(&contexts, &mut other_refs);
            contexts[0].steps.finish(cmd);
            drop(other_refs);
            drop(contexts);
            for (r, node) in runtimes[1..].iter_mut().zip(others) {
                r.nodes[index] = node;
            }
            recorded
        };
        runtimes[0].nodes[index] = lead_node;
        recorded?;
        // Scopes close in reverse (labels nest); then one barrier before every view's copies.
        for runtime in runtimes.iter().rev() {
            runtime.end_scope(cmd);
        }
        let mut wait = Access::NONE;
        for runtime in runtimes.iter_mut() {
            runtime.track_pass(index);
            let w = runtime.copies_wait_for(index);
            wait.stage |= w.stage;
            wait.access |= w.access;
        }
        if let (Some(lead), false) = (runtimes.first(), wait.stage.is_empty()) {
            cmd_barriers(lead.ctx.device(), cmd, &[memory_barrier(wait, Access::TRANSFER_READ)], &[]);
        }
        for runtime in runtimes.iter_mut() {
            runtime.copy_out(cmd, index, false);
        }
        Ok(())
    }

    /// Ends the frame `recording` began once every pass is recorded; returns its number.
    pub fn end_frame(&mut self, recording: FrameRecording, cmd: vk::CommandBuffer, imports: &Imports) -> u64 {
        drop(recording);
        let frame = self.frame;
        if !self.counter_sources.is_empty() {
            cmd_barriers(self.ctx.device(), cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)], &[]);
        }
        self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize].borrow_mut().end(cmd);
        self.release_imports(cmd, imports);
        self.frame += 1;
        frame
    }

    /// Forgets the frame `recording` began, after an error: nothing of it is consumed (what
    /// the executor knows of each resource's state is as before it), so the host may discard
    /// the command buffer and record again.
    pub fn abandon_frame(&mut self, recording: FrameRecording) {
        self.tracker = recording.before;
    }

    /// Pass `index`'s barriers (its planned ones, widened by what the tracker knows the executor
    /// did since), debug label and the start of its timestamp scope.
    fn open_pass(&mut self, cmd: vk::CommandBuffer, index: usize) {
        let (memory, images) = self.pass_barriers(index);
        cmd_barriers(self.ctx.device(), cmd, &memory, &images);
        self.begin_scope(cmd, index);
    }

    /// The barriers pass `index` needs before it: one global memory barrier for every buffer
    /// dependency, and its images' barriers.
    fn pass_barriers(
        &mut self,
        index: usize,
    ) -> (Vec<vk::MemoryBarrier2<'static>>, Vec<vk::ImageMemoryBarrier2<'static>>) {
        let frame = self.frame;
        let pass = &self.plan.passes[index];
        let mut memory = Vec::new();
        let mut images = Vec::new();
        for b in &pass.barriers {
            let Some(phys) = self.resources.index(b.resource, b.version, frame) else { continue };
            // The plan knows the passes; what the executor itself did to the memory since
            // (copying counters or captured lists to the host) only the tracker knows, so a
            // planned source also waits for that.
            let pending = self.tracker.pending(self.resources.alias_set(phys));
            let src = match b.src {
                Some(planned) => {
                    Access { stage: planned.stage | pending.stage, access: planned.access | pending.access, ..planned }
                }
                None => pending,
            };
            match self.resources.get(phys) {
                Physical::Image(image) => {
                    let old = if b.discard { vk::ImageLayout::UNDEFINED } else { self.tracker.state(phys).layout };
                    images.push(image_barrier(image, Access { layout: old, ..src }, b.dst));
                }
                Physical::Buffer(_) => memory.push(memory_barrier(src, b.dst)),
                Physical::Unbound => {}
            }
        }
        if let Some((src, dst)) = self.nodes[index].own_dependency() {
            memory.push(memory_barrier(src, dst));
        }
        // One global barrier carries every buffer dependency of the pass.
        (merge_memory_barriers(memory), images)
    }

    /// The start of pass `index`'s label and timestamp scope.
    fn begin_scope(&self, cmd: vk::CommandBuffer, index: usize) {
        let name = &self.plan.passes[index].name;
        self.ctx.begin_label(cmd, name);
        self.timers[(self.frame % FRAMES_IN_FLIGHT as u64) as usize].borrow_mut().begin(cmd, name);
    }

    /// The end of pass `index`'s timestamp scope and label; what it did to its resources, for
    /// the tracker; and its captured slots' and counters' copies to the host.
    fn close_pass(&mut self, cmd: vk::CommandBuffer, index: usize) {
        self.end_scope(cmd);
        self.track_pass(index);
        self.copy_out(cmd, index, true);
    }

    /// The end of the open pass's timestamp scope and label.
    fn end_scope(&self, cmd: vk::CommandBuffer) {
        self.timers[(self.frame % FRAMES_IN_FLIGHT as u64) as usize].borrow_mut().end(cmd);
        self.ctx.end_label(cmd);
    }

    /// What pass `index` did to its resources, for the tracker.
    fn track_pass(&mut self, index: usize) {
        let frame = self.frame;
        for b in &self.plan.passes[index].bindings {
            if let Some(phys) = self.resources.index(b.resource, b.version, frame) {
                self.tracker.apply(phys, b.usage.access(), b.usage.writes());
            }
        }
    }

    /// The copy sources after pass `index`: its captured slots, then its counters.
    fn copy_sources(&self, index: usize) -> impl Iterator<Item = &crate::graph::plan::Binding> + '_ {
        let pass = &self.plan.passes[index];
        let captured = self.capture.iter().flat_map(move |c| c.copies_of(index, &pass.bindings).map(|(b, _)| b));
        captured.chain(self.counter_sources.iter().filter(move |s| s.pass == index).map(|s| &s.binding))
    }

    /// What the copies after pass `index` wait for.
    fn copies_wait_for(&self, index: usize) -> Access {
        let mut wait = Access::NONE;
        for b in self.copy_sources(index) {
            if let Some(phys) = self.resources.index(b.resource, b.version, self.frame) {
                let pending = self.tracker.pending(&[phys]);
                wait.stage |= pending.stage;
                wait.access |= pending.access;
            }
        }
        wait
    }

    /// Pass `index`'s captured slots' and counters' copies to the host; `wait`: each copy waits
    /// for its source with a barrier of its own (false: the caller recorded one for them all,
    /// [`GraphRuntime::copies_wait_for`]).
    fn copy_out(&mut self, cmd: vk::CommandBuffer, index: usize, wait: bool) {
        let frame = self.frame;
        let pass = &self.plan.passes[index];
        if let Some(capture) = &self.capture {
            let copies: Vec<_> = capture.copies_of(index, &pass.bindings).collect();
            for &(binding, host) in &copies {
                copy_to_host(
                    &self.ctx,
                    cmd,
                    &self.resources,
                    &mut self.tracker,
                    frame,
                    binding,
                    host,
                    0,
                    u64::MAX,
                    wait,
                );
            }
            if !copies.is_empty() {
                cmd_barriers(self.ctx.device(), cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)], &[]);
            }
        }
        let ring = &self.counter_ring[(frame % FRAMES_IN_FLIGHT as u64) as usize];
        for source in self.counter_sources.iter().filter(|s| s.pass == index) {
            let (binding, offset, record) = (&source.binding, source.offset, source.bytes);
            copy_to_host(
                &self.ctx,
                cmd,
                &self.resources,
                &mut self.tracker,
                frame,
                binding,
                ring,
                offset,
                record,
                wait,
            );
        }
    }

    /// Checks the host's resources against the graph's declarations and binds them for this frame.
    fn bind_imports(&mut self, imports: &Imports) -> crate::Result<()> {
        use crate::graph::plan::ResolvedKind;
        // What a frame abandoned before its end bound.
        self.frame_images.clear();
        for &(id, phys) in self.resources.imported().to_vec().iter() {
            // Errors name the resource's declaration.
            let invalid = |m: String| self.plan.error_at(id, crate::Error::Invalid(m));
            let declared = &self.plan.resources[id];
            let name = &declared.name;
            let given = imports.get(name).ok_or_else(|| {
                let provided: Vec<_> = imports.names().collect();
                invalid(if provided.is_empty() {
                    "is imported, but the host provided nothing (a graph with `Imported(...)` resources runs \
                     embedded, its host handing them to `Renderer::record_with_imports`)"
                        .to_string()
                } else {
                    format!("is imported, but the host did not provide it (provided: {})", provided.join(", "))
                })
            })?;
            let (resource, current) = match (given, &declared.kind) {
                (
                    Import::Image { host, current, .. },
                    ResolvedKind::Image { format, extent, mip_levels, samples, .. },
                ) => {
                    if host.format != *format
                        || host.extent != *extent
                        || host.samples != *samples
                        || host.mip_levels < *mip_levels
                    {
                        return Err(invalid(format!(
                            "is declared {format:?} {}x{} x{} samples, {mip_levels} mips; the host gave {:?} {}x{} x{} samples, {} mips",
                            extent.width,
                            extent.height,
                            samples.as_raw(),
                            host.format,
                            host.extent.width,
                            host.extent.height,
                            host.samples.as_raw(),
                            host.mip_levels
                        )));
                    }
                    // A fresh wrapper (and views of its mips and depth aspect) every frame: a
                    // host may destroy an image and get its handles back for a new one, so
                    // views are reused across frames only where the host vouches for the image
                    // under the same key.
                    let kept = self.frame_key.and_then(|key| {
                        let at =
                            self.kept_imports.iter().position(|(p, h, k, _)| *p == phys && h == host && *k == key)?;
                        Some(self.kept_imports.remove(at).3)
                    });
                    if self.frame_key.is_some() {
                        self.frame_images.push((phys, *host));
                    }
                    let wrapper = match kept {
                        Some(wrapper) => wrapper,
                        None => {
                            self.wrappers_changed += u64::from(self.frame_key.is_some());
                            Physical::Image(Image::from_host(&self.ctx, name, host)?)
                        }
                    };
                    (wrapper, *current)
                }
                (Import::Buffer { buffer, size, current, .. }, ResolvedKind::Buffer { size: needed, .. }) => {
                    if size < needed {
                        return Err(invalid(format!("needs {needed} bytes; the host gave {size}")));
                    }
                    (Physical::Buffer(crate::gpu::Buffer::from_host(&self.ctx, name, *buffer, *size)), *current)
                }
                _ => return Err(invalid("is an image in one place and a buffer in the other".into())),
            };
            // Normally unbound; a frame whose recording failed before its end left its wrapper.
            let stale = self.resources.bind_import(phys, resource);
            if !matches!(stale, Physical::Unbound) {
                self.wrappers_changed += 1;
                self.retired_imports.push((self.frame, stale));
            }
            self.tracker.set_external(phys, current);
        }
        // Kept wrappers go, once the frames that may use them have executed, when the host no
        // longer vouches for their images (no key, or another: its images may be gone), or
        // beyond the most kept per resource (the least recently given first).
        let frame = self.frame;
        let mut kept = std::mem::take(&mut self.kept_imports);
        for at in (0..kept.len()).rev() {
            let phys = kept[at].0;
            let given_since = self.frame_images.iter().filter(|(p, _)| *p == phys).count();
            let kept_since =
                kept[at + 1..].iter().filter(|(p, .., w)| *p == phys && !matches!(w, Physical::Unbound)).count();
            if self.frame_key != Some(kept[at].2) || given_since + kept_since >= KEPT_IMPORTS {
                self.retired_imports.push((frame, std::mem::replace(&mut kept[at].3, Physical::Unbound)));
                self.wrappers_changed += 1;
            }
        }
        kept.retain(|(.., wrapper)| !matches!(wrapper, Physical::Unbound));
        self.kept_imports = kept;
        // At most FRAMES_IN_FLIGHT recorded frames execute at once (`Renderer::record`): the
        // frame FRAMES_IN_FLIGHT before this one is done with its wrappers.
        self.retired_imports.retain(|(f, _)| frame < f + FRAMES_IN_FLIGHT as u64);
        Ok(())
    }

    /// Leaves every imported resource in the access its host asked for.
    fn release_imports(&mut self, cmd: vk::CommandBuffer, imports: &Imports) {
        let mut memory = Vec::new();
        let mut images = Vec::new();
        for &(id, phys) in self.resources.imported() {
            let after = match imports.get(&self.plan.resources[id].name) {
                Some(Import::Image { after, .. } | Import::Buffer { after, .. }) => *after,
                None => continue,
            };
            let state = self.tracker.state(phys);
            let src = self.tracker.pending(&[phys]);
            match self.resources.get(phys) {
                Physical::Image(image) => {
                    images.push(image_barrier(image, Access { layout: state.layout, ..src }, after))
                }
                _ => memory.push(memory_barrier(src, after)),
            }
            self.tracker.set_external(phys, after);
        }
        cmd_barriers(self.ctx.device(), cmd, &memory, &images);
        for &(_, phys) in self.resources.imported().to_vec().iter() {
            // The host's handles are only valid for this frame; the views made for them must
            // last until the frame has executed, or for as long as the host vouches for them.
            let used = self.resources.bind_import(phys, Physical::Unbound);
            match (self.frame_key, self.frame_images.iter().find(|(p, _)| *p == phys)) {
                (Some(key), Some(&(_, host))) => self.kept_imports.push((phys, host, key, used)),
                _ => self.retired_imports.push((self.frame, used)),
            }
        }
        self.frame_images.clear();
    }

    /// Output `index` (see [`CompiledGraph::outputs`]) as left by the last recorded frame, with
    /// the access it was last used with.
    pub fn output_image(&self, index: usize) -> Option<(&Image, Access)> {
        let id = *self.plan.outputs.get(index)?;
        let frame = self.frame.checked_sub(1)?;
        let phys = self.resources.index(id, Version::Current, frame)?;
        let Physical::Image(image) = self.resources.get(phys) else { return None };
        let state = self.tracker.state(phys);
        Some((image, Access { stage: state.write.0 | state.read_stages, access: state.write.1, layout: state.layout }))
    }

    /// Output `index` if it is a buffer, as left by the last recorded frame.
    pub fn output_buffer(&self, index: usize) -> Option<&crate::gpu::Buffer> {
        let id = *self.plan.outputs.get(index)?;
        let phys = self.resources.index(id, Version::Current, self.frame.checked_sub(1)?)?;
        match self.resources.get(phys) {
            Physical::Buffer(b) => Some(b),
            _ => None,
        }
    }

    /// Records that the caller used output `index` with `access` after the frame (e.g. a copy),
    /// so the next frame's barriers wait for it.
    pub fn note_output_use(&mut self, index: usize, access: Access) {
        let (Some(&id), Some(frame)) = (self.plan.outputs.get(index), self.frame.checked_sub(1)) else { return };
        if let Some(phys) = self.resources.index(id, Version::Current, frame) {
            self.tracker.apply(phys, access, false);
        }
    }

    /// Starts or stops timing the steps (dispatches) of passes that mark them
    /// ([`PassContext::step`]) separately: [`GraphRuntime::timings`] then also holds a
    /// `pass/step` scope per step, nested in the pass's own. The timestamps between steps may
    /// cost a little time themselves.
    pub fn set_step_timing(&mut self, on: bool) {
        self.step_timing = on;
    }

    /// Whether step timing is on.
    pub fn step_timing(&self) -> bool {
        self.step_timing
    }

    /// Starts (or stops) copying the draw list of every pass whose kind declares one to the
    /// host, after the pass (a checking tool: `--verify` reads what each pass drew this way).
    /// See [`GraphRuntime::captured`].
    pub fn capture_draw_lists(&mut self, on: bool) -> crate::Result<()> {
        self.capture = if on { Some(capture::SlotCapture::new(&self.ctx, &self.plan, &self.resources)?) } else { None };
        Ok(())
    }

    /// Whether draw lists are captured.
    pub fn captures_draw_lists(&self) -> bool {
        self.capture.is_some()
    }

    /// What the capturing passes bound to the captured slots in the last recorded frame, once
    /// it has completed (`None` without [`GraphRuntime::capture_draw_lists`]): per pass, in pass order,
    /// its index and each slot's bytes (`None` where the pass leaves a slot unbound). Read
    /// before recording the next frame.
    pub fn captured(&self) -> crate::Result<Option<Vec<Captured>>> {
        self.capture.as_ref().map(|c| c.read()).transpose()
    }

    /// The counters every counters slot held in `frame`, once the frame has completed (empty if
    /// its readback slot was reused since), in pass order. A list written by last frame's pass
    /// for this frame comes under the name of the pass that drew it, with the writer's kind.
    pub(crate) fn pass_counters(&self, frame: u64) -> crate::Result<Vec<PassCounters>> {
        if frame >= self.frame || self.frame - frame > FRAMES_IN_FLIGHT as u64 {
            return Ok(Vec::new());
        }
        let bytes = self.counter_ring[(frame % FRAMES_IN_FLIGHT as u64) as usize].read_bytes()?;
        Ok(self
            .counter_sources
            .iter()
            .map(|source| {
                let (start, end) = (source.offset as usize, (source.offset + source.bytes) as usize);
                PassCounters {
                    label: source.label.clone(),
                    kind: self.plan.passes[source.pass].kind.clone(),
                    slot: source.binding.slot.clone(),
                    bytes: bytes.get(start..end).unwrap_or_default().to_vec(),
                }
            })
            .collect())
    }

    /// What the kinds make of the counters of `frame` (the counters of its passes,
    /// [`crate::graph::PassKind::decode_counters`]), once it has completed, with the name of
    /// the pass that wrote each.
    pub fn counter_entries(&self, frame: u64) -> crate::Result<Vec<(String, CounterEntry)>> {
        let counters = self.pass_counters(frame)?;
        Ok(self
            .counter_sources
            .iter()
            .zip(counters)
            .filter_map(|(source, c)| {
                let kind = self.plan.kinds.get(&c.kind)?;
                let writer = self.plan.passes[source.pass].name.clone();
                Some((writer, kind.kind.decode_counters(&c.label, &c.slot, &c.bytes)?))
            })
            .collect())
    }

    /// The times of the newest frame before `frame` that has completed, without waiting (a
    /// frame still executing has no results yet and is skipped).
    fn newest_timings(&self, frame: u64) -> Option<CompletedTimings> {
        (1..=FRAMES_IN_FLIGHT as u64).filter_map(|back| frame.checked_sub(back)).find_map(|f| match self.timings(f) {
            Ok(passes) if !passes.is_empty() => Some(CompletedTimings { frame: f, passes }),
            _ => None,
        })
    }

    /// GPU time per pass of `frame`, once it has completed (empty if its timestamps were reused).
    pub fn timings(&self, frame: u64) -> crate::Result<Vec<PassTiming>> {
        if frame >= self.frame || self.frame - frame > FRAMES_IN_FLIGHT as u64 {
            return Ok(Vec::new());
        }
        Ok(self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize].borrow().results()?)
    }

    /// Makes the next recorded frame start from cleared history, as the first frame does: what
    /// last frame left (`.prev`) no longer describes this frame's world, for example after the
    /// scene's instances were laid out anew. Culling then tests everything once.
    pub fn reset_history(&mut self) {
        self.history_reset = true;
    }

    /// Starts this runtime's first frame from the history `old` (a runtime of the same graph,
    /// compiled for smaller inputs) last wrote, instead of cleared: each history buffer of the
    /// same name gets the old one's bytes at its start, and the rest is cleared. For resources
    /// indexed by something that kept its meaning, as a changing world's slots and draw groups
    /// do when the world grows; history images are cleared as in a first frame. `old` must stay
    /// alive until this runtime's first frame has executed.
    pub fn inherit_history(&mut self, old: &GraphRuntime) {
        self.inherited.clear();
        let Some(last) = old.frame.checked_sub(1) else { return };
        for id in 0..self.plan.resources.len() {
            let r = &self.plan.resources[id];
            if r.class != ResourceClass::History {
                continue;
            }
            let Some(old_id) = old.plan.resources.iter().position(|o| o.name == r.name && o.class == r.class) else {
                continue;
            };
            if let (Some(from), Some(to)) = (old.resources.buffer(old_id, last), self.resources.buffer(id, 0)) {
                self.inherited.push((id, from.handle(), from.size().min(to.size())));
            }
        }
    }

    /// Copies the inherited history ([`Self::inherit_history`]) into the copies that `frame`
    /// reads as `.prev`, after [`Self::clear_history`] and the old runtime's last frame.
    fn copy_inherited(&mut self, cmd: vk::CommandBuffer, frame: u64) {
        if self.inherited.is_empty() {
            return;
        }
        let device = self.ctx.device();
        let any_write = Access {
            stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::MEMORY_WRITE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        let transfer = Access {
            stage: vk::PipelineStageFlags2::COPY,
            access: vk::AccessFlags2::TRANSFER_READ | vk::AccessFlags2::TRANSFER_WRITE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        cmd_barriers(device, cmd, &[memory_barrier(any_write, transfer)], &[]);
        for (id, from, bytes) in std::mem::take(&mut self.inherited) {
            let Some(phys) = self.resources.index(id, Version::Previous, frame) else { continue };
            let Physical::Buffer(to) = self.resources.get(phys) else { continue };
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes };
            // SAFETY: `from` is alive until this frame has executed (inherit_history's contract)
            // and holds `bytes`; `to` has TRANSFER_DST usage and as many; cmd recording.
            unsafe { device.cmd_copy_buffer(cmd, from, to.handle(), &[region]) };
            self.tracker.apply(phys, Access::TRANSFER_WRITE, true);
        }
    }

    /// Clears both copies of every history resource to zero (reversed-Z "far", empty bits), so
    /// the first frame's `.prev` reads see defined contents (and after [`Self::reset_history`],
    /// contents that claim nothing), after whatever last touched them.
    fn clear_history(&mut self, cmd: vk::CommandBuffer) {
        let device = self.ctx.device();
        for &phys in self.resources.history() {
            let before = Access { layout: self.tracker.state(phys).layout, ..self.tracker.pending(&[phys]) };
            match self.resources.get(phys) {
                Physical::Image(image) => {
                    cmd_barriers(device, cmd, &[], &[image_barrier(image, before, Access::TRANSFER_WRITE)]);
                    let range = image.subresource_range();
                    // SAFETY: image in TRANSFER_DST layout with TRANSFER_DST usage; cmd recording.
                    unsafe {
                        if image.aspect().contains(vk::ImageAspectFlags::DEPTH) {
                            let value = vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 };
                            device.cmd_clear_depth_stencil_image(
                                cmd,
                                image.handle(),
                                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                                &value,
                                &[range],
                            );
                        } else {
                            let value = vk::ClearColorValue { float32: [0.0; 4] };
                            device.cmd_clear_color_image(
                                cmd,
                                image.handle(),
                                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                                &value,
                                &[range],
                            );
                        }
                    }
                }
                Physical::Unbound => continue,
                Physical::Buffer(buffer) => {
                    cmd_barriers(device, cmd, &[memory_barrier(before, Access::TRANSFER_WRITE)], &[]);
                    // SAFETY: buffer with TRANSFER_DST usage; cmd recording.
                    unsafe { device.cmd_fill_buffer(cmd, buffer.handle(), 0, vk::WHOLE_SIZE, 0) };
                }
            }
            self.tracker.apply(phys, Access::TRANSFER_WRITE, true);
        }
    }
}
