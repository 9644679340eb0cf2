//! Headless frames that do not wait for each other: while the GPU executes up to
//! [`FRAMES_IN_FLIGHT`] frames, the next one is recorded and submitted, and a frame's figures
//! (counters and timestamps, through the executor's per-frame host buffers) are read once its
//! fence has signalled, which is when its command buffer comes round again, `FRAMES_IN_FLIGHT`
//! frames later. The CLI renders this way; [`Renderer::render`] waits for every frame instead, and
//! an engine that embeds the renderer uses its own command buffers and fences the same way.

use super::renderer::Renderer;
use crate::error::Result;
use crate::gpu::error::VkResultExt;
use crate::gpu::GpuContext;
use crate::graph::executor::FRAMES_IN_FLIGHT;
use crate::scene::Camera;
use crate::stats::FrameStats;
use ash::vk;
use std::time::Instant;

/// One command buffer and fence per frame in flight, and the frame each last carried.
pub struct FramePipeline {
    ctx: GpuContext,
    pool: vk::CommandPool,
    slots: Vec<Slot>,
    /// The slot the next frame goes to.
    next: usize,
}

struct Slot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// The frame submitted with this slot whose figures have not been read yet, and how long
    /// recording it took on the CPU.
    pending: Option<(u64, f64)>,
}

impl FramePipeline {
    /// Command buffers and fences for [`FRAMES_IN_FLIGHT`] frames on `ctx`'s queue.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let device = ctx.device();
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family())
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: plain object creation on a valid device; destroyed in Drop (or below on error).
        let pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let mut pipeline = Self { ctx: ctx.clone(), pool, slots: Vec::new(), next: 0 };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(FRAMES_IN_FLIGHT as u32);
        // SAFETY: the pool was created above on this device.
        let buffers = unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?;
        for cmd in buffers {
            // Signalled, so that the first wait on each slot returns at once.
            let info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
            // SAFETY: as above; Drop destroys the fences.
            let fence = unsafe { device.create_fence(&info, None) }.vk("vkCreateFence")?;
            pipeline.slots.push(Slot { cmd, fence, pending: None });
        }
        Ok(pipeline)
    }

    /// Records `camera`'s frame and submits it without waiting for it. First waits for the frame
    /// submitted `FRAMES_IN_FLIGHT` frames ago, if any, and returns its figures: they come back
    /// that many frames late.
    pub fn submit(&mut self, renderer: &mut Renderer, camera: &Camera) -> Result<Option<FrameStats>> {
        self.submit_with(renderer, camera, &[], &[])
    }

    /// Like [`FramePipeline::submit`], the frame waiting on the host's `wait` semaphores before it
    /// executes and signalling `signal` once it has, binary or timeline (`value`), at the stages
    /// each names: how a host orders its own queue work, or another queue's, around cullgraph's
    /// frames. The host keeps the semaphores alive until the frame has executed.
    pub fn submit_with(
        &mut self,
        renderer: &mut Renderer,
        camera: &Camera,
        wait: &[vk::SemaphoreSubmitInfo<'_>],
        signal: &[vk::SemaphoreSubmitInfo<'_>],
    ) -> Result<Option<FrameStats>> {
        let done = self.collect(self.next, renderer)?;
        let device = self.ctx.device();
        let slot = &mut self.slots[self.next];
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the slot's last submission has executed (its fence was waited on in collect),
        // so its command buffer may be reset and recorded again.
        unsafe {
            device.reset_command_buffer(slot.cmd, vk::CommandBufferResetFlags::empty()).vk("vkResetCommandBuffer")?;
            device.begin_command_buffer(slot.cmd, &begin).vk("vkBeginCommandBuffer")?;
        }
        let start = Instant::now();
        let recorded = renderer.record(slot.cmd, camera);
        let record_ms = start.elapsed().as_secs_f64() * 1e3;
        // SAFETY: the command buffer is recording; it is ended even when recording failed.
        let ended = unsafe { device.end_command_buffer(slot.cmd) }.vk("vkEndCommandBuffer");
        let frame = recorded?;
        ended?;
        // SAFETY: the fence is signalled and no submission uses it (waited on in collect).
        unsafe { device.reset_fences(&[slot.fence]) }.vk("vkResetFences")?;
        let cmd_info = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let info = vk::SubmitInfo2::default()
            .wait_semaphore_infos(wait)
            .command_buffer_infos(&cmd_info)
            .signal_semaphore_infos(signal);
        self.ctx.submit(&info, slot.fence)?;
        slot.pending = Some((frame, record_ms));
        self.next = (self.next + 1) % self.slots.len();
        Ok(done)
    }

    /// Waits for every frame still executing and returns their figures, oldest first.
    pub fn finish(&mut self, renderer: &Renderer) -> Result<Vec<FrameStats>> {
        let mut out = Vec::new();
        for k in 0..self.slots.len() {
            // From the oldest submission on: the slot the next frame would take.
            let slot = (self.next + k) % self.slots.len();
            out.extend(self.collect(slot, renderer)?);
        }
        Ok(out)
    }

    /// Waits for `slot`'s last frame and reads its figures, once.
    fn collect(&mut self, slot: usize, renderer: &Renderer) -> Result<Option<FrameStats>> {
        let slot = &mut self.slots[slot];
        profiling::scope!("cullgraph::wait_gpu");
        // SAFETY: the fence belongs to this device.
        unsafe { self.ctx.device().wait_for_fences(&[slot.fence], true, u64::MAX) }.vk("vkWaitForFences")?;
        let Some((frame, record_ms)) = slot.pending.take() else { return Ok(None) };
        let mut stats = renderer.completed_stats(frame)?;
        stats.cpu_record_ms = record_ms;
        Ok(Some(stats))
    }
}

impl Drop for FramePipeline {
    fn drop(&mut self) {
        let device = self.ctx.device();
        let fences: Vec<vk::Fence> = self.slots.iter().map(|s| s.fence).collect();
        // SAFETY: waiting for the slots' own submissions before their objects are destroyed.
        unsafe {
            let _ = device.wait_for_fences(&fences, true, u64::MAX);
            for fence in fences {
                device.destroy_fence(fence, None);
            }
            device.destroy_command_pool(self.pool, None);
        }
    }
}
