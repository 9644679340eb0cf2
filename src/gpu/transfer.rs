//! Moving data between host and device: batched uploads that anyone can record, and readbacks.

use super::barrier::{cmd_barriers, image_barrier, memory_barrier, Access};
use super::buffer::{Buffer, BufferDesc};
use super::context::GpuContext;
use super::error::GpuResult;
use super::image::Image;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// Uploads waiting to be recorded: device-local buffers plus the staging copies that fill them.
///
/// The batch does not submit anything itself: [`UploadBatch::record`] puts the copies into any
/// command buffer (the host engine's, when embedded), and the batch must stay alive until that
/// command buffer has executed. [`UploadBatch::submit_and_wait`] is the headless shortcut.
#[derive(Default)]
pub struct UploadBatch {
    copies: Vec<(Buffer, vk::Buffer, u64)>,
}

impl UploadBatch {
    /// Creates a device-local buffer of `data.len()` bytes and queues its upload.
    pub fn buffer(
        &mut self,
        ctx: &GpuContext,
        name: &str,
        usage: vk::BufferUsageFlags,
        data: &[u8],
    ) -> GpuResult<Buffer> {
        let size = data.len() as u64;
        let dst = Buffer::new(
            ctx,
            &BufferDesc {
                name,
                size,
                usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        if size > 0 {
            let staging =
                Buffer::with_data(ctx, &format!("{name} (staging)"), vk::BufferUsageFlags::TRANSFER_SRC, data)?;
            self.copies.push((staging, dst.handle(), size));
        }
        Ok(dst)
    }

    /// True when nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.copies.is_empty()
    }

    /// Bytes queued for upload.
    pub fn bytes(&self) -> u64 {
        self.copies.iter().map(|c| c.2).sum()
    }

    /// Records the copies and a barrier that orders them before every later access (read or
    /// write: an uploaded buffer may be a counter that shaders update).
    pub fn record(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        if self.copies.is_empty() {
            return;
        }
        let device = ctx.device();
        for (staging, dst, size) in &self.copies {
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: *size };
            // SAFETY: both buffers are live and large enough; cmd is recording.
            unsafe { device.cmd_copy_buffer(cmd, staging.handle(), *dst, &[region]) };
        }
        let after = Access {
            stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::from_raw(
                vk::AccessFlags2::MEMORY_READ.as_raw() | vk::AccessFlags2::MEMORY_WRITE.as_raw(),
            ),
            layout: vk::ImageLayout::UNDEFINED,
        };
        cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, after)], &[]);
    }

    /// Records, submits and waits (headless use only).
    pub fn submit_and_wait(self, ctx: &GpuContext) -> GpuResult<()> {
        if self.copies.is_empty() {
            return Ok(());
        }
        ctx.submit_and_wait(|cmd| {
            self.record(ctx, cmd);
            GpuResult::Ok(())
        })
    }
}

/// Copies a device buffer back to the host, waiting for the GPU (headless and tests only).
pub fn read_buffer(ctx: &GpuContext, buffer: &Buffer) -> GpuResult<Vec<u8>> {
    let staging = Buffer::new(
        ctx,
        &BufferDesc {
            name: "readback",
            size: buffer.size(),
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        },
    )?;
    if buffer.size() > 0 {
        ctx.submit_and_wait(|cmd| {
            let device = ctx.device();
            let all = Access {
                stage: vk::PipelineStageFlags2::ALL_COMMANDS,
                access: vk::AccessFlags2::MEMORY_WRITE,
                layout: vk::ImageLayout::UNDEFINED,
            };
            cmd_barriers(device, cmd, &[memory_barrier(all, Access::TRANSFER_READ)], &[]);
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: buffer.size() };
            // SAFETY: both buffers live; cmd recording.
            unsafe { device.cmd_copy_buffer(cmd, buffer.handle(), staging.handle(), &[region]) };
            cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)], &[]);
            GpuResult::Ok(())
        })?;
    }
    Ok(staging.read_bytes()?.to_vec())
}

/// Records a copy of mip 0 of a color image (in `state`, left in `state`) into `dst`, tightly packed.
pub fn record_image_to_buffer(ctx: &GpuContext, cmd: vk::CommandBuffer, image: &Image, state: Access, dst: &Buffer) {
    let device = ctx.device();
    cmd_barriers(device, cmd, &[], &[image_barrier(image, state, Access::TRANSFER_READ)]);
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: image.aspect(),
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D { width: image.extent().width, height: image.extent().height, depth: 1 });
    // SAFETY: image in TRANSFER_SRC layout, dst large enough (caller contract).
    unsafe {
        device.cmd_copy_image_to_buffer(
            cmd,
            image.handle(),
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            dst.handle(),
            &[region],
        )
    };
    cmd_barriers(
        device,
        cmd,
        &[memory_barrier(Access::TRANSFER_WRITE, Access::HOST_READ)],
        &[image_barrier(image, Access::TRANSFER_READ, state)],
    );
}

/// Host-visible staging memory reused frame after frame for scattered updates of device
/// buffers: writes are gathered on the host, and each frame copies them through its own
/// segment (one per frame in flight, so a frame never overwrites what an executing one reads),
/// which grows geometrically when a frame needs more and is otherwise never reallocated.
pub struct StagingRing {
    segments: Vec<Option<Buffer>>,
    /// Bytes waiting for the next frame.
    data: Vec<u8>,
    /// Per destination buffer, its copies (source offsets into `data`).
    copies: Vec<(vk::Buffer, Vec<vk::BufferCopy>)>,
}

impl StagingRing {
    /// A ring for `frames` frames in flight.
    pub fn new(frames: usize) -> Self {
        Self { segments: (0..frames.max(1)).map(|_| None).collect(), data: Vec::new(), copies: Vec::new() }
    }

    /// Queues `bytes` for `dst` at `offset` (in bytes) for the next recorded frame.
    pub fn write(&mut self, dst: &Buffer, offset: u64, bytes: &[u8]) {
        let src_offset = self.data.len() as u64;
        self.data.extend_from_slice(bytes);
        let region = vk::BufferCopy { src_offset, dst_offset: offset, size: bytes.len() as u64 };
        match self.copies.iter_mut().find(|(b, _)| *b == dst.handle()) {
            Some((_, regions)) => regions.push(region),
            None => self.copies.push((dst.handle(), vec![region])),
        }
    }

    /// Bytes queued for the next frame.
    pub fn bytes(&self) -> u64 {
        self.data.len() as u64
    }

    /// Forgets what is queued (the buffers it was meant for were replaced).
    pub fn clear(&mut self) {
        self.data.clear();
        self.copies.clear();
    }

    /// Records the queued copies for frame `frame` into `cmd`: after every earlier use of their
    /// destinations, before every later one. The segment of `frame` must be free: the frame
    /// that last used it (`frame - frames in flight`) has completed. The queue is kept until
    /// [`StagingRing::clear`], so that a frame whose recording failed can be recorded again.
    pub fn record(&mut self, ctx: &GpuContext, cmd: vk::CommandBuffer, frame: u64) -> GpuResult<()> {
        if self.copies.is_empty() {
            return Ok(());
        }
        let k = (frame % self.segments.len() as u64) as usize;
        let need = self.data.len() as u64;
        let current = self.segments[k].as_ref().map_or(0, |b| b.size());
        if current < need {
            let size = need.max(current * 2).max(64 << 10);
            let desc = BufferDesc {
                name: &format!("staging ring {k}"),
                size,
                usage: vk::BufferUsageFlags::TRANSFER_SRC,
                location: MemoryLocation::CpuToGpu,
            };
            self.segments[k] = Some(Buffer::new(ctx, &desc)?);
        }
        let segment = self.segments[k].as_mut().expect("sized above");
        segment.write_bytes(0, &self.data)?;
        let device = ctx.device();
        let all = Access {
            stage: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::from_raw(
                vk::AccessFlags2::MEMORY_READ.as_raw() | vk::AccessFlags2::MEMORY_WRITE.as_raw(),
            ),
            layout: vk::ImageLayout::UNDEFINED,
        };
        // Earlier frames may still read or write what these copies overwrite.
        cmd_barriers(device, cmd, &[memory_barrier(all, Access::TRANSFER_WRITE)], &[]);
        for (dst, regions) in &self.copies {
            // SAFETY: the segment holds every source range and each destination range lies in
            // its buffer (the caller's offsets); cmd is recording.
            unsafe { device.cmd_copy_buffer(cmd, segment.handle(), *dst, regions) };
        }
        cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, all)], &[]);
        Ok(())
    }
}
