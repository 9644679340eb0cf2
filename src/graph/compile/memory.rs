//! Transient memory aliasing: resources whose lifetimes do not overlap share memory.
//!
//! [`plan_memory`] is a pure function of sizes, alignments, lifetimes and heap classes, so the
//! compiler uses it with estimates from formats and the executor again with the device's real
//! memory requirements. Greedy placement: largest first (ties: larger alignment, then lower
//! index), each at the lowest aligned offset that does not overlap, in memory, any already placed
//! item of the same heap class whose lifetime overlaps its own.

use super::resolve::Resolved;
use crate::graph::formats;
use crate::graph::plan::Placement;

/// Alignment the compiler assumes for images (the executor uses the device's).
pub const IMAGE_ALIGNMENT: u64 = 64 * 1024;
/// Alignment the compiler assumes for buffers.
pub const BUFFER_ALIGNMENT: u64 = 256;
/// Heap class of images in the compiler's estimate.
pub const IMAGE_HEAP_CLASS: u32 = 0;
/// Heap class of buffers in the compiler's estimate.
pub const BUFFER_HEAP_CLASS: u32 = 1;

/// An item placed in a heap: offset, end, lifetime.
type Placed = (u64, u64, (usize, usize));

/// One resource to place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryItem {
    /// Bytes.
    pub size: u64,
    /// Required alignment of its offset (0 or 1: none).
    pub alignment: u64,
    /// First and last execution position that uses it (inclusive).
    pub lifetime: (usize, usize),
    /// Items of different classes never share a heap (images vs buffers, memory types).
    pub heap_class: u32,
}

/// Places `items` (`None`: not placed, e.g. not transient). Returns one placement per item and
/// the size of each heap; heap `i` holds the `i`-th smallest heap class that occurs.
pub fn plan_memory(items: &[Option<MemoryItem>]) -> (Vec<Option<Placement>>, Vec<u64>) {
    let mut classes: Vec<u32> = items.iter().flatten().map(|i| i.heap_class).collect();
    classes.sort_unstable();
    classes.dedup();
    let mut order: Vec<usize> = (0..items.len()).filter(|&i| items[i].is_some()).collect();
    let key = |i: usize| items[i].map_or((0, 0), |m| (m.size, m.alignment));
    order.sort_by(|&a, &b| key(b).cmp(&key(a)).then(a.cmp(&b)));
    let mut placements: Vec<Option<Placement>> = vec![None; items.len()];
    let mut heaps = vec![0u64; classes.len()];
    let mut heap_align = vec![1u64; classes.len()];
    // Placed items per heap.
    let mut placed: Vec<Vec<Placed>> = vec![Vec::new(); classes.len()];
    for i in order {
        let Some(item) = items[i] else { continue };
        let heap = classes.binary_search(&item.heap_class).unwrap_or(0);
        let align = item.alignment.max(1);
        let mut conflicts: Vec<(u64, u64)> = placed[heap]
            .iter()
            .filter(|(_, _, l)| l.0 <= item.lifetime.1 && item.lifetime.0 <= l.1)
            .map(|(o, e, _)| (*o, *e))
            .collect();
        conflicts.sort_unstable();
        let mut offset = 0u64;
        if item.size > 0 {
            for (start, end) in conflicts {
                if end <= offset || start == end {
                    continue;
                }
                if offset.saturating_add(item.size) <= start {
                    break;
                }
                offset = end.div_ceil(align).saturating_mul(align);
            }
        }
        let end = offset.saturating_add(item.size);
        placed[heap].push((offset, end, item.lifetime));
        heaps[heap] = heaps[heap].max(end);
        heap_align[heap] = heap_align[heap].max(align);
        placements[i] = Some(Placement { heap, offset });
    }
    // A heap is allocated in whole alignment units, as each resource alone would be: with
    // nothing to alias, "with" and "without aliasing" then agree.
    for (size, align) in heaps.iter_mut().zip(&heap_align) {
        *size = size.div_ceil(*align).saturating_mul(*align);
    }
    (placements, heaps)
}

/// The compiler's estimate of a resource's memory: texel bytes x width x height x samples,
/// summed over the mip chain, for images (64 KiB aligned, heap class 0); the size for buffers
/// (256-byte aligned, heap class 1).
pub fn estimate(resource: &Resolved, lifetime: (usize, usize)) -> MemoryItem {
    match *resource {
        Resolved::Image { format, extent, mips, samples } => {
            let texel = formats::info(format).map_or(4, |f| f.bytes) as u64;
            let texels: u64 = (0..mips.max(1))
                .map(|l| ((extent.width >> l).max(1) as u64) * ((extent.height >> l).max(1) as u64))
                .sum();
            MemoryItem {
                size: texels * texel * samples.max(1) as u64,
                alignment: IMAGE_ALIGNMENT,
                lifetime,
                heap_class: IMAGE_HEAP_CLASS,
            }
        }
        Resolved::Buffer(size) => {
            MemoryItem { size, alignment: BUFFER_ALIGNMENT, lifetime, heap_class: BUFFER_HEAP_CLASS }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(size: u64, lifetime: (usize, usize)) -> Option<MemoryItem> {
        Some(MemoryItem { size, alignment: 256, lifetime, heap_class: 0 })
    }

    #[test]
    fn disjoint_lifetimes_share_memory() {
        let (p, heaps) = plan_memory(&[item(1000, (0, 1)), item(1000, (2, 3)), item(500, (1, 2)), None]);
        assert_eq!(p[0], Some(Placement { heap: 0, offset: 0 }));
        assert_eq!(p[1], Some(Placement { heap: 0, offset: 0 }));
        assert_eq!(p[2], Some(Placement { heap: 0, offset: 1024 }));
        assert_eq!(p[3], None);
        assert_eq!(heaps, vec![1536], "1524 rounded up to whole 256-byte units");
    }

    #[test]
    fn fills_gaps_between_placed_items() {
        let items = [item(4096, (0, 0)), item(1000, (1, 1)), item(1000, (1, 1)), item(1000, (0, 1))];
        let (p, heaps) = plan_memory(&items);
        assert_eq!(p[0].map(|p| p.offset), Some(0));
        assert_eq!(p[3].map(|p| p.offset), Some(4096));
        assert_eq!(p[1].map(|p| p.offset), Some(0));
        assert_eq!(p[2].map(|p| p.offset), Some(1024));
        assert_eq!(heaps, vec![5120], "5096 rounded up to whole 256-byte units");
    }
}

#[cfg(test)]
mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
    #[test]
    fn memory_placement_never_overlaps_live_items(
        items in prop::collection::vec(
            prop::option::weighted(0.9, (1u64..5000, prop::sample::select(vec![1u64, 4, 256, 4096]), 0usize..8, 0usize..4, 0u32..2)),
            0..24,
        )
    ) {
        let items: Vec<Option<MemoryItem>> = items
            .into_iter()
            .map(|i| i.map(|(size, alignment, start, len, heap_class)| MemoryItem {
                size,
                alignment,
                lifetime: (start, start + len),
                heap_class,
            }))
            .collect();
        let (placements, heaps) = plan_memory(&items);
        prop_assert_eq!(placements.len(), items.len());
        for (i, (item, p)) in items.iter().zip(&placements).enumerate() {
            let (Some(item), Some(p)) = (item, p) else {
                prop_assert!(item.is_none() && p.is_none());
                continue;
            };
            prop_assert_eq!(p.offset % item.alignment, 0);
            prop_assert!(p.offset + item.size <= heaps[p.heap]);
            for (j, (other, q)) in items.iter().zip(&placements).enumerate() {
                let (Some(other), Some(q)) = (other, q) else { continue };
                if i == j {
                    continue;
                }
                if other.heap_class == item.heap_class {
                    prop_assert_eq!(p.heap, q.heap);
                } else {
                    prop_assert!(p.heap != q.heap);
                }
                let live = item.lifetime.0 <= other.lifetime.1 && other.lifetime.0 <= item.lifetime.1;
                if p.heap == q.heap && live {
                    prop_assert!(p.offset + item.size <= q.offset || q.offset + other.size <= p.offset);
                }
            }
        }
        // Each placement adds at most its size plus alignment padding to the heaps, and each
        // heap is rounded up to whole units of its largest alignment.
        let max_align = items.iter().flatten().map(|i| i.alignment.max(1)).max().unwrap_or(1);
        let bound: u64 = items.iter().flatten().map(|i| i.size + i.alignment - 1).sum::<u64>()
            + heaps.len() as u64 * max_align;
        prop_assert!(heaps.iter().sum::<u64>() <= bound);
    }
    }
}
