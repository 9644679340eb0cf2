//! Moving data between host and device: batched uploads that anyone can record, and readbacks.

use super::barrier::{cmd_barriers, image_barrier, image_barrier_raw, memory_barrier, Access};
use super::buffer::{Buffer, BufferDesc};
use super::context::GpuContext;
use super::edits::Edits;
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
    images: Vec<ImageUpload>,
    /// Edits of resources already in use, recorded after the uploads above.
    pub edits: Edits,
}

/// Texels for an image: a staging buffer and where each part of it goes.
struct ImageUpload {
    staging: Buffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    regions: Vec<vk::BufferImageCopy>,
}

/// The state uploaded images are left in: sampled by any shader.
const SAMPLED: Access = Access {
    stage: vk::PipelineStageFlags2::ALL_COMMANDS,
    access: vk::AccessFlags2::SHADER_SAMPLED_READ,
    layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
};

/// A device-local buffer of `size` bytes that an upload copies into.
fn upload_target(ctx: &GpuContext, name: &str, usage: vk::BufferUsageFlags, size: u64) -> GpuResult<Buffer> {
    let desc =
        BufferDesc { name, size, usage: usage | vk::BufferUsageFlags::TRANSFER_DST, location: MemoryLocation::GpuOnly };
    Buffer::new(ctx, &desc)
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
        self.buffer_with_room(ctx, name, usage, data, 0)
    }

    /// As [`UploadBatch::buffer`], the buffer at least `size` bytes long (room for what is to
    /// come; the bytes past `data` are undefined).
    pub fn buffer_with_room(
        &mut self,
        ctx: &GpuContext,
        name: &str,
        usage: vk::BufferUsageFlags,
        data: &[u8],
        size: u64,
    ) -> GpuResult<Buffer> {
        let dst = upload_target(ctx, name, usage, size.max(data.len() as u64))?;
        if !data.is_empty() {
            let staging =
                Buffer::with_data(ctx, &format!("{name} (staging)"), vk::BufferUsageFlags::TRANSFER_SRC, data)?;
            self.copies.push((staging, dst.handle(), data.len() as u64));
        }
        Ok(dst)
    }

    /// As [`UploadBatch::buffer_with_room`], for `count` elements of `T` that `fill` writes
    /// straight into the staging memory, so that no host copy of them is made first (a scene's
    /// per-instance tables are as large as the scene). `fill(first, elements)` writes elements
    /// `first..first + elements.len()`; many elements are filled on several threads.
    pub fn buffer_filled<T: bytemuck::Pod + Send>(
        &mut self,
        ctx: &GpuContext,
        name: &str,
        usage: vk::BufferUsageFlags,
        count: usize,
        size: u64,
        fill: impl Fn(usize, &mut [T]) + Sync,
    ) -> GpuResult<Buffer> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        let dst = upload_target(ctx, name, usage, size.max(bytes))?;
        if bytes == 0 {
            return Ok(dst);
        }
        let desc = BufferDesc {
            name: &format!("{name} (staging)"),
            size: bytes,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::CpuToGpu,
        };
        let mut staging = Buffer::new(ctx, &desc)?;
        let fill_all = |elements: &mut [T]| {
            use rayon::prelude::*;
            // Chunks of a few pages' worth each, so that threads write whole lines.
            let chunk = (crate::parallel::MIN_ITEMS_PER_THREAD * 16).max(1);
            if elements.len() <= chunk {
                fill(0, elements);
            } else {
                elements.par_chunks_mut(chunk).enumerate().for_each(|(c, part)| fill(c * chunk, part));
            }
        };
        match bytemuck::try_cast_slice_mut::<u8, T>(staging.mapped_mut()?) {
            Ok(elements) => fill_all(elements),
            // Mapped memory is aligned far beyond any element; should it not be, one host copy.
            Err(_) => {
                let mut elements = vec![T::zeroed(); count];
                fill_all(&mut elements);
                staging.write_bytes(0, bytemuck::cast_slice(&elements))?;
            }
        }
        self.copies.push((staging, dst.handle(), bytes));
        Ok(dst)
    }

    /// Queues `data` into `image` (`range`: what it covers, left in `SHADER_READ_ONLY_OPTIMAL`
    /// for sampling), each region reading its part of `data`. The image must stay alive until
    /// the batch has executed.
    pub fn image(
        &mut self,
        ctx: &GpuContext,
        name: &str,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        data: &[u8],
        regions: Vec<vk::BufferImageCopy>,
    ) -> GpuResult<()> {
        let staging = Buffer::with_data(ctx, &format!("{name} (staging)"), vk::BufferUsageFlags::TRANSFER_SRC, data)?;
        self.images.push(ImageUpload { staging, image, range, regions });
        Ok(())
    }

    /// True when nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.copies.is_empty() && self.images.is_empty() && self.edits.is_empty()
    }

    /// Bytes queued for upload.
    pub fn bytes(&self) -> u64 {
        self.copies.iter().map(|c| c.2).sum::<u64>()
            + self.images.iter().map(|i| i.staging.size()).sum::<u64>()
            + self.edits.bytes()
    }

    /// Records the copies and a barrier that orders them before every later access (read or
    /// write: an uploaded buffer may be a counter that shaders update).
    pub fn record(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        self.record_uploads(ctx, cmd);
        self.edits.record(ctx, cmd);
    }

    fn record_uploads(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        if self.copies.is_empty() && self.images.is_empty() {
            return;
        }
        let device = ctx.device();
        if !self.images.is_empty() {
            let undefined = Access {
                stage: vk::PipelineStageFlags2::NONE,
                access: vk::AccessFlags2::NONE,
                layout: vk::ImageLayout::UNDEFINED,
            };
            let to_dst: Vec<_> = self
                .images
                .iter()
                .map(|i| image_barrier_raw(i.image, i.range, undefined, Access::TRANSFER_WRITE))
                .collect();
            cmd_barriers(device, cmd, &[], &to_dst);
            for upload in &self.images {
                // SAFETY: the staging buffer holds every region; the image is in TRANSFER_DST.
                unsafe {
                    device.cmd_copy_buffer_to_image(
                        cmd,
                        upload.staging.handle(),
                        upload.image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &upload.regions,
                    )
                };
            }
            let to_sampled: Vec<_> = self
                .images
                .iter()
                .map(|i| image_barrier_raw(i.image, i.range, Access::TRANSFER_WRITE, SAMPLED))
                .collect();
            cmd_barriers(device, cmd, &[], &to_sampled);
        }
        if self.copies.is_empty() {
            return;
        }
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
    pub fn submit_and_wait(mut self, ctx: &GpuContext) -> GpuResult<()> {
        self.edits.stage(ctx)?;
        if self.is_empty() {
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

/// Records a copy of mip 0 of a color image, or of the depth aspect of a depth image (in `state`,
/// left in `state`), into `dst`, tightly packed.
pub fn record_image_to_buffer(ctx: &GpuContext, cmd: vk::CommandBuffer, image: &Image, state: Access, dst: &Buffer) {
    let device = ctx.device();
    cmd_barriers(device, cmd, &[], &[image_barrier(image, state, Access::TRANSFER_READ)]);
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            // A copy takes one aspect: of a depth-stencil image, its depth.
            aspect_mask: if image.aspect().contains(vk::ImageAspectFlags::DEPTH) {
                vk::ImageAspectFlags::DEPTH
            } else {
                image.aspect()
            },
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
