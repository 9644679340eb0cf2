//! The barrier plan (synchronization2): before each pass, one barrier per resource version that
//! needs one, derived from the uses of that version within the frame in execution order.
//!
//! The uses of one resource version are cut into segments: each write is a segment of its own;
//! consecutive reads with the same image layout form one read segment. A barrier goes before the
//! first pass of every segment:
//!
//! - first segment of the frame: `src: None` (the executor knows what last touched the memory:
//!   last frame, the host, or a resource aliased with this one), `discard` when the first use does
//!   not read;
//! - after a write: a memory dependency from the write's stage and access (read-after-write,
//!   write-after-write), with the layout change if any;
//! - a write after a read segment: an execution dependency on the readers' stages (no access:
//!   write-after-read needs no memory dependency, and the write before the reads was already made
//!   available by the barrier before them), with the layout change if any;
//! - a read segment after a read segment: only when the layout changes (it always does, or they
//!   would be one segment): an execution dependency on the earlier readers plus the transition.
//!
//! The barrier before a read segment waits for *all* of its readers' stages and accesses, so the
//! later reads of the segment need no barrier of their own (read after read, same layout).

use crate::gpu::Access;
use crate::graph::plan::{PlannedBarrier, ResourceId, Version};
use crate::graph::usage::Usage;
use crate::graph::validated::ValidatedGraph;
use ash::vk;
use std::collections::BTreeMap;

/// One use of a resource version.
#[derive(Clone, Copy, Debug)]
struct UseAt {
    /// Execution position.
    pos: usize,
    usage: Usage,
}

/// The barriers before each pass (indexed by execution position), in the order of the pass's
/// bindings. `is_image[r]` tells images from buffers (buffers have no layouts).
pub fn plan_barriers(graph: &ValidatedGraph, order: &[usize], is_image: &[bool]) -> Vec<Vec<PlannedBarrier>> {
    let mut uses: BTreeMap<(ResourceId, Version), Vec<UseAt>> = BTreeMap::new();
    for (pos, &p) in order.iter().enumerate() {
        for b in &graph.passes[p].bindings {
            uses.entry((b.resource, b.version)).or_default().push(UseAt { pos, usage: b.usage });
        }
    }
    let mut at: BTreeMap<(usize, ResourceId, Version), PlannedBarrier> = BTreeMap::new();
    for (&(resource, version), list) in &uses {
        for (pos, barrier) in barriers_of(resource, version, list, is_image[resource]) {
            at.insert((pos, resource, version), barrier);
        }
    }
    order
        .iter()
        .enumerate()
        .map(|(pos, &p)| {
            graph.passes[p].bindings.iter().filter_map(|b| at.remove(&(pos, b.resource, b.version))).collect()
        })
        .collect()
}

fn layout(usage: Usage, image: bool) -> vk::ImageLayout {
    if image {
        usage.access().layout
    } else {
        vk::ImageLayout::UNDEFINED
    }
}

fn access(usage: Usage, image: bool) -> Access {
    Access { layout: layout(usage, image), ..usage.access() }
}

/// Barriers of one resource version: (execution position, barrier).
fn barriers_of(resource: ResourceId, version: Version, uses: &[UseAt], image: bool) -> Vec<(usize, PlannedBarrier)> {
    let mut out = Vec::new();
    // The previous segment: its (src) access for the next barrier.
    let mut prev: Option<Access> = None;
    let mut i = 0;
    while i < uses.len() {
        let first = uses[i];
        let (dst, next_i, src_after) = if first.usage.writes() {
            let a = access(first.usage, image);
            (a, i + 1, a)
        } else {
            let l = layout(first.usage, image);
            let mut j = i;
            let mut dst = Access { stage: vk::PipelineStageFlags2::NONE, access: vk::AccessFlags2::NONE, layout: l };
            while j < uses.len() && !uses[j].usage.writes() && layout(uses[j].usage, image) == l {
                let a = uses[j].usage.access();
                dst.stage |= a.stage;
                dst.access |= a.access;
                j += 1;
            }
            // Later barriers wait for these readers (execution dependency only).
            let src_after = Access { access: vk::AccessFlags2::NONE, ..dst };
            (dst, j, src_after)
        };
        out.push((
            first.pos,
            PlannedBarrier { resource, version, src: prev, dst, discard: prev.is_none() && !first.usage.reads() },
        ));
        prev = Some(src_after);
        i = next_i;
    }
    out
}
