//! A renderer that mirrors a [`World`]: [`Renderer::from_world`] lays the world out in slots
//! ([`SlotLayout`]) and [`Renderer::sync`] applies the world's changes since the last sync.
//!
//! A change of instances rewrites only their slots: each changed slot's index, instance record
//! (64 bytes) and cull bound (32 bytes) go into a host-visible update list, one per frame in
//! flight, reused frame after frame and grown geometrically when a frame needs more. At the
//! start of the next recorded frame one compute dispatch (`shaders/world/scatter.comp`) scatters
//! them into the scene buffers, after every earlier frame's use of those buffers: frames in
//! flight are not disturbed. (Copy regions, one per record, cost the copy engine about a
//! microsecond each on an H100, thousands of times the bytes they move.)
//!
//! What a slot change cannot express is laid out anew: an instance whose group has no free
//! slot or no range yet, a registered or unregistered mesh or material (a material's sidedness
//! decides its instances' groups), more lights than the light buffers hold, or a journal that no
//! longer reaches back to the last sync. The new layout leaves room to grow; the graph is
//! recompiled only when the slots or groups outgrow what it was compiled for (both grow by half
//! again), and otherwise only its culling history is cleared.

use super::{build_runtime_for, Renderer};
use crate::error::{Error, Result};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{
    Access, Bind, Buffer, BufferDesc, GpuContext, GpuTimer, MemoryLocation, Pipeline, ShaderCompiler, UploadBatch,
};
use crate::graph::{FrameInputs, FRAMES_IN_FLIGHT};
use crate::passes::shared::cull_data::cull_record;
use crate::passes::shared::cull_data::GpuCullRecord;
use crate::passes::shared::gpu_types::GpuInstance;
use crate::passes::shared::slot_layout::{group_key, SlotLayout};
use crate::passes::shared::{GpuScene, SceneInputs};
use crate::render::{GraphSpec, RenderSettings};
use crate::scene::world::{Change, InstanceHandle, World};
use crate::scene::Scene;
use std::time::Instant;

/// What one [`Renderer::sync`] did.
pub use crate::stats::UpdateStats as SyncStats;

/// One slot's new contents, as `shaders/world/scatter.comp` reads it (100 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SlotUpdate {
    slot: u32,
    instance: GpuInstance,
    record: GpuCullRecord,
}

/// Bytes uploaded per changed slot.
const UPDATE_BYTES: u64 = std::mem::size_of::<SlotUpdate>() as u64;

/// What a renderer keeps of the world it mirrors.
pub(super) struct WorldMirror {
    /// The world version applied last.
    version: u64,
    layout: SlotLayout,
    /// Point lights the per-frame light buffers hold.
    light_capacity: usize,
    /// What the graph was compiled for (slots and groups with room to grow).
    compiled: FrameInputs,
    /// The handle each world instance index had when its slot was written: a new handle at an
    /// index (removed and inserted between two syncs) is a new instance and takes a new slot.
    handles: Vec<Option<InstanceHandle>>,
    /// The slot updates waiting for the next recorded frame, and where each slot's is.
    updates: Vec<SlotUpdate>,
    /// Per slot, the index of its queued update (`u32::MAX`: none).
    update_of_slot: Vec<u32>,
    /// Per frame in flight, the host-visible buffer its updates are read from.
    segments: Vec<Option<Buffer>>,
    scatter: Pipeline,
    /// What the syncs since the last recorded frame did, for that frame's figures.
    pending: Option<SyncStats>,
    /// Recent frames' figures, by frame.
    recent: std::collections::VecDeque<(u64, SyncStats)>,
    /// Per frame in flight, a timer of the scatter and the frame it timed.
    timers: Vec<(GpuTimer, Option<u64>)>,
}

impl WorldMirror {
    /// Instances the GPU holds (occupied slots).
    pub(super) fn instances(&self) -> u32 {
        self.layout.occupied()
    }

    /// What the graph is compiled for.
    pub(super) fn compiled(&self) -> &FrameInputs {
        &self.compiled
    }

    /// Queues `slot`'s new contents for the next recorded frame (replacing any queued before).
    fn queue(&mut self, slot: u32, instance: GpuInstance, record: GpuCullRecord) {
        let update = SlotUpdate { slot, instance, record };
        if self.update_of_slot.len() <= slot as usize {
            self.update_of_slot.resize(slot as usize + 1, u32::MAX);
        }
        match self.update_of_slot[slot as usize] {
            u32::MAX => {
                self.update_of_slot[slot as usize] = self.updates.len() as u32;
                self.updates.push(update);
            }
            i => self.updates[i as usize] = update,
        }
    }

    /// Forgets the queued updates (recorded, or for buffers being replaced).
    fn clear_updates(&mut self) {
        for u in &self.updates {
            self.update_of_slot[u.slot as usize] = u32::MAX;
        }
        self.updates.clear();
    }

    /// Records frame `frame`'s scatter of the queued updates into `cmd`, timed. The buffer of
    /// `frame` is free: the frame that last read it (`frame - FRAMES_IN_FLIGHT`) has completed.
    /// The queue is kept until the frame is recorded whole ([`Self::recorded`]), so that a frame
    /// whose recording failed can be recorded again.
    pub(super) fn record_updates(
        &mut self,
        ctx: &GpuContext,
        cmd: ash::vk::CommandBuffer,
        frame: u64,
        scene: &GpuScene,
    ) -> Result<()> {
        let k = (frame % FRAMES_IN_FLIGHT as u64) as usize;
        let (timer, timed) = &mut self.timers[k];
        timer.reset(cmd);
        *timed = Some(frame);
        if self.updates.is_empty() {
            return Ok(());
        }
        let bytes: &[u8] = bytemuck::cast_slice(&self.updates);
        let current = self.segments[k].as_ref().map_or(0, |b| b.size());
        if current < bytes.len() as u64 {
            let desc = BufferDesc {
                name: &format!("world updates {k}"),
                size: (bytes.len() as u64).max(current * 2).max(64 << 10),
                usage: ash::vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::CpuToGpu,
            };
            self.segments[k] = Some(Buffer::new(ctx, &desc)?);
        }
        let segment = self.segments[k].as_mut().expect("sized above");
        segment.write_bytes(0, bytes)?;
        let device = ctx.device();
        let all = Access {
            stage: ash::vk::PipelineStageFlags2::ALL_COMMANDS,
            access: ash::vk::AccessFlags2::MEMORY_READ | ash::vk::AccessFlags2::MEMORY_WRITE,
            layout: ash::vk::ImageLayout::UNDEFINED,
        };
        timer.begin(cmd, "update scene");
        // Earlier frames may still read what this overwrites.
        cmd_barriers(device, cmd, &[memory_barrier(all, Access::COMPUTE_WRITE)], &[]);
        self.scatter.bind(cmd);
        self.scatter.push_bindings(
            cmd,
            &[
                Bind::Buffer(0, segment.handle()),
                Bind::Buffer(1, scene.instances.handle()),
                Bind::Buffer(2, scene.cull_records.handle()),
            ],
        );
        let count = self.updates.len() as u32;
        self.scatter.push_constants(cmd, &count);
        // SAFETY: cmd recording with the scatter pipeline bound.
        unsafe { device.cmd_dispatch(cmd, count.div_ceil(64), 1, 1) };
        cmd_barriers(device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, all)], &[]);
        timer.end(cmd);
        Ok(())
    }

    /// The frame `frame` was recorded: the queued updates are in it, and the syncs before it
    /// are its figures.
    pub(super) fn recorded(&mut self, frame: u64) {
        self.clear_updates();
        if let Some(stats) = self.pending.take() {
            self.recent.push_back((frame, stats));
            // Kept while the frame's other figures can still be read back.
            while self.recent.len() > 2 * FRAMES_IN_FLIGHT {
                self.recent.pop_front();
            }
        }
    }

    /// The world changes frame `frame` applied, once it has completed (with the GPU time of
    /// its scatter).
    pub(super) fn update_of(&self, frame: u64) -> Result<Option<SyncStats>> {
        let Some(mut stats) = self.recent.iter().find(|(f, _)| *f == frame).map(|(_, s)| s.clone()) else {
            return Ok(None);
        };
        let (timer, timed) = &self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize];
        if *timed == Some(frame) {
            stats.gpu_ms = timer.results()?.first().map_or(0.0, |t| t.ms);
        }
        Ok(Some(stats))
    }

    fn note(&mut self, stats: &SyncStats) {
        self.pending.get_or_insert_with(Default::default).add(stats);
    }
}

/// `n` with room to grow by half again.
fn with_room(n: u64) -> u64 {
    n + n / 2 + 16
}

/// The handle of every world instance index (`None`: removed).
fn world_handles(world: &World) -> Vec<Option<InstanceHandle>> {
    (0..world.instance_slots() as u32).map(|i| world.handle_at(i)).collect()
}

/// The world's live lights, in index order.
fn live_lights(world: &World) -> Vec<crate::scene::PointLight> {
    let scene = world.scene();
    (0..scene.lights.len() as u32).filter(|&i| world.is_light_live(i)).map(|i| scene.lights[i as usize]).collect()
}

/// The world laid out in slots: the layout, the scene in slot order (live lights only) and its
/// unculled draw list.
fn lay_out(world: &World) -> (SlotLayout, Scene) {
    let layout = SlotLayout::new(world.scene(), |i| world.is_live(i));
    let mut scene = layout.slot_scene(world.scene());
    scene.lights = live_lights(world);
    (layout, scene)
}

/// What a graph for `scene` laid out as `layout` is compiled for, with room to grow.
fn frame_inputs(scene: &Scene, layout: &SlotLayout, settings: &RenderSettings) -> FrameInputs {
    FrameInputs {
        width: settings.width,
        height: settings.height,
        instances: with_room(layout.slots() as u64),
        meshes: with_room(layout.groups.len() as u64),
        lights: scene.lights.len() as u64,
        materials: scene.materials.len() as u64,
        triangles: scene.instances.iter().map(|i| scene.meshes[i.mesh as usize].index_count as u64 / 3).sum(),
        params: Vec::new(),
    }
}

impl Renderer {
    /// Prepares `world` for rendering through the graph `spec`; [`Renderer::sync`] then
    /// applies its changes. Slot ids (what draw lists, culling history and verification report)
    /// are the renderer's own: [`Renderer::slot_of`] maps a world instance to its slot.
    pub fn from_world(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        world: &World,
        settings: RenderSettings,
        spec: &GraphSpec,
    ) -> Result<Self> {
        settings.validate()?;
        if world.live_instances() == 0 {
            return Err(Error::Invalid("the world has no instances".into()));
        }
        let (layout, scene) = lay_out(world);
        let compiled = frame_inputs(&scene, &layout, &settings);
        let runtime = build_runtime_for(ctx, shaders, &compiled, spec)?;
        let mut uploads = UploadBatch::default();
        let gpu_scene = GpuScene::upload_with(ctx, &scene, layout.draw_list(&scene), &mut uploads)?;
        let light_capacity = with_room(scene.lights.len() as u64) as usize;
        let inputs = SceneInputs::new(ctx, gpu_scene, light_capacity)?;
        let mut renderer = Self::assemble(ctx, scene, inputs, uploads, runtime, settings, spec);
        renderer.world = Some(WorldMirror {
            version: world.version(),
            layout,
            light_capacity,
            compiled,
            handles: world_handles(world),
            updates: Vec::new(),
            update_of_slot: Vec::new(),
            segments: (0..FRAMES_IN_FLIGHT).map(|_| None).collect(),
            scatter: Pipeline::compute(ctx, "world scatter", &shaders.compile("world/scatter.comp", &[])?)?,
            pending: None,
            recent: Default::default(),
            timers: (0..FRAMES_IN_FLIGHT)
                .map(|_| GpuTimer::new(ctx, 1).map(|t| (t, None)))
                .collect::<std::result::Result<_, _>>()?,
        });
        Ok(renderer)
    }

    /// The world version this renderer applied last (`None`: not a world renderer); the world's
    /// journal may be trimmed up to the least of its renderers' ([`World::trim_journal`]).
    pub fn synced_version(&self) -> Option<u64> {
        self.world.as_ref().map(|w| w.version)
    }

    /// The slot world instance `index` holds in this renderer (`None`: removed, or not a world
    /// renderer).
    pub fn slot_of(&self, index: u32) -> Option<u32> {
        self.world.as_ref()?.layout.slot_of(index)
    }

    /// Applies the changes `world` had since the last sync; they take effect at the next
    /// recorded frame.
    pub fn sync(&mut self, shaders: &ShaderCompiler, world: &World) -> Result<SyncStats> {
        let start = Instant::now();
        let mirror = self.world.as_mut().ok_or_else(|| {
            Error::Invalid("sync: this renderer was made from a scene, not a world (Renderer::from_world)".into())
        })?;
        let Some(changes) = world.changes_since(mirror.version) else {
            return self.relayout(shaders, world, start);
        };
        if changes.is_empty() {
            return Ok(SyncStats::default());
        }
        let mut instances = Vec::with_capacity(changes.len());
        let mut lights = false;
        for change in changes {
            match *change {
                Change::Instance(i) => instances.push(i),
                Change::Light(_) => lights = true,
                Change::Mesh(_) | Change::Material(_) => return self.relayout(shaders, world, start),
            }
        }
        if lights {
            let live = live_lights(world);
            if live.len() > mirror.light_capacity {
                return self.relayout(shaders, world, start);
            }
            self.scene.lights = live;
        }
        instances.sort_unstable();
        instances.dedup();
        mirror.layout.release_quarantine(self.frame_index);
        // Slots first: a group without room means a relayout, which replaces the layout whole
        // (so a half-updated one does not matter), before anything is written.
        let layout = &mut mirror.layout;
        let mut touched = Vec::with_capacity(instances.len());
        for &i in &instances {
            let old = layout.slot_of(i);
            let key = world.is_live(i).then(|| group_key(world.scene(), &world.scene().instances[i as usize]));
            let same_instance = mirror.handles.get(i as usize).copied().flatten() == world.handle_at(i);
            match (old, key) {
                (Some(slot), Some(key)) if same_instance && layout.key_of_slot(slot) == key => {
                    touched.push(slot);
                }
                (old, key) => {
                    if old.is_some() {
                        touched.extend(layout.vacate(i, self.frame_index));
                    }
                    if let Some(key) = key {
                        match layout.place(i, key) {
                            Some(slot) => touched.push(slot),
                            None => return self.relayout(shaders, world, start),
                        };
                    }
                }
            }
        }
        for &i in &instances {
            if mirror.handles.len() <= i as usize {
                mirror.handles.resize(i as usize + 1, None);
            }
            mirror.handles[i as usize] = world.handle_at(i);
        }
        for &slot in &touched {
            let contents = mirror.layout.slot_contents(slot, world.scene());
            let group = mirror.layout.group_of_slot(slot) as u32;
            mirror.queue(slot, GpuInstance::new(&contents), cull_record(world.scene(), &contents, group));
            self.scene.instances[slot as usize] = contents;
        }
        mirror.version = world.version();
        let stats = SyncStats {
            instances_changed: instances.len() as u64,
            bytes_uploaded: touched.len() as u64 * UPDATE_BYTES,
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            gpu_ms: 0.0,
            relayout: false,
        };
        mirror.note(&stats);
        Ok(stats)
    }

    /// Lays the world out anew (see the module documentation).
    fn relayout(&mut self, shaders: &ShaderCompiler, world: &World, start: Instant) -> Result<SyncStats> {
        if world.live_instances() == 0 {
            return Err(Error::Invalid("sync: the world has no instances".into()));
        }
        let (layout, scene) = lay_out(world);
        let mirror = self.world.as_ref().expect("a world renderer");
        let needed = frame_inputs(&scene, &layout, &self.settings);
        let outgrown = layout.slots() as u64 > mirror.compiled.instances
            || layout.groups.len() as u64 > mirror.compiled.meshes
            || needed.materials != mirror.compiled.materials
            || needed.lights > mirror.light_capacity as u64;
        let mut uploads = UploadBatch::default();
        let gpu_scene = GpuScene::upload_with(&self.ctx, &scene, layout.draw_list(&scene), &mut uploads)?;
        let light_capacity = with_room(scene.lights.len() as u64).max(mirror.light_capacity as u64) as usize;
        let inputs = SceneInputs::new(&self.ctx, gpu_scene, light_capacity)?;
        if outgrown {
            let runtime = build_runtime_for(&self.ctx, shaders, &needed, &self.spec)?;
            self.install_runtime(runtime)?;
        } else {
            // Slots were given out anew: last frame's visibility and draw lists name other
            // instances now.
            self.runtime.reset_history();
        }
        let bytes = uploads.bytes();
        let old = std::mem::replace(&mut self.inputs, inputs);
        self.retired_inputs.push((self.frame_index.saturating_sub(1), old));
        // A batch not recorded yet would fill the buffers being replaced: it goes unrecorded.
        self.pending_uploads = Some(uploads);
        let mirror = self.world.as_mut().expect("a world renderer");
        if outgrown {
            mirror.compiled = needed;
        }
        mirror.clear_updates();
        mirror.layout = layout;
        mirror.handles = world_handles(world);
        mirror.light_capacity = light_capacity;
        mirror.version = world.version();
        self.scene = scene;
        let stats = SyncStats {
            instances_changed: world.live_instances() as u64,
            bytes_uploaded: bytes,
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            gpu_ms: 0.0,
            relayout: true,
        };
        mirror.note(&stats);
        Ok(stats)
    }
}
