//! Copies of the draw lists the draw passes consumed (for `--verify`): which instances a frame
//! actually drew. A checking tool: the copies are read after the frame completed, before the
//! next frame is recorded.

use super::resources::{Physical, RuntimeResources};
use crate::gpu::{Buffer, BufferDesc, GpuContext, MemoryLocation};
use crate::graph::kinds::builtin_kinds;
use crate::graph::plan::PlannedPass;
use crate::render::face_cull::DrawRegions;
use crate::render::gpu_types::DrawIndexedIndirect;
use ash::vk;

/// The draw-list slots of a draw pass.
const SLOTS: [&str; 3] = ["draw_commands", "draw_count", "draw_instance_ids"];

/// What one draw pass drew.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DrawnInstances {
    /// The scene's unculled list: every instance.
    All,
    /// These instance ids (in draw order).
    Some(Vec<u32>),
}

/// Host copies of each draw pass's list, refreshed every recorded frame.
pub struct DrawCapture {
    /// Per pass index: host copies of commands, count and ids (None: the pass draws everything).
    copies: Vec<(usize, Option<[Buffer; 3]>)>,
}

impl DrawCapture {
    /// Host buffers for every draw pass of `passes` (kinds that take a draw list).
    pub fn new(ctx: &GpuContext, passes: &[PlannedPass], resources: &RuntimeResources) -> crate::Result<Self> {
        // Draw passes read a draw list (cull passes write one).
        let draw_kinds: Vec<&str> = builtin_kinds()
            .into_iter()
            .filter(|k| k.reads.iter().any(|s| s.name == "draw_instance_ids"))
            .map(|k| k.name)
            .collect();
        let mut copies = Vec::new();
        for (i, pass) in passes.iter().enumerate() {
            if !draw_kinds.contains(&pass.kind.as_str()) {
                continue;
            }
            let bound: Vec<_> = SLOTS.iter().filter_map(|s| pass.bindings.iter().find(|b| b.slot == *s)).collect();
            if bound.len() < SLOTS.len() {
                copies.push((i, None));
                continue;
            }
            let host = |k: usize| -> crate::Result<Buffer> {
                let size = match resources.index(bound[k].resource, bound[k].version, 0).map(|p| resources.get(p)) {
                    Some(Physical::Buffer(b)) => b.size(),
                    _ => 16,
                };
                Ok(Buffer::new(
                    ctx,
                    &BufferDesc {
                        name: &format!("{} {} capture", pass.name, SLOTS[k]),
                        size,
                        usage: vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuToCpu,
                    },
                )?)
            };
            copies.push((i, Some([host(0)?, host(1)?, host(2)?])));
        }
        Ok(Self { copies })
    }

    /// The bindings of pass `index`'s draw list with the host buffers to copy them into
    /// (right after the pass); empty for passes that draw everything or are not draw passes.
    pub fn copies_of<'a>(
        &'a self,
        index: usize,
        pass: &'a PlannedPass,
    ) -> impl Iterator<Item = (&'a crate::graph::plan::Binding, &'a Buffer)> + 'a {
        let hosts = self.copies.iter().find(|(i, _)| *i == index).and_then(|(_, h)| h.as_ref());
        SLOTS
            .iter()
            .zip(hosts.into_iter().flatten())
            .filter_map(move |(slot, host)| pass.bindings.iter().find(|b| b.slot == *slot).map(|b| (b, host)))
    }

    /// What each draw pass drew in the last completed frame, in pass order (command lists laid
    /// out in `regions`).
    pub fn drawn(&self, regions: &DrawRegions) -> crate::Result<Vec<DrawnInstances>> {
        self.copies
            .iter()
            .map(|(_, hosts)| {
                let Some([commands, count, ids]) = hosts else { return Ok(DrawnInstances::All) };
                // Whole elements only: a graph may size a buffer to any number of bytes.
                let commands: Vec<DrawIndexedIndirect> = whole(commands.read_bytes()?);
                let counts: Vec<u32> = whole(count.read_bytes()?);
                let ids: Vec<u32> = whole(ids.read_bytes()?);
                let mut out = Vec::new();
                for c in regions.drawn(&commands, &counts) {
                    let start = c.first_instance as usize;
                    let end = (start + c.instance_count as usize).min(ids.len());
                    out.extend_from_slice(&ids[start.min(end)..end]);
                }
                Ok(DrawnInstances::Some(out))
            })
            .collect()
    }
}

/// The whole `T`s at the start of `bytes` (a trailing partial one is left out).
fn whole<T: bytemuck::Pod>(bytes: &[u8]) -> Vec<T> {
    bytes.chunks_exact(std::mem::size_of::<T>()).map(bytemuck::pod_read_unaligned).collect()
}
