//! A renderer that mirrors a [`World`]: [`Renderer::from_world`] lays the world out in slots
//! ([`SlotLayout`]) and [`Renderer::sync`] applies the world's changes since the last sync.
//!
//! A change of instances rewrites only their slots. A changed slot (an instance moved, or
//! another instance, material or flags in it) queues its whole new record with its slot and
//! draw group, 72 bytes, written by the sync straight into the host-visible memory the GPU
//! reads them from ([`super::update_ring`]); a slot's last update supersedes those queued before
//! it. At the start of the next recorded frame one compute dispatch
//! (`shaders/world/scatter.comp`) writes them into the instance records and derives each
//! slot's cull bound from its record and its group's local bounds, after every earlier frame's
//! use of those buffers: frames in flight are not disturbed. (Copy regions, one per record,
//! cost the copy engine about a microsecond each on an H100, thousands of times the bytes they
//! move.)
//!
//! Motion vectors need each instance's transform of the previous frame: while some view's
//! graph writes them ([`Renderer::fit_previous_records`]) the scene keeps a second copy of the
//! instance records ([`GpuScene::prev_instances`]). Before the scatter
//! writes the new records, the slots it updates and the slots the last frame updated get
//! their current record as previous (`shaders/world/keep_previous.comp`): every slot's previous
//! record is then the one it had last frame, and an instance moved last frame but not this one
//! gets previous = current (no stale motion). Every other slot's previous record already equals
//! its record, so the cost follows what moves, not the slots (a frame listing more than a
//! quarter of them copies the table whole). The world's previous frame is the renderer's
//! previous frame: a view that skipped frames sees its camera's motion since its own last frame,
//! but the instances' motion since the world's last frame. A scene made anew (a rebuild, below)
//! starts with previous = current: its instances show no motion at that frame.
//!
//! A group without a free slot, or an instance of a group the layout lacks, grows the layout
//! at its end ([`SlotLayout::grow`]). That, a registered mesh, material or texture, or more
//! lights than the light buffers hold, is applied in place
//! ([`crate::passes::shared::scene_growth`]): only the new slots, groups, meshes, materials
//! and textures are written, and a buffer that no longer holds what the world needs is
//! carried into a larger one on the GPU. Every slot and group keeps its index, so the culling
//! history stays valid: it is kept, and when the slots or groups outgrow what the graph was
//! compiled for (both grow by half again), the recompiled graph inherits it
//! ([`crate::graph::GraphRuntime::inherit_history`]). The scene is uploaded again from the
//! host, laid out as before, only when a texture size class needs more layers than the device
//! allows. A face-cull region out of reserved groups, or a journal that no longer reaches back
//! to the last sync, lays the world out anew in spatial order, with the history cleared.

use super::graphs::build_runtime;
use super::update_ring::{SlotUpdate, UpdateRing, DROPPED};
use super::Renderer;
use crate::error::{Error, Result};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{
    Access, Bind, Buffer, BufferDesc, GpuContext, GpuTimer, MemoryLocation, Pipeline, ShaderCompiler, UploadBatch,
};
use crate::graph::{FrameInputs, Growth, KindRegistry, Quantities, FRAMES_IN_FLIGHT};
use crate::passes::shared::gpu_types::GpuInstance;
use crate::passes::shared::instance_ranges;
use crate::passes::shared::slot_layout::{group_key, Placement, SlotLayout};
use crate::passes::shared::{GpuScene, LaidOutScene, SceneInputs};
use crate::render::{GraphSpec, RenderSettings, ViewId};
use crate::scene::world::{Change, InstanceHandle, World};
use crate::scene::{Instance, Scene};
use crate::stats::UpdateStats;
use std::sync::Arc;
use std::time::Instant;

/// Previous records are copied whole when the slots to list exceed this share of the table
/// (1 / `COPY_ALL_SHARE`): a listed slot costs a scattered read and write of its record and its
/// slot number, the whole copy 128 linear bytes a slot.
const COPY_ALL_SHARE: usize = 4;
/// Below this many listed slots they are copied one by one whatever the share: either way
/// costs next to nothing, and small worlds (the tests') take the path large ones take.
const COPY_ALL_MIN_LISTED: usize = 1024;

/// What a renderer keeps of the world it mirrors.
pub(super) struct WorldMirror {
    /// The id of the world it mirrors ([`World::id`]): another world is refused.
    world: u32,
    /// The world version applied last.
    version: u64,
    layout: SlotLayout,
    /// The handle each world instance index had when its slot was written: a new handle at an
    /// index (removed and inserted between two syncs) is a new instance and takes a new slot.
    handles: Vec<Option<InstanceHandle>>,
    /// The slot updates waiting for the next recorded frame (written where the GPU reads
    /// them), and per slot where its update is (an index into `updates`; `u32::MAX`: none).
    updates: UpdateRing,
    update_of_slot: Vec<u32>,
    /// The user data waiting for the next recorded frame: per entry the slot, then its
    /// [`GpuScene::user_words`] words; per slot where its entry starts (`u32::MAX`: none).
    user: Vec<u32>,
    user_of_slot: Vec<u32>,
    /// Per frame in flight, the host-visible buffers its user data and the slots whose
    /// previous records it keeps are read from.
    segments: Vec<[Option<Buffer>; 2]>,
    /// The scatter of slot updates.
    scatter: Pipeline,
    /// The scatter of user data (`None`: the world has none).
    scatter_user: Option<Pipeline>,
    /// What the syncs since the last recorded frame did, for that frame's figures.
    pending: Option<UpdateStats>,
    /// Recent frames' figures, by frame.
    recent: std::collections::VecDeque<(u64, UpdateStats)>,
    /// Per frame in flight, a timer of the scatter and the frame it timed.
    timers: Vec<(GpuTimer, Option<u64>)>,
    /// The slots the last recorded frame updated: this frame copies their records to the
    /// previous ones even if it scatters none (previous = current again).
    last_slots: Vec<u32>,
    /// Copies listed slots' records to the previous ones.
    keep_previous: Pipeline,
    /// Whether the scene's previous records are still to be filled (a new scene).
    refresh_previous: bool,
    /// Words of user data per instance ([`World::user_words`]).
    user_words: u32,
    /// The posed instances' deformations (made at the first pose).
    deformer: Option<super::deform::Deformer>,
}

/// The move of `instance` in its place: its transform, material and flags, the slot's group.
fn move_of(instance: &Instance, placed: Placement) -> SlotUpdate {
    let (rows, translation_lo) = GpuInstance::transform_words(&instance.transform);
    let material_flags = GpuInstance::material_flags_of(instance);
    SlotUpdate { rows, translation_lo, slot: placed.slot, group: placed.group, material_flags }
}

impl WorldMirror {
    /// Instances the GPU holds (occupied slots).
    pub(super) fn instances(&self) -> u32 {
        self.layout.occupied()
    }

    /// What a graph loaded with `kinds` is compiled for on this world's `scene` (as the
    /// renderer holds it, in slots) at `settings`: its quantities with room to grow.
    pub(super) fn compiled_for(
        &mut self,
        kinds: &KindRegistry,
        scene: &mut Arc<Scene>,
        settings: &RenderSettings,
    ) -> Result<FrameInputs> {
        let layout = std::mem::take(&mut self.layout);
        let (counted, counted_scene, layout) = quantities(kinds, take_scene(scene), layout);
        *scene = Arc::new(counted_scene);
        self.layout = layout;
        Ok(with_room_to_grow(kinds, &counted?, settings))
    }

    /// Where `slot`'s queued update is, growing the table to hold it.
    fn entry(&mut self, slot: u32) -> &mut u32 {
        if self.update_of_slot.len() <= slot as usize {
            self.update_of_slot.resize(slot as usize + 1, u32::MAX);
        }
        &mut self.update_of_slot[slot as usize]
    }

    /// Queues `update` of its slot, in place of any queued before.
    fn queue_update(&mut self, update: SlotUpdate) -> Result<()> {
        let slot = update.slot;
        match *self.entry(slot) {
            u32::MAX => self.update_of_slot[slot as usize] = self.updates.push(update)? as u32,
            i => *self.updates.at(i as usize) = update,
        }
        Ok(())
    }

    /// Queues moves of the instances `movers`, in order, with each instance's transform as
    /// `world` has it now; instances without a slot (removed) are skipped. A long list is queued
    /// on several threads: each move is written to the ring in list order, then the threads
    /// that own the slots' entries of [`Self::update_of_slot`] take them (`crate::parallel`), so
    /// that a slot's last update wins; the updates it supersedes are then dropped.
    fn queue_moves(&mut self, movers: &[u32], world: &World) -> Result<()> {
        // The renderer's own copy of the slot keeps its old transform: a random write per move
        // into a table of every slot would cost more than the rest of the move (see
        // `Renderer::scene`).
        let instances = &world.scene().instances;
        if !crate::parallel::worth_routing(movers.len()) {
            for &i in movers {
                let Some(placed) = self.layout.placement_of(i) else { continue };
                self.queue_update(move_of(&instances[i as usize], placed))?;
            }
            return Ok(());
        }
        let slots = self.layout.slots() as usize;
        if self.update_of_slot.len() < slots {
            self.update_of_slot.resize(slots, u32::MAX);
        }
        let owners = crate::parallel::Owners::new(slots, movers.len());
        let layout = &self.layout;
        // The moves are written straight into the memory the GPU reads them from.
        let (base, room) = self.updates.room(movers.len())?;
        let ahead = |k: usize| {
            let i = movers[k];
            layout.prefetch(i);
            if let Some(instance) = instances.get(i as usize) {
                crate::parallel::prefetch(instance);
            }
        };
        let routed = crate::parallel::route(room, &owners, ahead, |k, update| {
            let i = movers[k];
            let Some(placed) = layout.placement_of(i) else {
                *update = SlotUpdate::DROPPED;
                return Ok::<_, std::convert::Infallible>(None);
            };
            *update = move_of(&instances[i as usize], placed);
            Ok(Some(placed.slot as usize))
        });
        let Ok(routed) = routed;
        self.updates.note_slots(&routed);
        // The updates the list supersedes: queued before it, or earlier in it.
        let superseded = crate::parallel::apply_routed(&mut self.update_of_slot, &owners, &routed, |entry, k| {
            let earlier = std::mem::replace(entry, (base + k) as u32);
            (earlier != u32::MAX).then_some(earlier)
        });
        for &at in &superseded {
            self.updates.at(at as usize).slot = DROPPED;
        }
        Ok(())
    }

    /// Queues `slot`'s whole new record (replacing any update queued before).
    fn queue_whole(&mut self, slot: u32, group: u32, record: GpuInstance) -> Result<()> {
        let GpuInstance { rows, translation_lo, material_flags } = record;
        self.queue_update(SlotUpdate { rows, translation_lo, slot, group, material_flags })
    }

    /// Queues `data` as `slot`'s user data (replacing any queued before).
    fn queue_user_data(&mut self, slot: u32, data: &[u32]) {
        if data.is_empty() {
            return;
        }
        if self.user_of_slot.len() <= slot as usize {
            self.user_of_slot.resize(slot as usize + 1, u32::MAX);
        }
        match self.user_of_slot[slot as usize] {
            u32::MAX => {
                self.user_of_slot[slot as usize] = self.user.len() as u32;
                self.user.push(slot);
                self.user.extend_from_slice(data);
            }
            at => self.user[at as usize + 1..at as usize + 1 + data.len()].copy_from_slice(data),
        }
    }

    /// Forgets the queued updates (recorded, or for buffers being replaced).
    fn clear_updates(&mut self) {
        if let Some(deformer) = &mut self.deformer {
            deformer.clear();
        }
        let words = self.user_words() as usize;
        for entry in self.user.chunks_exact(words + 1) {
            self.user_of_slot[entry[0] as usize] = u32::MAX;
        }
        self.user.clear();
        for slot in Self::updated_slots(&self.updates) {
            self.update_of_slot[slot as usize] = u32::MAX;
        }
        self.updates.clear();
    }

    /// The slots whose records the queued updates replace (a slot may be listed twice).
    fn updated_slots(updates: &UpdateRing) -> impl Iterator<Item = u32> + '_ {
        updates.slots().iter().copied().filter(|&s| s != DROPPED)
    }

    /// Bytes queued.
    fn queued_bytes(&self) -> u64 {
        (self.updates.len() * std::mem::size_of::<SlotUpdate>() + std::mem::size_of_val(self.user.as_slice())) as u64
            + self.deformer.as_ref().map_or(0, |d| d.queued_bytes())
    }

    /// Words of user data per instance.
    fn user_words(&self) -> u32 {
        self.user_words
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
        uploads: Option<&UploadBatch>,
    ) -> Result<()> {
        let k = (frame % FRAMES_IN_FLIGHT as u64) as usize;
        let (timer, timed) = &mut self.timers[k];
        timer.reset(cmd);
        *timed = Some(frame);
        let scatters = !self.updates.is_empty();
        let deforms = self.deformer.as_ref().is_some_and(|d| d.pending());
        let uploads = uploads.filter(|b| !b.is_empty());
        let previous = scene.prev_instances.as_ref();
        // A new scene copies every record; so does a frame whose listed slots are a large share
        // of the table, where one linear copy is faster than scattered ones (`COPY_ALL_SHARE`).
        // Otherwise the slots updated now and last frame are copied.
        let listed = self.last_slots.len() + self.updates.len();
        let most_listed = (scene.instance_count as usize / COPY_ALL_SHARE).max(COPY_ALL_MIN_LISTED);
        let copies_all = previous.is_some() && (self.refresh_previous || listed > most_listed);
        let keeps_previous = previous.is_some() && !copies_all && (scatters || !self.last_slots.is_empty());
        let computes = keeps_previous || scatters || !self.user.is_empty() || deforms;
        if !copies_all && !computes && uploads.is_none() {
            return Ok(());
        }
        let device = ctx.device();
        let all = Access {
            stage: ash::vk::PipelineStageFlags2::ALL_COMMANDS,
            access: ash::vk::AccessFlags2::MEMORY_READ | ash::vk::AccessFlags2::MEMORY_WRITE,
            layout: ash::vk::ImageLayout::UNDEFINED,
        };
        // Uploads and edits of the scene (registrations, growth) are timed with the updates.
        timer.begin(cmd, "update scene");
        if let Some(batch) = uploads {
            batch.record(ctx, cmd);
        }
        if !copies_all && !computes {
            timer.end(cmd);
            return Ok(());
        }
        if let Some(previous) = previous.filter(|_| copies_all) {
            // Last frame's records become the previous ones before the scatter replaces them.
            let transfer = Access {
                stage: ash::vk::PipelineStageFlags2::COPY,
                access: ash::vk::AccessFlags2::TRANSFER_READ | ash::vk::AccessFlags2::TRANSFER_WRITE,
                layout: ash::vk::ImageLayout::UNDEFINED,
            };
            cmd_barriers(device, cmd, &[memory_barrier(all, transfer)], &[]);
            // The slots in use: the buffers have room beyond them.
            let used = scene.instance_count as u64 * std::mem::size_of::<GpuInstance>() as u64;
            let size = used.min(scene.instances.size()).min(previous.size()).max(1);
            let region = ash::vk::BufferCopy { src_offset: 0, dst_offset: 0, size };
            // SAFETY: cmd is recording; both buffers live as long as the scene, which outlives
            // the frames that use it, and hold at least one record.
            unsafe { device.cmd_copy_buffer(cmd, scene.instances.handle(), previous.handle(), &[region]) };
            cmd_barriers(device, cmd, &[memory_barrier(transfer, all)], &[]);
        }
        if !computes {
            timer.end(cmd);
            return Ok(());
        }
        // Earlier frames may still read what this overwrites.
        let compute_rw = Access {
            stage: ash::vk::PipelineStageFlags2::COMPUTE_SHADER,
            access: ash::vk::AccessFlags2::SHADER_STORAGE_READ | ash::vk::AccessFlags2::SHADER_STORAGE_WRITE,
            layout: ash::vk::ImageLayout::UNDEFINED,
        };
        cmd_barriers(device, cmd, &[memory_barrier(all, compute_rw)], &[]);
        if let Some(previous) = previous.filter(|_| keeps_previous) {
            // A slot in both lists is written twice with the same record.
            let now = Self::updated_slots(&self.updates);
            let slots: Vec<u32> = self.last_slots.iter().copied().chain(now).collect();
            let name = format!("previous record slots {k}");
            let segment = fill_segment(ctx, &mut self.segments[k][1], &name, bytemuck::cast_slice(&slots))?;
            self.keep_previous.bind(cmd);
            let mut binds = vec![Bind::Buffer(0, segment.handle())];
            binds.extend(scene.instance_binds(1));
            let range = scene.binding_range;
            binds.extend(instance_ranges::binds(previous, 2, instance_ranges::PREV_INSTANCE_RANGE_BINDING, range));
            self.keep_previous.push_bindings(cmd, &binds);
            self.keep_previous.push_constants(cmd, &[slots.len() as u32]);
            // SAFETY: cmd recording with the keep_previous pipeline bound.
            unsafe {
                crate::gpu::line_dispatch::cmd_dispatch_line(
                    device,
                    cmd,
                    &ctx.caps().limits,
                    (slots.len() as u32).div_ceil(64),
                )
            };
            cmd_barriers(device, cmd, &[memory_barrier(compute_rw, compute_rw)], &[]);
        }
        if let Some(deformer) = self.deformer.as_mut().filter(|_| deforms) {
            // The poses' bounds into their groups before the scatters derive cull records.
            deformer.record(ctx, cmd, k, scene)?;
            cmd_barriers(device, cmd, &[memory_barrier(compute_rw, compute_rw)], &[]);
        }
        if let (Some(pipeline), Some(user_data), false) = (&self.scatter_user, &scene.user_data, self.user.is_empty()) {
            let bytes: &[u8] = bytemuck::cast_slice(&self.user);
            let segment = fill_segment(ctx, &mut self.segments[k][0], &format!("user data updates {k}"), bytes)?;
            let count = self.user.len() as u32 / (self.user_words + 1);
            pipeline.bind(cmd);
            pipeline.push_bindings(cmd, &[Bind::Buffer(0, segment.handle()), Bind::Buffer(1, user_data.handle())]);
            pipeline.push_constants(cmd, &[count, self.user_words]);
            // SAFETY: cmd recording with the user data scatter bound.
            unsafe {
                crate::gpu::line_dispatch::cmd_dispatch_line(device, cmd, &ctx.caps().limits, count.div_ceil(64))
            };
        }
        // A slot's superseded updates are dropped, so the chunks touch different slots, but a
        // barrier between them keeps the tools sure of it (a frame has more than one chunk only
        // when its syncs outgrew the ring).
        for (c, (buffer, count)) in self.updates.chunks().enumerate() {
            if c > 0 {
                cmd_barriers(device, cmd, &[memory_barrier(compute_rw, compute_rw)], &[]);
            }
            self.scatter.bind(cmd);
            // Without block bounds the binding only needs some buffer.
            let blocks = scene.block_bounds.as_ref().unwrap_or(&scene.cull_records);
            let mut binds = vec![
                Bind::Buffer(0, buffer.handle()),
                Bind::Buffer(2, scene.cull_records.handle()),
                Bind::Buffer(3, scene.group_bounds.handle()),
                Bind::Buffer(4, blocks.handle()),
            ];
            binds.extend(scene.instance_binds(1));
            self.scatter.push_bindings(cmd, &binds);
            self.scatter.push_constants(cmd, &[count as u32, u32::from(scene.block_bounds.is_some())]);
            // SAFETY: cmd recording with the scatter pipeline bound.
            unsafe {
                crate::gpu::line_dispatch::cmd_dispatch_line(
                    device,
                    cmd,
                    &ctx.caps().limits,
                    (count as u32).div_ceil(64),
                )
            };
        }
        cmd_barriers(device, cmd, &[memory_barrier(compute_rw, all)], &[]);
        timer.end(cmd);
        Ok(())
    }

    /// The frame `frame` was recorded: the queued updates are in it, and the syncs before it
    /// are its figures.
    pub(super) fn recorded(&mut self, frame: u64) {
        self.last_slots.clear();
        self.last_slots.extend(Self::updated_slots(&self.updates));
        self.refresh_previous = false;
        self.clear_updates();
        self.updates.advance();
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
    pub(super) fn update_of(&self, frame: u64) -> Result<Option<UpdateStats>> {
        let Some(mut stats) = self.recent.iter().find(|(f, _)| *f == frame).map(|(_, s)| s.clone()) else {
            return Ok(None);
        };
        let (timer, timed) = &self.timers[(frame % FRAMES_IN_FLIGHT as u64) as usize];
        if *timed == Some(frame) {
            stats.gpu_ms = timer.results()?.first().map_or(0.0, |t| t.ms);
        }
        Ok(Some(stats))
    }

    fn note(&mut self, stats: &UpdateStats) {
        self.pending.get_or_insert_with(Default::default).add(stats);
    }
}

/// `segment` holding `bytes` (made, or made larger, where it does not hold them).
pub(super) fn fill_segment<'a>(
    ctx: &GpuContext,
    segment: &'a mut Option<Buffer>,
    name: &str,
    bytes: &[u8],
) -> Result<&'a Buffer> {
    let current = segment.as_ref().map_or(0, |b| b.size());
    if segment.is_none() || current < bytes.len() as u64 {
        let desc = BufferDesc {
            name,
            size: (bytes.len() as u64).max(current * 2).max(64 << 10),
            usage: ash::vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        };
        *segment = Some(Buffer::new(ctx, &desc)?);
    }
    let segment = segment.as_mut().expect("sized above");
    segment.write_bytes(0, bytes)?;
    Ok(segment)
}

/// The user data of `world` in the slot order of `layout` (zeros for empty slots).
fn slot_user_data(world: &World, layout: &SlotLayout) -> Vec<u32> {
    let words = world.user_words() as usize;
    let mut data = vec![0u32; layout.slots() as usize * words];
    if words > 0 {
        for (slot, out) in data.chunks_exact_mut(words).enumerate() {
            if let Some(i) = layout.instance_in(slot as u32) {
                out.copy_from_slice(world.user_data_at(i));
            }
        }
    }
    data
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

/// The renderer's copy of the world, taken out of `scene` to be changed and put back with
/// `Arc::new`: copied only if a caller still shares it ([`Renderer::shared_scene`]).
fn take_scene(scene: &mut Arc<Scene>) -> Scene {
    Arc::unwrap_or_clone(std::mem::take(scene))
}

/// The world laid out in slots: the layout, the scene in slot order (live lights only) and its
/// unculled draw list.
fn lay_out(world: &World) -> (SlotLayout, Scene) {
    let layout = SlotLayout::new(world.scene(), |i| world.is_live(i));
    let mut scene = layout.slot_scene(world.scene());
    scene.lights = live_lights(world);
    (layout, scene)
}

/// The quantities of `scene` laid out as `layout`, as the graph's kinds count them (the scene
/// and layout handed back whatever the outcome).
fn quantities(kinds: &KindRegistry, scene: Scene, layout: SlotLayout) -> (Result<Quantities>, Scene, SlotLayout) {
    let laid = LaidOutScene { scene, layout };
    let counted = kinds.count(&laid);
    (counted, laid.scene, laid.layout)
}

/// What a graph is compiled for with `counted` quantities: room to grow in those that grow.
fn with_room_to_grow(kinds: &KindRegistry, counted: &Quantities, settings: &RenderSettings) -> FrameInputs {
    let quantities = counted
        .iter()
        .map(|(name, n)| {
            let grows = kinds.quantity(name).is_some_and(|q| q.growth == Growth::Grows);
            (name.to_string(), if grows { with_room(n) } else { n })
        })
        .collect();
    FrameInputs::with_quantities(settings.width, settings.height, quantities)
}

/// Whether a graph compiled for `compiled` no longer holds what `counted` counts: a quantity
/// that grows beyond its room, or another that changed.
fn outgrows(kinds: &KindRegistry, counted: &Quantities, compiled: &FrameInputs) -> bool {
    counted.iter().any(|(name, n)| match kinds.quantity(name).map(|q| q.growth) {
        Some(Growth::Grows) => n > compiled.quantity(name),
        _ => n != compiled.quantity(name),
    })
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
        let (counted, scene, layout) = quantities(&spec.kinds, scene, layout);
        let compiled = with_room_to_grow(&spec.kinds, &counted?, &settings);
        let runtime = build_runtime(ctx, shaders, &compiled, spec)?;
        let mut uploads = UploadBatch::default();
        let mut gpu_scene = GpuScene::upload_with_room(ctx, &scene, layout.draw_list(&scene), &mut uploads, None)?;
        if runtime.reads_previous_instances() {
            gpu_scene.add_previous_instances(ctx)?;
        }
        gpu_scene.add_user_data(ctx, &mut uploads, world.user_words(), &slot_user_data(world, &layout))?;
        let gpu_scene = Arc::new(gpu_scene);
        let light_capacity = with_room(scene.lights.len() as u64) as usize;
        let mut renderer = Self::assemble(
            ctx,
            Arc::new(scene),
            gpu_scene,
            light_capacity,
            uploads,
            runtime,
            compiled,
            settings,
            spec,
        )?;
        renderer.world = Some(WorldMirror {
            world: world.id(),
            version: world.version(),
            layout,
            handles: world_handles(world),
            updates: UpdateRing::new(ctx),
            update_of_slot: Vec::new(),
            user: Vec::new(),
            user_of_slot: Vec::new(),
            segments: (0..FRAMES_IN_FLIGHT).map(|_| [None, None]).collect(),
            scatter: Pipeline::compute(ctx, "world scatter", &shaders.compile("world/scatter.comp", &[])?)?,
            keep_previous: Pipeline::compute(
                ctx,
                "world previous records",
                &shaders.compile("world/keep_previous.comp", &[])?,
            )?,
            scatter_user: match world.user_words() {
                0 => None,
                _ => Some(Pipeline::compute(
                    ctx,
                    "world scatter (user data)",
                    &shaders.compile("world/scatter_user_data.comp", &[])?,
                )?),
            },
            pending: None,
            recent: Default::default(),
            timers: (0..FRAMES_IN_FLIGHT)
                .map(|_| GpuTimer::new(ctx, 1).map(|t| (t, None)))
                .collect::<std::result::Result<_, _>>()?,
            last_slots: Vec::new(),
            refresh_previous: true,
            user_words: world.user_words(),
            deformer: None,
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

    /// The world instances `view` drew in its last completed frame, as the handles they had
    /// when their slots were written, in slot order without repeats (`None` unless draw lists
    /// are captured, [`Renderer::capture_draw_lists`], or before a frame completed; an error
    /// for a renderer made from a scene, whose [`Renderer::drawn_in_view`] names instances).
    pub fn drawn_handles(&self, view: ViewId) -> Result<Option<Vec<InstanceHandle>>> {
        let mirror = self.world.as_ref().ok_or_else(|| {
            Error::Invalid("drawn_handles: this renderer was made from a scene, not a world (see drawn_in_view)".into())
        })?;
        let Some(lists) = self.drawn_in_view(view)? else { return Ok(None) };
        let mut slots: Vec<u32> = Vec::new();
        for list in lists {
            match list {
                crate::render::DrawnInstances::All => slots.extend(0..mirror.layout.slots()),
                crate::render::DrawnInstances::Some(ids) => slots.extend(ids),
            }
        }
        slots.sort_unstable();
        slots.dedup();
        Ok(Some(
            slots
                .into_iter()
                .filter_map(|slot| mirror.layout.instance_in(slot))
                .filter_map(|index| mirror.handles.get(index as usize).copied().flatten())
                .collect(),
        ))
    }

    /// The world instance `view` showed at pixel (`x`, `y`) of its last frame, `None` for the
    /// background ([`Renderer::pick`] through this renderer's slots).
    pub fn pick_handle(&mut self, view: ViewId, x: u32, y: u32) -> Result<Option<InstanceHandle>> {
        let Some(slot) = self.pick(view, x, y)? else { return Ok(None) };
        let mirror = self.world.as_ref().ok_or_else(|| {
            Error::Invalid("pick_handle: this renderer was made from a scene, not a world (see pick)".into())
        })?;
        Ok(mirror.layout.instance_in(slot).and_then(|index| mirror.handles.get(index as usize).copied().flatten()))
    }

    /// Applies the changes `world` had since the last sync; they take effect at the next
    /// recorded frame.
    pub fn sync(&mut self, shaders: &ShaderCompiler, world: &World) -> Result<UpdateStats> {
        let start = Instant::now();
        let mirror = self.world.as_mut().ok_or_else(|| {
            Error::Invalid("sync: this renderer was made from a scene, not a world (Renderer::from_world)".into())
        })?;
        if mirror.world != world.id() {
            return Err(Error::World(crate::scene::world::WorldError::ForeignWorld {
                renders: mirror.world,
                given: world.id(),
            }));
        }
        let Some(changes) = world.changes_since(mirror.version) else {
            return self.rebuild(shaders, world, start, Layout::Fresh, true);
        };
        if changes.is_empty() {
            return Ok(UpdateStats::default());
        }
        // Moves take the cheap path below; anything else about an instance the general one.
        let mut instances = Vec::new();
        let mut registered = Registered::default();
        let mut lights = false;
        let mut movers = Vec::with_capacity(changes.len());
        let mut user_changed = Vec::new();
        let mut posed = Vec::new();
        for change in changes {
            match *change {
                Change::Instance(i) => instances.push(i),
                Change::Transform(i) => movers.push(i),
                Change::Light(_) => lights = true,
                Change::Sun => Arc::make_mut(&mut self.scene).sun = world.scene().sun,
                Change::Mesh(m) => registered.meshes.push(m),
                Change::Texture(t) => registered.textures.push(t),
                Change::Material(m) => registered.materials.push(m),
                Change::UserData(i) => user_changed.push(i),
                Change::Pose(i) => posed.push(i),
            }
        }
        registered.dedup();
        // A moved, changed or posed instance queues at most one move (a regrouped material's
        // instances aside): with the room made first, queueing them cannot fail halfway.
        mirror.updates.reserve(movers.len() + instances.len() + posed.len())?;
        let textures_changed = !registered.textures.is_empty();
        // A material's sidedness and blending decide its instances' draw groups: they are
        // re-placed where those changed (a rare event, so a pass over the instances is fine). A
        // material new to the renderer has no instances placed yet.
        let regrouped: Vec<u32> = registered
            .materials
            .iter()
            .copied()
            .filter(|&m| {
                let (old, new) = (self.scene.materials.get(m as usize), &world.scene().materials[m as usize]);
                old.is_some_and(|old| !groups_alike(old, new))
            })
            .collect();
        if !regrouped.is_empty() {
            instances.extend((0..world.instance_slots() as u32).filter(|&i| {
                world.is_live(i) && regrouped.binary_search(&world.scene().instances[i as usize].material).is_ok()
            }));
        }
        if lights {
            let live = live_lights(world);
            registered.lights_outgrown = live.len() > self.light_capacity;
            Arc::make_mut(&mut self.scene).lights = live;
        }
        instances.sort_unstable();
        instances.dedup();
        mirror.layout.release_quarantine(self.frame_index);
        let slots_before = mirror.layout.slots();
        // Slots first: a region without reserve lays the world out anew, which replaces the
        // layout whole (so a half-updated one does not matter), before anything is written.
        let layout = &mut mirror.layout;
        let mut touched = Vec::with_capacity(instances.len());
        let mut moved_in_place = Vec::new();
        let mut grew = false;
        for &i in &instances {
            let old = layout.slot_of(i);
            let key = world.is_live(i).then(|| group_key(world.scene(), &world.scene().instances[i as usize]));
            let same_instance = mirror.handles.get(i as usize).copied().flatten() == world.handle_at(i);
            match (old, key) {
                (Some(slot), Some(key)) if same_instance && layout.key_of_slot(slot) == key => {
                    touched.push(slot);
                    moved_in_place.push(slot);
                }
                (old, key) => {
                    if old.is_some() {
                        touched.extend(layout.vacate(i, self.frame_index));
                    }
                    if let Some(key) = key {
                        let slot = match layout.place(i, key) {
                            Some(slot) => slot,
                            None if layout.grow(key) => {
                                grew = true;
                                layout.place(i, key).expect("a grown group has free slots")
                            }
                            None => return self.rebuild(shaders, world, start, Layout::Fresh, textures_changed),
                        };
                        touched.push(slot);
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
        let queued_before = mirror.queued_bytes();
        let mut edited_bytes = 0;
        // A list must hold a command per level of detail of every group: new groups, or
        // meshes registered with longer chains, may need more than the regions hold.
        let level_room = |layout: &SlotLayout| layout.has_level_room(world.scene());
        if (grew || !registered.meshes.is_empty()) && !level_room(&mirror.layout) {
            return self.rebuild(shaders, world, start, Layout::Fresh, textures_changed);
        }
        if grew || !registered.is_empty() {
            match self.grow_in_place(shaders, world, &registered, slots_before)? {
                Some(bytes) => edited_bytes = bytes,
                None => return self.rebuild(shaders, world, start, Layout::Kept, textures_changed),
            }
        }
        let mirror = self.world.as_mut().expect("a world renderer");
        moved_in_place.sort_unstable();
        // The renderer's own slots, copied first if a caller shares them: once, not per slot,
        // and not for a sync that only moves instances.
        let slots: &mut [Instance] =
            if touched.is_empty() { &mut [] } else { &mut Arc::make_mut(&mut self.scene).instances };
        for &slot in &touched {
            let contents = mirror.layout.slot_contents(slot, world.scene());
            let before = &slots[slot as usize];
            // The same instance in the same slot with its material and flags: a move, which
            // keeps the slot's user data.
            let moved = before.mesh == contents.mesh
                && before.material == contents.material
                && before.flags == contents.flags
                && moved_in_place.binary_search(&slot).is_ok();
            let group = mirror.layout.group_of_slot(slot) as u32;
            mirror.queue_whole(slot, group, GpuInstance::new(&contents))?;
            // An instance new to its slot brings its user data along.
            if let Some(i) = mirror.layout.instance_in(slot).filter(|_| !moved && mirror.user_words > 0) {
                mirror.queue_user_data(slot, world.user_data_at(i));
            }
            slots[slot as usize] = contents;
        }
        // A move of an instance that was also inserted, removed or changed since the last sync
        // is applied after the general path has given it its slot (or none); the world's
        // transform is the latest either way.
        mirror.queue_moves(&movers, world)?;
        for &i in &user_changed {
            if let Some(slot) = mirror.layout.slot_of(i) {
                mirror.queue_user_data(slot, world.user_data_at(i));
            }
        }
        posed.sort_unstable();
        posed.dedup();
        let edited_before = self.uploads.pending.as_ref().map_or(0, |b| b.edits.bytes());
        self.queue_poses(shaders, world, &posed)?;
        let edited_bytes = edited_bytes + self.uploads.pending.as_ref().map_or(0, |b| b.edits.bytes()) - edited_before;
        let mirror = self.world.as_mut().expect("a world renderer");
        mirror.version = world.version();
        let stats = UpdateStats {
            instances_changed: (instances.len() + movers.len() + user_changed.len() + posed.len()) as u64,
            bytes_uploaded: mirror.queued_bytes() - queued_before + edited_bytes,
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            gpu_ms: 0.0,
            relayout: false,
        };
        mirror.note(&stats);
        Ok(stats)
    }

    /// Keeps the world's previous instance records while some view's graph reads them (motion
    /// vectors, [`crate::graph::PassNode::reads_previous_instances`]) and only then: a view
    /// added, resized or given other settings may start or stop reading them. Made anew, they
    /// are filled with the current records at the next frame (no motion at that frame).
    pub(super) fn fit_previous_records(&mut self) -> Result<()> {
        let Some(mirror) = &mut self.world else { return Ok(()) };
        let wanted = self.views.iter().any(|view| view.graphs.runtime.reads_previous_instances());
        if wanted == self.gpu_scene.prev_instances.is_some() {
            return Ok(());
        }
        let mut scene = (*self.gpu_scene).clone();
        if wanted {
            scene.add_previous_instances(&self.ctx)?;
            mirror.refresh_previous = true;
        } else {
            scene.prev_instances = None;
        }
        let unchanged = self.views.iter().map(|_| None).collect();
        self.install_scene(Arc::new(scene), self.light_capacity, unchanged, Layout::Kept)
    }

    /// Makes the scene's buffers anew from `world`: with the slots laid out anew
    /// ([`Layout::Fresh`], culling history cleared) or as the mirror's layout has them
    /// ([`Layout::Kept`], history kept: every slot and group holds what it held). The graph is
    /// recompiled when the scene outgrew what it was compiled for.
    fn rebuild(
        &mut self,
        shaders: &ShaderCompiler,
        world: &World,
        start: Instant,
        how: Layout,
        textures_changed: bool,
    ) -> Result<UpdateStats> {
        if world.live_instances() == 0 {
            return Err(Error::Invalid("sync: the world has no instances".into()));
        }
        let mirror = self.world.as_ref().expect("a world renderer");
        let layout = match how {
            Layout::Fresh => SlotLayout::new(world.scene(), |i| world.is_live(i)),
            Layout::Kept => mirror.layout.clone(),
        };
        let mut scene = layout.slot_scene(world.scene());
        scene.lights = live_lights(world);
        let lights_outgrown = scene.lights.len() > self.light_capacity;
        // Every view's graph first, so that an error leaves all of them as they were.
        let (recompiled, scene, layout) = self.recompile_views(shaders, scene, layout, how, lights_outgrown);
        let recompiled = recompiled?;
        let mut uploads = UploadBatch::default();
        // Textures are the slowest part of an upload (resampling and mips on the CPU): they are
        // made again only when the world registered one, or when their upload has not been
        // recorded yet (the batch that holds it is replaced below).
        let reuse = !textures_changed && self.uploads.pending.is_none();
        let textures = reuse.then(|| self.gpu_scene.textures.clone());
        let mut gpu_scene =
            GpuScene::upload_with_room(&self.ctx, &scene, layout.draw_list(&scene), &mut uploads, textures)?;
        let reads_previous = self.views.iter().zip(&recompiled).any(|(view, new)| match new {
            Some((runtime, _)) => runtime.reads_previous_instances(),
            None => view.graphs.runtime.reads_previous_instances(),
        });
        if reads_previous {
            gpu_scene.add_previous_instances(&self.ctx)?;
        }
        let user_data = slot_user_data(world, &layout);
        gpu_scene.add_user_data(&self.ctx, &mut uploads, world.user_words(), &user_data)?;
        let light_capacity = with_room(scene.lights.len() as u64).max(self.light_capacity as u64) as usize;
        self.install_scene(Arc::new(gpu_scene), light_capacity, recompiled, how)?;
        let bytes = uploads.bytes();
        // A batch not recorded yet would fill the buffers being replaced: it goes unrecorded.
        self.uploads.pending = Some(uploads);
        let mirror = self.world.as_mut().expect("a world renderer");
        mirror.clear_updates();
        // The new scene's previous records are its current ones (no motion at its first frame).
        mirror.refresh_previous = true;
        mirror.last_slots.clear();
        mirror.layout = layout;
        mirror.handles = world_handles(world);
        mirror.version = world.version();
        self.scene = Arc::new(scene);
        // The pool holds the rest shape of every posed copy again, and the batch that wrote the
        // deformation data may be gone: every pose is queued anew.
        if let Some(deformer) = &mut mirror.deformer {
            deformer.forget_data();
        }
        let posed: Vec<u32> = world.posed().map(|(i, _)| i).collect();
        self.queue_poses(shaders, world, &posed)?;
        let mirror = self.world.as_mut().expect("a world renderer");
        let stats = UpdateStats {
            instances_changed: world.live_instances() as u64,
            bytes_uploaded: bytes,
            cpu_ms: start.elapsed().as_secs_f64() * 1e3,
            gpu_ms: 0.0,
            relayout: how == Layout::Fresh,
        };
        mirror.note(&stats);
        Ok(stats)
    }

    /// Queues the deformations of posed instance indices `posed` (those with a slot), and a
    /// move of each slot in place so that its cull record is derived again from the bound of
    /// its pose.
    fn queue_poses(&mut self, shaders: &ShaderCompiler, world: &World, posed: &[u32]) -> Result<()> {
        let mirror = self.world.as_mut().expect("a world renderer");
        let mut batch = None;
        for &i in posed {
            let (Some(pose), Some(placed)) = (world.pose_at(i), mirror.layout.placement_of(i)) else { continue };
            if mirror.deformer.is_none() {
                mirror.deformer = Some(super::deform::Deformer::new(&self.ctx, shaders)?);
            }
            let batch = batch.get_or_insert_with(|| self.uploads.pending.take().unwrap_or_default());
            let deformer = mirror.deformer.as_mut().expect("made above");
            deformer.queue(&self.ctx, &mut batch.edits, world.scene(), i, pose, placed.group)?;
            mirror.queue_update(move_of(&world.scene().instances[i as usize], placed))?;
        }
        if let Some(mut batch) = batch {
            batch.edits.stage(&self.ctx)?;
            self.uploads.pending = Some(batch);
        }
        Ok(())
    }

    /// Every view's graph for `scene` laid out as `layout`: recompiled where the scene outgrew
    /// what it was compiled for (or the light buffers are outgrown), with the culling history
    /// inherited when the layout is [`Layout::Kept`]; `None` where the graph still holds it.
    /// The scene and layout are handed back whatever the outcome.
    #[allow(clippy::type_complexity)]
    fn recompile_views(
        &self,
        shaders: &ShaderCompiler,
        mut scene: Scene,
        mut layout: SlotLayout,
        how: Layout,
        lights_outgrown: bool,
    ) -> (Result<Vec<Option<(crate::graph::GraphRuntime, FrameInputs)>>>, Scene, SlotLayout) {
        let mut recompiled = Vec::new();
        for view in &self.views {
            let kinds = &view.graphs.spec.kinds;
            let (counted, counted_scene, counted_layout) = quantities(kinds, scene, layout);
            (scene, layout) = (counted_scene, counted_layout);
            let counted = match counted {
                Ok(counted) => counted,
                Err(e) => return (Err(view.error(e)), scene, layout),
            };
            if lights_outgrown || outgrows(kinds, &counted, &view.graphs.compiled) {
                let needed = with_room_to_grow(kinds, &counted, &view.settings);
                let mut runtime = match build_runtime(&self.ctx, shaders, &needed, &view.graphs.spec) {
                    Ok(runtime) => runtime,
                    Err(e) => return (Err(view.error(e)), scene, layout),
                };
                if how == Layout::Kept {
                    // Slots and groups kept their indices: last frame's visibility still holds.
                    runtime.inherit_history(&view.graphs.runtime);
                }
                recompiled.push(Some((runtime, needed)));
            } else {
                recompiled.push(None);
            }
        }
        (Ok(recompiled), scene, layout)
    }

    /// Makes `gpu_scene` the scene every view reads from the next recorded frame on: each
    /// view's inputs anew (the old ones kept until the frames that use them have completed)
    /// and its recompiled graph, if any, installed.
    fn install_scene(
        &mut self,
        gpu_scene: Arc<GpuScene>,
        light_capacity: usize,
        recompiled: Vec<Option<(crate::graph::GraphRuntime, FrameInputs)>>,
        how: Layout,
    ) -> Result<()> {
        let mut inputs = Vec::with_capacity(self.views.len());
        for _ in &self.views {
            inputs.push(SceneInputs::new(&self.ctx, gpu_scene.clone(), light_capacity)?);
        }
        let (frame, last_use) = (self.frame_index, self.frame_index.saturating_sub(1));
        for ((view, runtime), inputs) in self.views.iter_mut().zip(recompiled).zip(inputs) {
            match runtime {
                Some((runtime, needed)) => view.graphs.install(runtime, needed, frame)?,
                // Slots were given out anew: last frame's visibility and draw lists name other
                // instances now.
                None if how == Layout::Fresh => view.graphs.runtime.reset_history(),
                None => {}
            }
            let old = std::mem::replace(&mut view.inputs, inputs);
            self.retired.inputs.push((last_use, old));
        }
        self.gpu_scene = gpu_scene;
        self.light_capacity = light_capacity;
        Ok(())
    }

    /// Applies what `registered` lists, and the slots opened since `slots_before`, in place
    /// ([`crate::passes::shared::scene_growth`]): only those meshes, materials, textures,
    /// groups and slots are written, on the pending batch's edits. Returns the bytes that
    /// takes, or `None` when the scene must be laid out anew from the host instead (a texture
    /// size class beyond the device's layers).
    fn grow_in_place(
        &mut self,
        shaders: &ShaderCompiler,
        world: &World,
        registered: &Registered,
        slots_before: u32,
    ) -> Result<Option<u64>> {
        let source = world.scene();
        let mirror = self.world.as_mut().expect("a world renderer");
        // The renderer's copy of the world: the registered meshes' pool ranges, the tables,
        // and the new slots (empty until the instances placed there are written).
        let copy = Arc::make_mut(&mut self.scene);
        copy.meshes.clone_from(&source.meshes);
        copy.materials.clone_from(&source.materials);
        copy.textures.clone_from(&source.textures);
        copy.vertices.resize(source.vertices.len(), Default::default());
        copy.indices.resize(source.indices.len(), 0);
        for &m in &registered.meshes {
            let mesh = &source.meshes[m as usize];
            let vertices = mesh.vertex_offset as usize..(mesh.vertex_offset + mesh.vertex_count) as usize;
            let indices = mesh.first_index as usize..(mesh.first_index + mesh.index_span()) as usize;
            copy.vertices[vertices.clone()].copy_from_slice(&source.vertices[vertices]);
            copy.indices[indices.clone()].copy_from_slice(&source.indices[indices]);
        }
        let slots = mirror.layout.slots();
        for slot in slots_before..slots {
            let contents = mirror.layout.slot_contents(slot, source);
            let empty = crate::scene::Instance { flags: crate::scene::FLAG_EMPTY_SLOT, ..contents };
            copy.instances.push(empty);
        }
        // Every view's graph before anything on the GPU changes, so that an error leaves them
        // as they were.
        let layout = std::mem::take(&mut mirror.layout);
        let scene = take_scene(&mut self.scene);
        let lights_outgrown = registered.lights_outgrown;
        let (recompiled, scene, layout) = self.recompile_views(shaders, scene, layout, Layout::Kept, lights_outgrown);
        self.scene = Arc::new(scene);
        let mirror = self.world.as_mut().expect("a world renderer");
        mirror.layout = layout;
        let recompiled = recompiled?;

        let mut batch = self.uploads.pending.take().unwrap_or_default();
        let bytes_before = batch.edits.bytes();
        let textures = if registered.textures.is_empty() && registered.materials.is_empty() {
            Some(self.gpu_scene.textures.clone())
        } else {
            self.gpu_scene
                .textures
                .updated(&self.ctx, &self.scene, &registered.textures, &mut batch.edits)?
                .map(Arc::new)
        };
        let Some(textures) = textures else {
            // The batch may hold half of these edits: the scene laid out anew replaces it.
            self.uploads.pending = Some(batch);
            return Ok(None);
        };
        let placements_moved = !textures.same_placements(&self.gpu_scene.textures);
        let meshes_changed = !registered.meshes.is_empty();
        let mut next = self.gpu_scene.grown(&self.ctx, &self.scene, textures, meshes_changed, &mut batch.edits)?;
        for &m in &registered.meshes {
            next.write_mesh(&mut batch.edits, &self.scene, m);
        }
        let mirror = self.world.as_mut().expect("a world renderer");
        let layout = &mirror.layout;
        let mut opened_any = false;
        for (g, group) in layout.groups.iter().enumerate() {
            let opened = !group.spare() && group.first_slot >= slots_before;
            let remeshed = !group.spare() && registered.meshes.binary_search(&group.key.1).is_ok();
            if opened || remeshed {
                next.write_group(&mut batch.edits, &self.scene, layout, g);
            }
            opened_any |= opened;
        }
        if opened_any {
            next.write_group_order(&mut batch.edits, layout);
        }
        next.write_slot_ids(&mut batch.edits, slots_before..slots);
        let materials: Vec<u32> = if placements_moved {
            (0..self.scene.materials.len() as u32).collect()
        } else {
            registered.materials.clone()
        };
        for m in materials {
            next.write_material(&mut batch.edits, &self.scene, m);
        }
        batch.edits.stage(&self.ctx)?;
        let bytes = batch.edits.bytes() - bytes_before;
        self.uploads.pending = Some(batch);
        // The new slots' records (empty; the instances placed there are queued after).
        for slot in slots_before..slots {
            let group = mirror.layout.group_of_slot(slot) as u32;
            mirror.queue_whole(slot, group, GpuInstance::new(&self.scene.instances[slot as usize]))?;
        }
        let light_capacity =
            if lights_outgrown { with_room(self.scene.lights.len() as u64) as usize } else { self.light_capacity };
        self.install_scene(Arc::new(next), light_capacity, recompiled, Layout::Kept)?;
        Ok(Some(bytes))
    }
}

/// Whether instances of material `a` and of material `b` fall into the same draw groups
/// ([`crate::passes::shared::face_cull::FaceCull::of`]: blending, masking, then sidedness).
fn groups_alike(a: &crate::scene::Material, b: &crate::scene::Material) -> bool {
    use crate::scene::AlphaMode;
    let masked = |m: &crate::scene::Material| matches!(m.alpha_mode, AlphaMode::Mask { .. });
    (a.alpha_mode == AlphaMode::Blend) == (b.alpha_mode == AlphaMode::Blend)
        && masked(a) == masked(b)
        && a.double_sided == b.double_sided
}

/// What a sync registered, changed or unregistered besides instances.
#[derive(Default)]
struct Registered {
    meshes: Vec<u32>,
    materials: Vec<u32>,
    textures: Vec<u32>,
    /// More lights than the light buffers hold.
    lights_outgrown: bool,
}

impl Registered {
    fn dedup(&mut self) {
        for list in [&mut self.meshes, &mut self.materials, &mut self.textures] {
            list.sort_unstable();
            list.dedup();
        }
    }

    fn is_empty(&self) -> bool {
        self.meshes.is_empty() && self.materials.is_empty() && self.textures.is_empty() && !self.lights_outgrown
    }
}

/// How [`Renderer::rebuild`] places the world's instances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    /// Laid out anew, each group in spatial order.
    Fresh,
    /// Where the renderer's layout has them.
    Kept,
}
