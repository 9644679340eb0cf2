//! The slot updates a world renderer applies at its next frame (moves and every other change of
//! a slot), written by [`Renderer::sync`] straight into host-visible memory that the frame's
//! scatter (`shaders/world/scatter.comp`) reads: an update costs one 72-byte write on the host,
//! with no queue copied at record time.
//!
//! Sync runs before the frame it feeds is recorded, while the [`FRAMES_IN_FLIGHT`] frames
//! before it may still be executing (the host waits for the oldest only before recording the
//! next one): the ring has one part more than frames in flight, so the part written now was
//! last read by the frame recorded `FRAMES_IN_FLIGHT + 1` frames ago, which had completed
//! before the last frame was recorded. A part is a list of chunks: a sync that
//! finds the part full takes a new, larger chunk rather than copying what earlier syncs of the
//! frame wrote (reading back write-combined memory is slow), and the part keeps only its largest
//! chunk once its frame has completed.
//!
//! An update superseded before its frame (by a later update of its slot) stays where it is with
//! its slot set to [`DROPPED`], which the scatter skips: rewriting the list would read it back.
//!
//! [`Renderer::sync`]: super::Renderer::sync

use crate::error::Result;
use crate::gpu::{Buffer, BufferDesc, GpuContext, MemoryLocation};
use crate::graph::FRAMES_IN_FLIGHT;

/// A slot's new instance record with the slot and its draw group, as
/// `shaders/world/scatter.comp` reads it (72 bytes), the cull bound being derived on the GPU. A
/// move carries the whole record too (the material and flags, and the group, cost the host no
/// more than the memory its transform is read from), so that the scatter reads nothing of the
/// slot's old records, and moves and other changes go in one list and one dispatch.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct SlotUpdate {
    pub rows: [[f32; 4]; 3],
    pub translation_lo: [f32; 3],
    pub slot: u32,
    pub group: u32,
    /// As [`GpuInstance::material_flags`](crate::passes::shared::gpu_types::GpuInstance).
    pub material_flags: u32,
}

impl SlotUpdate {
    /// An update that the scatter skips ([`DROPPED`]).
    pub const DROPPED: SlotUpdate =
        SlotUpdate { rows: [[0.0; 4]; 3], translation_lo: [0.0; 3], slot: DROPPED, group: 0, material_flags: 0 };
}

/// The slot of an update that was superseded before its frame: the scatter skips it.
pub(super) const DROPPED: u32 = u32::MAX;

/// Parts of the ring: one more than frames in flight (see the module's text).
const PARTS: usize = FRAMES_IN_FLIGHT + 1;

/// The fewest updates a chunk holds (72 KiB).
const MIN_CHUNK: usize = 1024;

/// Host-visible memory holding `capacity` updates, the first `len` of them written.
struct Chunk {
    buffer: Buffer,
    len: usize,
    capacity: usize,
}

impl Chunk {
    fn updates(&mut self) -> &mut [SlotUpdate] {
        let bytes = self.buffer.mapped_mut().expect("update chunks are host-visible");
        &mut bytemuck::cast_slice_mut(bytes)[..self.capacity]
    }
}

/// The slot updates of the next frame, in ring memory the GPU reads.
pub(super) struct UpdateRing {
    ctx: GpuContext,
    parts: Vec<Vec<Chunk>>,
    /// The part the next frame reads.
    current: usize,
    /// Updates written to the current part, over all its chunks.
    len: usize,
    /// The slot of every update written to the current part, dropped ones included (4 bytes an
    /// update, read on the host: which slots the frame updates).
    slots: Vec<u32>,
}

impl UpdateRing {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            ctx: ctx.clone(),
            parts: (0..PARTS).map(|_| Vec::new()).collect(),
            current: 0,
            len: 0,
            slots: Vec::new(),
        }
    }

    /// Updates written for the next frame (dropped ones included).
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The slots the written updates name (some [`DROPPED`] ones among them once superseded).
    pub fn slots(&self) -> &[u32] {
        &self.slots
    }

    /// Makes room for `n` more updates in one chunk, so that writing them cannot fail.
    pub fn reserve(&mut self, n: usize) -> Result<()> {
        let part = &mut self.parts[self.current];
        if part.last().is_none_or(|c| c.capacity - c.len < n) {
            let held: usize = part.iter().map(|c| c.capacity).sum();
            let capacity = n.max(held).max(MIN_CHUNK);
            let name = format!("world slot updates {}.{}", self.current, part.len());
            let desc = BufferDesc {
                name: &name,
                size: (capacity * std::mem::size_of::<SlotUpdate>()) as u64,
                usage: ash::vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::CpuToGpu,
            };
            part.push(Chunk { buffer: Buffer::new(&self.ctx, &desc)?, len: 0, capacity });
        }
        Ok(())
    }

    /// Room for `n` more updates in one chunk: the index the first gets, and the memory to write
    /// them to (every element must be written, its slot added with [`UpdateRing::note_slots`]).
    pub fn room(&mut self, n: usize) -> Result<(usize, &mut [SlotUpdate])> {
        self.reserve(n)?;
        let part = &mut self.parts[self.current];
        let chunk = part.last_mut().expect("a chunk with room");
        let start = chunk.len;
        chunk.len += n;
        let base = self.len;
        self.len += n;
        Ok((base, &mut chunk.updates()[start..start + n]))
    }

    /// Records the slots of updates just written through [`UpdateRing::room`] on several threads:
    /// those `routed` sends to their owners.
    pub fn note_slots(&mut self, routed: &crate::parallel::Routed) {
        routed.append_entries(&mut self.slots);
    }

    /// Writes one update at the end; returns its index.
    pub fn push(&mut self, update: SlotUpdate) -> Result<usize> {
        let (at, room) = self.room(1)?;
        room[0] = update;
        self.slots.push(update.slot);
        Ok(at)
    }

    /// The update at `index` (of this frame's), to overwrite or to drop; never read back.
    pub fn at(&mut self, index: usize) -> &mut SlotUpdate {
        let mut start = 0;
        for chunk in &mut self.parts[self.current] {
            if index < start + chunk.len {
                return &mut chunk.updates()[index - start];
            }
            start += chunk.len;
        }
        panic!("update {index} is beyond the {} written", self.len)
    }

    /// The chunks holding the next frame's updates, and how many each holds.
    pub fn chunks(&self) -> impl Iterator<Item = (&Buffer, usize)> + '_ {
        self.parts[self.current].iter().filter(|c| c.len > 0).map(|c| (&c.buffer, c.len))
    }

    /// Forgets the updates written for the next frame (its memory is not in use yet).
    pub fn clear(&mut self) {
        for chunk in &mut self.parts[self.current] {
            chunk.len = 0;
        }
        self.len = 0;
        self.slots.clear();
    }

    /// The next frame was recorded: later updates go to the next part, whose frame has completed.
    pub fn advance(&mut self) {
        self.current = (self.current + 1) % PARTS;
        let part = &mut self.parts[self.current];
        // Its largest chunk holds what the syncs of a frame needed lately.
        if part.len() > 1 {
            let largest = part.iter().enumerate().max_by_key(|(_, c)| c.capacity).map(|(i, _)| i).unwrap_or(0);
            let kept = part.swap_remove(largest);
            *part = vec![kept];
        }
        self.len = 0;
        self.slots.clear();
        for chunk in part {
            chunk.len = 0;
        }
    }
}
