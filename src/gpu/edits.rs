//! Changes to resources that frames already use: bytes written at an offset of a live buffer,
//! a live buffer copied into its larger successor, texture layers written or carried over into
//! a larger array. What a changing world records instead of uploading its scene again.
//!
//! The edits are recorded in the order they were queued, so that a write queued after a growth
//! lands in the grown buffer, and a growth queued after a write carries it. Earlier frames may
//! still read what an edit overwrites: the first edit waits for every earlier command, and the
//! last one is waited for by every later command.

use super::barrier::{cmd_barriers, image_barrier_raw, memory_barrier, Access};
use super::buffer::Buffer;
use super::context::GpuContext;
use super::error::GpuResult;
use super::texture_array::TextureArray;
use ash::vk;
use std::collections::HashSet;
use std::sync::Arc;

/// A sampled texture array, as every frame leaves it.
const SAMPLED: Access = Access {
    stage: vk::PipelineStageFlags2::ALL_COMMANDS,
    access: vk::AccessFlags2::SHADER_SAMPLED_READ,
    layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
};

/// Whatever earlier commands did with a buffer.
const ANY: Access = Access {
    stage: vk::PipelineStageFlags2::ALL_COMMANDS,
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::MEMORY_READ.as_raw() | vk::AccessFlags2::MEMORY_WRITE.as_raw(),
    ),
    layout: vk::ImageLayout::UNDEFINED,
};

/// Where an edit's bytes wait: a staged chunk, or the bytes not staged yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Chunk {
    Staged(usize),
    Open,
}

enum Edit {
    /// `size` bytes from `chunk` at `src_offset` into `dst` at `dst_offset`.
    Write { chunk: Chunk, src_offset: u64, dst: vk::Buffer, dst_offset: u64, size: u64 },
    /// The first `size` bytes of `src` into `dst` (a buffer outgrown by its successor).
    Carry { src: Arc<Buffer>, dst: vk::Buffer, size: u64 },
    /// Every layer and mip of `src` (if any) into the first layers of `dst` (of the same side,
    /// more layers, undefined until now: every layer of it is left sampled).
    CarryLayers { src: Option<Arc<TextureArray>>, dst: vk::Image, dst_range: vk::ImageSubresourceRange },
    /// Texels from `chunk` into `layers` of `image` (sampled before and after), one region per
    /// mip, their offsets relative to `src_offset`.
    WriteLayers {
        chunk: Chunk,
        src_offset: u64,
        image: vk::Image,
        layers: vk::ImageSubresourceRange,
        regions: Vec<vk::BufferImageCopy>,
    },
}

/// Edits of live resources, in order; see the module documentation.
#[derive(Default)]
pub struct Edits {
    edits: Vec<Edit>,
    /// Staging buffers the writes read from.
    staged: Vec<Buffer>,
    /// Bytes of writes queued since the last [`Edits::stage`].
    open: Vec<u8>,
    /// Bytes staged in all.
    bytes: u64,
}

impl Edits {
    /// Queues `data` written into `dst` at `offset` (which must hold it).
    pub fn write(&mut self, dst: &Buffer, offset: u64, data: &[u8]) {
        if data.is_empty() {
            return;
        }
        debug_assert!(offset + data.len() as u64 <= dst.size(), "a write past the end of '{}'", dst.name());
        let src_offset = self.open.len() as u64;
        self.open.extend_from_slice(data);
        self.edits.push(Edit::Write {
            chunk: Chunk::Open,
            src_offset,
            dst: dst.handle(),
            dst_offset: offset,
            size: data.len() as u64,
        });
    }

    /// Queues the first `size` bytes of `src` copied into `dst`, its successor; `src` is kept
    /// until the edits have executed.
    pub fn carry(&mut self, src: Arc<Buffer>, dst: &Buffer, size: u64) {
        if size > 0 {
            self.edits.push(Edit::Carry { src, dst: dst.handle(), size: size.min(dst.size()) });
        }
    }

    /// Queues every layer of `src` (if any) copied into the first layers of `dst` (same side,
    /// at least as many layers, never sampled yet); every layer of `dst` is left ready to
    /// sample, so that its views can be bound before the layers beyond `src`'s are written.
    pub fn carry_layers(&mut self, src: Option<Arc<TextureArray>>, dst: &TextureArray) {
        debug_assert!(src.as_ref().is_none_or(|s| s.size() == dst.size() && s.layers() <= dst.layers()));
        self.edits.push(Edit::CarryLayers { src, dst: dst.handle(), dst_range: dst.range() });
    }

    /// Queues `chain` (one layer's whole mip chain, mip 0 first, tightly packed RGBA8) written
    /// into `layer` of `array`.
    pub fn write_layer(&mut self, array: &TextureArray, layer: u32, chain: &[u8]) {
        let src_offset = self.open.len() as u64;
        self.open.extend_from_slice(chain);
        let regions = array.layer_regions(layer, 0);
        let layers = array.range().base_array_layer(layer).layer_count(1);
        self.edits.push(Edit::WriteLayers { chunk: Chunk::Open, src_offset, image: array.handle(), layers, regions });
    }

    /// Puts the bytes of the writes queued since the last call into a staging buffer: due
    /// before [`Edits::record`].
    pub fn stage(&mut self, ctx: &GpuContext) -> GpuResult<()> {
        if self.open.is_empty() {
            return Ok(());
        }
        let staging = Buffer::with_data(ctx, "scene edits (staging)", vk::BufferUsageFlags::TRANSFER_SRC, &self.open)?;
        let chunk = Chunk::Staged(self.staged.len());
        self.staged.push(staging);
        self.bytes += self.open.len() as u64;
        self.open.clear();
        for edit in &mut self.edits {
            match edit {
                Edit::Write { chunk: c, .. } | Edit::WriteLayers { chunk: c, .. } if *c == Chunk::Open => *c = chunk,
                _ => {}
            }
        }
        Ok(())
    }

    /// True when nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.edits.is_empty()
    }

    /// Bytes staged for writes (carries move none from the host).
    pub fn bytes(&self) -> u64 {
        self.bytes + self.open.len() as u64
    }

    /// Records the edits in order (see the module documentation). Writes not staged yet are
    /// left out: [`Edits::stage`] comes first.
    pub fn record(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        if self.edits.is_empty() {
            return;
        }
        debug_assert!(self.open.is_empty(), "scene edits recorded before they were staged");
        let device = ctx.device();
        let transfer = Access {
            stage: vk::PipelineStageFlags2::ALL_TRANSFER,
            access: vk::AccessFlags2::TRANSFER_READ | vk::AccessFlags2::TRANSFER_WRITE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        cmd_barriers(device, cmd, &[memory_barrier(ANY, transfer)], &[]);
        // Buffers written since the last barrier: an edit that touches one again waits.
        let mut touched: HashSet<vk::Buffer> = HashSet::new();
        let wait_if = |touched: &mut HashSet<vk::Buffer>, buffers: &[vk::Buffer]| {
            if buffers.iter().any(|b| touched.contains(b)) {
                cmd_barriers(device, cmd, &[memory_barrier(transfer, transfer)], &[]);
                touched.clear();
            }
        };
        for edit in &self.edits {
            match edit {
                Edit::Write { chunk: Chunk::Staged(chunk), src_offset, dst, dst_offset, size } => {
                    wait_if(&mut touched, &[*dst]);
                    let region = vk::BufferCopy { src_offset: *src_offset, dst_offset: *dst_offset, size: *size };
                    // SAFETY: the staging chunk holds the bytes; dst is live and holds the range
                    // (checked when queued); cmd is recording.
                    unsafe { device.cmd_copy_buffer(cmd, self.staged[*chunk].handle(), *dst, &[region]) };
                    touched.insert(*dst);
                }
                Edit::Carry { src, dst, size } => {
                    wait_if(&mut touched, &[src.handle(), *dst]);
                    let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: *size };
                    // SAFETY: both buffers are live and at least `size` long; cmd is recording.
                    unsafe { device.cmd_copy_buffer(cmd, src.handle(), *dst, &[region]) };
                    touched.insert(*dst);
                }
                Edit::CarryLayers { src: None, dst, dst_range } => {
                    cmd_barriers(device, cmd, &[], &[image_barrier_raw(*dst, *dst_range, Access::NONE, SAMPLED)]);
                }
                Edit::CarryLayers { src: Some(src), dst, dst_range } => {
                    let before = [
                        image_barrier_raw(src.handle(), src.range(), SAMPLED, Access::TRANSFER_READ),
                        image_barrier_raw(*dst, *dst_range, Access::NONE, Access::TRANSFER_WRITE),
                    ];
                    cmd_barriers(device, cmd, &[], &before);
                    let regions: Vec<vk::ImageCopy> = (0..src.mip_levels())
                        .map(|mip| {
                            let layers = vk::ImageSubresourceLayers::default()
                                .aspect_mask(vk::ImageAspectFlags::COLOR)
                                .mip_level(mip)
                                .base_array_layer(0)
                                .layer_count(src.layers());
                            let side = (src.size() >> mip).max(1);
                            vk::ImageCopy::default()
                                .src_subresource(layers)
                                .dst_subresource(layers)
                                .extent(vk::Extent3D { width: side, height: side, depth: 1 })
                        })
                        .collect();
                    // SAFETY: both images are live, in the layouts just set, with the same
                    // side and mip chain; dst has at least src's layers.
                    unsafe {
                        device.cmd_copy_image(
                            cmd,
                            src.handle(),
                            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                            *dst,
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            &regions,
                        )
                    };
                    let after = [
                        image_barrier_raw(src.handle(), src.range(), Access::TRANSFER_READ, SAMPLED),
                        image_barrier_raw(*dst, *dst_range, Access::TRANSFER_WRITE, SAMPLED),
                    ];
                    cmd_barriers(device, cmd, &[], &after);
                }
                Edit::WriteLayers { chunk: Chunk::Staged(chunk), src_offset, image, layers, regions } => {
                    // Frames before may sample the layer: its old texels are discarded after them.
                    let discard = Access { layout: vk::ImageLayout::UNDEFINED, ..SAMPLED };
                    cmd_barriers(
                        device,
                        cmd,
                        &[],
                        &[image_barrier_raw(*image, *layers, discard, Access::TRANSFER_WRITE)],
                    );
                    let regions: Vec<vk::BufferImageCopy> =
                        regions.iter().map(|r| r.buffer_offset(r.buffer_offset + src_offset)).collect();
                    // SAFETY: the chunk holds every region; the layer is in TRANSFER_DST.
                    unsafe {
                        device.cmd_copy_buffer_to_image(
                            cmd,
                            self.staged[*chunk].handle(),
                            *image,
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            &regions,
                        )
                    };
                    cmd_barriers(
                        device,
                        cmd,
                        &[],
                        &[image_barrier_raw(*image, *layers, Access::TRANSFER_WRITE, SAMPLED)],
                    );
                }
                Edit::Write { chunk: Chunk::Open, .. } | Edit::WriteLayers { chunk: Chunk::Open, .. } => {}
            }
        }
        cmd_barriers(device, cmd, &[memory_barrier(transfer, ANY)], &[]);
    }
}
