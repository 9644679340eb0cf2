//! What each drawing pass drew in a frame, read from the draw lists the runtime captured
//! ([`crate::graph::GraphRuntime::capture_draw_lists`]) as each pass's kind says to read its
//! list ([`crate::graph::DrawList`]).

use crate::graph::{CompiledGraph, DrawOrder};
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::GpuScene;

/// What one draw pass drew.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DrawnInstances {
    /// The scene's unculled list: every instance.
    All,
    /// These instance ids (in draw order).
    Some(Vec<u32>),
}

/// The instances each capturing pass of `plan` drew, in pass order, from what the runtime
/// captured.
pub(crate) fn drawn(
    plan: &CompiledGraph,
    scene: &GpuScene,
    captured: Vec<crate::graph::Captured>,
) -> Vec<DrawnInstances> {
    captured
        .into_iter()
        .map(|(pass, lists)| {
            let order = plan
                .passes
                .get(pass)
                .and_then(|p| plan.kinds.get(&p.kind))
                .and_then(|k| k.kind.draw_list())
                .map_or(DrawOrder::Regions, |l| l.order);
            drawn_instances(scene, lists, order)
        })
        .collect()
}

/// The instances a draw pass's captured list (commands, counts, ids, and each cluster list's
/// commands and counts where bound) drew; `None`: the pass binds no list and draws the scene's
/// unculled one. A list in regions has its opaque regions drawn; a sorted list its first
/// `count` commands; a cluster list its regions' surviving clusters (an instance drawn by
/// several clusters counts once).
fn drawn_instances(scene: &GpuScene, lists: Option<Vec<Vec<u8>>>, order: DrawOrder) -> DrawnInstances {
    let Some(mut lists) = lists.filter(|l| l.len() >= 3 && l.len() % 2 == 1) else {
        return DrawnInstances::All;
    };
    let cluster_lists: Vec<Vec<u8>> = lists.split_off(3);
    let Ok([commands, counts, ids]) = <[Vec<u8>; 3]>::try_from(lists) else {
        return DrawnInstances::All;
    };
    // Whole elements only: a graph may size a buffer to any number of bytes.
    let commands: Vec<DrawIndexedIndirect> = whole(&commands);
    let counts: Vec<u32> = whole(&counts);
    let ids: Vec<u32> = whole(&ids);
    let mut out = Vec::new();
    let drawn: Box<dyn Iterator<Item = &DrawIndexedIndirect>> = match order {
        DrawOrder::Sorted => Box::new(commands.iter().take(counts.first().copied().unwrap_or(0) as usize)),
        DrawOrder::Regions => Box::new(scene.regions.drawn(&commands, &counts)),
    };
    for c in drawn {
        let start = c.first_instance as usize;
        let end = (start + c.instance_count as usize).min(ids.len());
        out.extend_from_slice(&ids[start.min(end)..end]);
    }
    if !cluster_lists.is_empty() {
        let mut seen: std::collections::HashSet<u32> = out.iter().copied().collect();
        for pair in cluster_lists.chunks_exact(2) {
            let drawn = crate::passes::cluster_cull::clusters_drawn(&ids, &pair[0], &pair[1]);
            out.extend(drawn.into_iter().map(|(id, _)| id).filter(|&id| seen.insert(id)));
        }
    }
    DrawnInstances::Some(out)
}

/// The whole `T`s at the start of `bytes` (a trailing partial one is left out).
fn whole<T: bytemuck::Pod>(bytes: &[u8]) -> Vec<T> {
    bytes.chunks_exact(std::mem::size_of::<T>()).map(bytemuck::pod_read_unaligned).collect()
}

/// The clusters the capturing passes drew through cluster lists (`cluster_cull`'s), as
/// (instance id, first index of the cluster's range), in pass order (what verification checks).
#[cfg(feature = "verify")]
pub(crate) fn drawn_clusters(captured: &[crate::graph::Captured]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for (_, lists) in captured {
        let Some(lists) = lists.as_ref().filter(|l| l.len() >= 5 && l.len() % 2 == 1) else { continue };
        let ids = whole(&lists[2]);
        for pair in lists[3..].chunks_exact(2) {
            out.extend(crate::passes::cluster_cull::clusters_drawn(&ids, &pair[0], &pair[1]));
        }
    }
    out
}
