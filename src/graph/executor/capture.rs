//! Host copies of the buffers some passes read through named slots (for checking tools such as
//! `--verify`, which reads the draw lists a frame consumed). The copies are read after the frame
//! completed, before the next frame is recorded.

use super::resources::{Physical, RuntimeResources};
use crate::gpu::{Buffer, BufferDesc, GpuContext, MemoryLocation};
use crate::graph::plan::{Binding, CompiledGraph};
use ash::vk;

/// What one capturing pass bound to the captured slots: its index in the plan and each slot's
/// bytes (`None`: the pass leaves one of the slots unbound).
pub type Captured = (usize, Option<Vec<Vec<u8>>>);

/// Host buffers for the captured slots of each capturing pass, refreshed every recorded frame.
pub struct SlotCapture {
    slots: Vec<&'static str>,
    /// Per capturing pass: its index and a host copy per slot (None: it leaves a slot unbound).
    copies: Vec<(usize, Option<Vec<Buffer>>)>,
}

impl SlotCapture {
    /// Host buffers for `slots` of every pass whose kind reads all of them.
    pub fn new(
        ctx: &GpuContext,
        plan: &CompiledGraph,
        resources: &RuntimeResources,
        slots: &[&'static str],
    ) -> crate::Result<Self> {
        let mut copies = Vec::new();
        for (i, pass) in plan.passes.iter().enumerate() {
            let Some(kind) = plan.kinds.info(&pass.kind) else { continue };
            if !slots.iter().all(|s| kind.reads.iter().any(|r| r.name == *s)) {
                continue;
            }
            let bound: Vec<_> = slots.iter().filter_map(|s| pass.bindings.iter().find(|b| b.slot == *s)).collect();
            if bound.len() < slots.len() {
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
                        name: &format!("{} {} capture", pass.name, slots[k]),
                        size,
                        usage: vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuToCpu,
                    },
                )?)
            };
            copies.push((i, Some((0..slots.len()).map(host).collect::<crate::Result<Vec<_>>>()?)));
        }
        Ok(Self { slots: slots.to_vec(), copies })
    }

    /// The bindings of pass `index`'s captured slots with the host buffers to copy them into
    /// (right after the pass); empty for passes that capture nothing.
    pub fn copies_of<'a>(
        &'a self,
        index: usize,
        bindings: &'a [Binding],
    ) -> impl Iterator<Item = (&'a Binding, &'a Buffer)> + 'a {
        let hosts = self.copies.iter().find(|(i, _)| *i == index).and_then(|(_, h)| h.as_ref());
        self.slots
            .iter()
            .zip(hosts.into_iter().flatten())
            .filter_map(move |(slot, host)| bindings.iter().find(|b| b.slot == *slot).map(|b| (b, host)))
    }

    /// Per capturing pass, in pass order: its index and the bytes of each captured slot as the
    /// last completed frame left them (`None`: the pass leaves one of the slots unbound).
    pub fn read(&self) -> crate::Result<Vec<Captured>> {
        self.copies
            .iter()
            .map(|(i, hosts)| {
                let bytes = match hosts {
                    Some(h) => Some(h.iter().map(|b| b.read_bytes().map(|s| s.to_vec())).collect::<Result<_, _>>()?),
                    None => None,
                };
                Ok((*i, bytes))
            })
            .collect()
    }
}
