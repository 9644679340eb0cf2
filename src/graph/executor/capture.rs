//! Host copies of the draw lists the passes drew (for checking tools such as `--verify`, which
//! compares what a frame drew with what it should have): each pass whose kind declares a draw
//! list ([`crate::graph::PassKind::draw_list`]) has the buffers bound to that list's slots
//! copied right after it runs. The copies are read after the frame completed, before the next
//! frame is recorded.

use super::resources::{Physical, RuntimeResources};
use crate::gpu::{Buffer, BufferDesc, GpuContext, MemoryLocation};
use crate::graph::plan::{Binding, CompiledGraph};
use ash::vk;

/// What one capturing pass bound to the captured slots: its index in the plan and each slot's
/// bytes (`None`: the pass leaves one of the slots unbound).
pub type Captured = (usize, Option<Vec<Vec<u8>>>);

/// One drawing pass's captured list: its index, its list's slots (and its cluster list's, where
/// bound) and a host copy per slot (`None`: it leaves a slot of the list unbound).
type PassCopies = (usize, Vec<&'static str>, Option<Vec<Buffer>>);

/// Host buffers for the draw list of each drawing pass, refreshed every recorded frame.
pub struct SlotCapture {
    copies: Vec<PassCopies>,
}

impl SlotCapture {
    /// Host buffers for the draw list of every pass whose kind declares one.
    pub fn new(ctx: &GpuContext, plan: &CompiledGraph, resources: &RuntimeResources) -> crate::Result<Self> {
        let mut copies = Vec::new();
        for (i, pass) in plan.passes.iter().enumerate() {
            let Some(list) = plan.kinds.get(&pass.kind).and_then(|k| k.kind.draw_list()) else { continue };
            let find = |s: &&str| pass.bindings.iter().find(|b| b.slot == *s);
            let mut slots = list.slots.to_vec();
            for cluster in list.cluster_slots.iter().filter(|c| c.iter().all(|s| find(s).is_some())) {
                slots.extend(cluster);
            }
            let bound: Vec<_> = slots.iter().filter_map(find).collect();
            if bound.len() < slots.len() {
                copies.push((i, slots, None));
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
                        name: &format!("{} {} capture", pass.name, slots[k]),
                        size,
                        usage: vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuToCpu,
                    },
                )?)
            };
            let hosts = (0..slots.len()).map(host).collect::<crate::Result<Vec<_>>>()?;
            copies.push((i, slots, Some(hosts)));
        }
        Ok(Self { copies })
    }

    /// The bindings of pass `index`'s captured slots with the host buffers to copy them into
    /// (right after the pass); empty for passes that capture nothing.
    pub fn copies_of<'a>(
        &'a self,
        index: usize,
        bindings: &'a [Binding],
    ) -> impl Iterator<Item = (&'a Binding, &'a Buffer)> + 'a {
        let pass = self.copies.iter().find(|(i, _, _)| *i == index);
        let slots = pass.map(|(_, s, _)| s.as_slice()).unwrap_or(&[]);
        let hosts = pass.and_then(|(_, _, h)| h.as_ref());
        slots
            .iter()
            .zip(hosts.into_iter().flatten())
            .filter_map(move |(slot, host)| bindings.iter().find(|b| b.slot == *slot).map(|b| (b, host)))
    }

    /// Per capturing pass, in pass order: its index and the bytes of each captured slot as the
    /// last completed frame left them (`None`: the pass leaves one of the slots unbound).
    pub fn read(&self) -> crate::Result<Vec<Captured>> {
        self.copies
            .iter()
            .map(|(i, _, hosts)| {
                let bytes = match hosts {
                    Some(h) => Some(h.iter().map(|b| b.read_bytes().map(|s| s.to_vec())).collect::<Result<_, _>>()?),
                    None => None,
                };
                Ok((*i, bytes))
            })
            .collect()
    }
}
