//! Work over many items spread over the machine's cores through rayon's pool of worker threads,
//! where a list is long enough that it pays (bulk moves of a living world and their sync).
//!
//! A bulk move writes entries of a table at random places, and two items of one list may name
//! the same entry, the later to win. [`route`] visits a list in chunks on several threads and
//! sends each item to the owner of the entry it writes, one owner per contiguous range of the
//! table; [`apply_routed`] then has each owner write its range on a thread of its own, taking its
//! items in list order. No two threads write one entry, and no lock or atomic is needed.

use rayon::prelude::*;
use std::ops::Range;

/// Below this many items per thread the work stays on fewer threads (one for a short list):
/// handing a range to a pool thread costs some microseconds, which a short list does not repay.
pub const MIN_ITEMS_PER_THREAD: usize = 1 << 10;

/// How many items ahead of the one at hand a loop asks for the memory of ([`prefetch`]): the
/// items of a bulk move hit random places of tables larger than the caches, and one at a time
/// each waits for its cache miss.
const AHEAD: usize = 16;

/// Asks the CPU to bring in the cache lines of `value` (its first and last byte: the values
/// here span at most two lines): a hint, which changes no result.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let first = (value as *const T).cast::<i8>();
        let last = first.wrapping_add(std::mem::size_of::<T>().saturating_sub(1));
        // SAFETY: `_mm_prefetch` needs SSE, which every x86-64 CPU has; a prefetch reads
        // nothing the program sees and cannot fault.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(first);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

/// The threads work is spread over at most: rayon's pool, one per core unless the embedding
/// engine configured the global pool otherwise.
pub fn threads() -> usize {
    rayon::current_num_threads()
}

/// The ranges `0..n` is cut into, one per thread: at most [`threads`], each of at least
/// [`MIN_ITEMS_PER_THREAD`] items (one range for a short list, none for an empty one).
pub fn chunks(n: usize) -> Vec<Range<usize>> {
    let count = (n / MIN_ITEMS_PER_THREAD).clamp(1, threads());
    let size = n.div_ceil(count).max(1);
    (0..count).map(|t| t * size..((t + 1) * size).min(n)).filter(|r| !r.is_empty()).collect()
}

/// Whether a list of `n` items is worth routing over several threads: long enough, and short
/// enough that an item's number fits the routes' 32 bits.
pub fn worth_routing(n: usize) -> bool {
    chunks(n).len() > 1 && u32::try_from(n).is_ok()
}

/// Who writes which entries of a table: owner `t` the entries `t * span .. (t + 1) * span`.
#[derive(Clone, Copy, Debug)]
pub struct Owners {
    span: usize,
    count: usize,
}

impl Owners {
    /// Owners of a table of `entries` entries that a list of `items` items writes: as many as
    /// the list has [`chunks`].
    pub fn new(entries: usize, items: usize) -> Self {
        let count = chunks(items).len().max(1);
        Self { span: entries.div_ceil(count).max(1), count }
    }

    fn of(&self, entry: usize) -> usize {
        (entry / self.span).min(self.count - 1)
    }
}

/// One chunk's items per owner: `(entry, item)` in list order.
type OwnerLists = Vec<Vec<(u32, u32)>>;

/// A list's items sent to the owners of the entries they write: per chunk of the list, per
/// owner, `(entry, item)` in list order.
pub struct Routed {
    lists: Vec<OwnerLists>,
    unrouted: usize,
}

impl Routed {
    /// Items that write no entry.
    #[cfg(test)]
    pub fn unrouted(&self) -> usize {
        self.unrouted
    }

    /// Appends to `out` the entries the routed items write (in no particular order), each
    /// chunk's on a thread of its own.
    pub fn append_entries(&self, out: &mut Vec<u32>) {
        let counts: Vec<usize> = self.lists.iter().map(|lists| lists.iter().map(Vec::len).sum()).collect();
        let total: usize = counts.iter().sum();
        let base = out.len();
        out.reserve(total);
        let mut rest = &mut out.spare_capacity_mut()[..total];
        let mut parts = Vec::with_capacity(counts.len());
        for &count in &counts {
            let (part, after) = rest.split_at_mut(count);
            parts.push(part);
            rest = after;
        }
        parts.into_par_iter().zip(self.lists.par_iter()).for_each(|(part, lists)| {
            for (slot, &(entry, _)) in part.iter_mut().zip(lists.iter().flatten()) {
                slot.write(entry);
            }
        });
        // SAFETY: the `total` elements after `base` were each written above: every chunk's
        // part is as long as its lists hold entries.
        unsafe { out.set_len(base + total) };
    }
}

/// Visits the items of a list, one per element of `out`, in chunks on several threads:
/// `visit(i, &mut out[i])` fills the item's output and says which entry of the owners' table the
/// item writes (`None`: none) or why the list is refused; `ahead(i)` is called some items before
/// item `i` is visited, to [`prefetch`] what its visit reads. Unless it is refused, every element
/// of `out` was visited once. The first refusal in list order is
/// returned, whichever thread meets it first. Entries are below `u32::MAX`, and so is the
/// list's length ([`worth_routing`]).
pub fn route<O: Send, E: Send>(
    out: &mut [O],
    owners: &Owners,
    ahead: impl Fn(usize) + Sync,
    visit: impl Fn(usize, &mut O) -> Result<Option<usize>, E> + Sync,
) -> Result<Routed, E> {
    let size = chunks(out.len()).first().map_or(1, |r| r.len());
    let per_chunk = |(c, part): (usize, &mut [O])| -> Result<(OwnerLists, usize), E> {
        let mut lists: OwnerLists =
            (0..owners.count).map(|_| Vec::with_capacity(part.len() / owners.count + 16)).collect();
        let mut unrouted = 0;
        let len = part.len();
        for (j, o) in part.iter_mut().enumerate() {
            let item = c * size + j;
            if j + AHEAD < len {
                ahead(item + AHEAD);
            }
            match visit(item, o)? {
                Some(entry) => lists[owners.of(entry)].push((entry as u32, item as u32)),
                None => unrouted += 1,
            }
        }
        Ok((lists, unrouted))
    };
    let chunks: Vec<_> = if out.len() <= size {
        out.chunks_mut(size).enumerate().map(per_chunk).collect()
    } else {
        out.par_chunks_mut(size).enumerate().map(per_chunk).collect()
    };
    let mut routed = Routed { lists: Vec::with_capacity(chunks.len()), unrouted: 0 };
    for chunk in chunks {
        let (lists, unrouted) = chunk?;
        routed.lists.push(lists);
        routed.unrouted += unrouted;
    }
    Ok(routed)
}

/// Has each owner, on a thread of its own, apply its routed items to its entries of `table` in
/// list order: `apply(&mut table[entry], item)`, which may say something about the item. What
/// they said, in no particular order.
pub fn apply_routed<T: Send, R: Send>(
    table: &mut [T],
    owners: &Owners,
    routed: &Routed,
    apply: impl Fn(&mut T, usize) -> Option<R> + Sync,
) -> Vec<R> {
    let span = owners.span;
    let per_owner = |(t, part): (usize, &mut [T])| -> Vec<R> {
        let mut said = Vec::new();
        for lists in &routed.lists {
            let list = &lists[t];
            for (j, &(entry, item)) in list.iter().enumerate() {
                if let Some(&(later, _)) = list.get(j + AHEAD) {
                    prefetch(&part[later as usize - t * span]);
                }
                said.extend(apply(&mut part[entry as usize - t * span], item as usize));
            }
        }
        said
    };
    if owners.count == 1 {
        return table.chunks_mut(span).enumerate().flat_map(per_owner).collect();
    }
    table.par_chunks_mut(span).enumerate().flat_map_iter(per_owner).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_every_item_once_in_order() {
        for n in [0, 1, 100, MIN_ITEMS_PER_THREAD * 3 + 7, MIN_ITEMS_PER_THREAD * 100] {
            let ranges = chunks(n);
            let flat: Vec<usize> = ranges.iter().flat_map(|r| r.clone()).collect();
            assert_eq!(flat, (0..n).collect::<Vec<_>>(), "{n}");
            assert!(ranges.iter().all(|r| r.len() >= MIN_ITEMS_PER_THREAD.min(n)), "{n}");
        }
    }

    /// A pool of at least four threads, whatever the machine's cores: routing over one owner
    /// would not test the ownership.
    fn pool() -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(4).build().expect("a pool of 4 threads")
    }

    #[test]
    fn routed_writes_leave_each_entry_its_last_item_in_list_order() {
        pool().install(|| {
            let n = MIN_ITEMS_PER_THREAD * 6 + 5;
            // Items write entries with many repeats, the table shorter than the list.
            let entry_of = |i: usize| (i * 7919) % 5003;
            let mut out = vec![0usize; n];
            let owners = Owners::new(5003, n);
            assert!(owners.count > 1 && worth_routing(n));
            let routed = route(
                &mut out,
                &owners,
                |_| {},
                |i, o| -> Result<_, ()> {
                    *o = i + 1;
                    Ok((i % 97 != 0).then(|| entry_of(i)))
                },
            )
            .expect("nothing refused");
            assert_eq!(out, (1..=n).collect::<Vec<_>>());
            assert_eq!(routed.unrouted(), n.div_ceil(97));
            // Every routed item's entry once, after what the list held.
            let mut entries = vec![u32::MAX];
            routed.append_entries(&mut entries);
            assert_eq!(entries[0], u32::MAX);
            entries[1..].sort_unstable();
            let mut expected: Vec<u32> = (0..n).filter(|i| i % 97 != 0).map(|i| entry_of(i) as u32).collect();
            expected.sort_unstable();
            assert_eq!(entries[1..], expected[..]);
            let mut table = vec![usize::MAX; 5003];
            let said = apply_routed(&mut table, &owners, &routed, |entry, item| {
                let overwritten = *entry != usize::MAX;
                *entry = item;
                overwritten.then_some(item)
            });
            let mut expected = vec![usize::MAX; 5003];
            let mut overwrites = 0;
            for i in (0..n).filter(|i| i % 97 != 0) {
                overwrites += usize::from(expected[entry_of(i)] != usize::MAX);
                expected[entry_of(i)] = i;
            }
            assert_eq!(table, expected);
            assert_eq!(said.len(), overwrites);
        });
    }

    #[test]
    fn routing_refuses_with_the_first_refusal_in_list_order() {
        pool().install(|| {
            let n = MIN_ITEMS_PER_THREAD * 8;
            let bad = [n - 3, n / 2 + 11, 5 * MIN_ITEMS_PER_THREAD + 1];
            let mut out = vec![(); n];
            let owners = Owners::new(n, n);
            let refused = route(&mut out, &owners, |_| {}, |i, _| if bad.contains(&i) { Err(i) } else { Ok(Some(i)) });
            assert_eq!(refused.err(), Some(n / 2 + 11));
        });
    }
}
