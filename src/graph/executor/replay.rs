//! Frames recorded once and replayed: when nothing that decides a frame's commands has changed
//! since the frame in flight slot was last recorded, the runtime executes that slot's
//! secondary command buffer again instead of recording every pass (recording costs the host
//! microseconds per pass; replaying one call). A host that interleaves several runtimes'
//! passes in one frame (cullgraph's renderer, for several views) keeps such frames whole the
//! same way, from each runtime's key ([`super::GraphRuntime::replay_key`]) and what each was
//! left with ([`RecordedFrame`]).
//!
//! What decides the commands, and so the [`ReplayKey`]: the host's word on its shared data
//! ([`super::FrameData::replay_key`]: for cullgraph's renderer, which scene buffers and
//! which frame slot of constants and lights), the output size, the settings the nodes took
//! live, step timing, every node's own state ([`super::PassNode::replay_state`]) and what the
//! executor knew of every resource before the frame (the barriers' sources and layouts). A
//! frame with captures, a pass that reads timings, or history to clear is never replayed, nor
//! one with imports that no key vouches for ([`super::FrameData::import_key`]): the views made
//! of an imported image are kept only for images vouched for (cullgraph's renderer vouches for
//! its shadow maps and the user data it imports, and for the engine's images where the engine
//! does, [`super::Imports::vouched`], its replay key then covering the resources imported).
//! The camera and the lights change nothing here: they live in the slot's buffers, which the
//! host writes before every frame.
//!
//! A recording is kept per frame modulo [`SLOTS`]: a frame's commands name its slot of frames
//! in flight (timestamps, counters) and which copy of each history resource is this frame's
//! (they alternate). A slot's buffer is recorded again only once the frame that last executed
//! it has completed (at most [`FRAMES_IN_FLIGHT`] frames execute at once), and is recorded
//! for simultaneous use, since the engine's primary command buffers that executed it may still
//! be pending re-execution.

use super::tracker::Tracker;
use super::FRAMES_IN_FLIGHT;
use crate::gpu::error::VkResultExt;
use crate::gpu::GpuContext;
use ash::vk;

/// Recordings kept: one per frame modulo frames in flight and the two copies of history.
pub(crate) const SLOTS: usize = 2 * FRAMES_IN_FLIGHT;

/// Everything that decides a frame's commands beyond the plan (see the module's text).
#[derive(Clone, PartialEq)]
pub(crate) struct ReplayKey {
    pub shared: u64,
    /// The host's word on the images it imports ([`super::FrameData::import_key`]): a frame
    /// that imports new images never replays one that named the views of older ones.
    pub imports: Option<u64>,
    /// Kept wrappers of imported images made or retired so far (`GraphRuntime::bind_imports`).
    pub wrappers: u64,
    pub extent: (u32, u32),
    pub settings: u64,
    pub step_timing: bool,
    pub nodes: Vec<u64>,
    pub before: Tracker,
}

/// What a runtime's frame left behind once recorded: what the executor knows of every resource
/// after it, and the scopes its timestamps time (another slot may share its timer since).
#[derive(Clone)]
pub(crate) struct RecordedFrame {
    pub after: Tracker,
    pub scopes: Vec<String>,
}

/// A slot's recording: its key, and what the frame left behind.
pub(super) struct Recorded {
    pub key: ReplayKey,
    pub frame: RecordedFrame,
}

/// One secondary command buffer per slot ([`SLOTS`]), and what each holds (`R`: its key and
/// whatever replaying it must restore).
pub(crate) struct Replays<R> {
    ctx: GpuContext,
    pool: vk::CommandPool,
    buffers: Vec<vk::CommandBuffer>,
    recorded: Vec<Option<R>>,
}

impl<R> Replays<R> {
    pub fn new(ctx: &GpuContext) -> crate::Result<Self> {
        let device = ctx.device();
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family())
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: plain object creation on a valid device; destroyed in Drop (or below).
        let pool = unsafe { device.create_command_pool(&info, None) }.vk("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::SECONDARY)
            .command_buffer_count(SLOTS as u32);
        // SAFETY: the pool was created above on this device.
        match unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers") {
            Ok(buffers) => Ok(Self { ctx: ctx.clone(), pool, buffers, recorded: (0..SLOTS).map(|_| None).collect() }),
            Err(e) => {
                // SAFETY: nothing was allocated from the pool.
                unsafe { device.destroy_command_pool(pool, None) };
                Err(e.into())
            }
        }
    }

    /// What slot `slot` holds, if it holds a whole recording.
    pub fn get(&self, slot: usize) -> Option<&R> {
        self.recorded[slot].as_ref()
    }

    /// Forgets what slot `slot` holds: a frame of that slot was recorded without being kept,
    /// and may have rewritten host data its recording reads.
    pub fn forget(&mut self, slot: usize) {
        self.recorded[slot] = None;
    }

    /// Executes slot `slot`'s recording in `cmd`.
    pub fn execute(&self, cmd: vk::CommandBuffer, slot: usize) {
        // SAFETY: cmd is a primary command buffer recording outside a render pass; the
        // secondary was recorded whole for simultaneous use and its resources live as long as
        // the runtime.
        unsafe { self.ctx.device().cmd_execute_commands(cmd, &[self.buffers[slot]]) };
    }

    /// Starts recording slot `slot` anew (forgetting what it held) and returns its buffer.
    pub fn begin(&mut self, slot: usize) -> crate::Result<vk::CommandBuffer> {
        self.recorded[slot] = None;
        let inheritance = vk::CommandBufferInheritanceInfo::default();
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::SIMULTANEOUS_USE)
            .inheritance_info(&inheritance);
        // SAFETY: the frame that last executed this buffer (SLOTS frames ago) has completed (at
        // most FRAMES_IN_FLIGHT frames execute at once), so it may be reset; its pool allows it.
        unsafe { self.ctx.device().begin_command_buffer(self.buffers[slot], &begin) }.vk("vkBeginCommandBuffer")?;
        Ok(self.buffers[slot])
    }

    /// Ends slot `slot`'s recording; `recorded`: what it holds, when the frame was recorded
    /// whole and may be replayed.
    pub fn end(&mut self, slot: usize, recorded: Option<R>) -> crate::Result<()> {
        // SAFETY: the buffer is recording (begun above).
        unsafe { self.ctx.device().end_command_buffer(self.buffers[slot]) }.vk("vkEndCommandBuffer")?;
        self.recorded[slot] = recorded;
        Ok(())
    }
}

impl<R> Drop for Replays<R> {
    fn drop(&mut self) {
        // SAFETY: the runtime is dropped only once the frames that executed its recordings have
        // completed; destroying the pool frees its buffers.
        unsafe { self.ctx.device().destroy_command_pool(self.pool, None) };
    }
}
