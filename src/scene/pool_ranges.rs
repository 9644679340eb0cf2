//! Free ranges of a pool (the vertex or the index pool of a live world): a removed mesh's range
//! is given back, neighbouring free ranges merge, and a registration takes the smallest free
//! range that fits (best fit) before the pool grows. Best fit with merging keeps the pool
//! within a small factor of what is live under any sequence of registrations and removals of
//! similar sizes (`tests` below and `tests/world_churn.rs` measure it).

use std::collections::{BTreeMap, BTreeSet};

/// The free ranges of a pool `len` entries long.
#[derive(Clone, Debug, Default)]
pub struct PoolRanges {
    /// Free ranges by start: length.
    by_start: BTreeMap<u32, u32>,
    /// The same ranges by (length, start), for best fit.
    by_len: BTreeSet<(u32, u32)>,
    /// Entries in the pool (free or not).
    len: u32,
}

impl PoolRanges {
    /// The ranges of a pool whose `len` entries are all in use.
    pub fn new(len: u32) -> Self {
        Self { len, ..Default::default() }
    }

    /// Entries in the pool, free or not.
    pub fn len(&self) -> u32 {
        self.len
    }

    /// Whether the pool has no entries.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Free entries.
    pub fn free(&self) -> u32 {
        self.by_start.values().sum()
    }

    /// Where `count` entries go: the start of the smallest free range that holds them, or the
    /// pool's end (the pool then grows by `count`). `None` when the pool would pass `u32::MAX`.
    pub fn take(&mut self, count: u32) -> Option<u32> {
        if count == 0 {
            return Some(0);
        }
        if let Some(&(len, start)) = self.by_len.range((count, 0)..).next() {
            self.remove(start, len);
            if len > count {
                self.insert(start + count, len - count);
            }
            return Some(start);
        }
        // The free range at the end, if any, is extended.
        let tail = self.by_start.last_key_value().map(|(&s, &l)| (s, l)).filter(|&(s, l)| s + l == self.len);
        let start = match tail {
            Some((s, l)) => {
                self.remove(s, l);
                s
            }
            None => self.len,
        };
        self.len = start.checked_add(count)?;
        Some(start)
    }

    /// Gives back `count` entries from `start` (a range [`PoolRanges::take`] gave), merging it
    /// with free neighbours.
    pub fn give_back(&mut self, start: u32, count: u32) {
        if count == 0 {
            return;
        }
        let (mut start, mut count) = (start, count);
        if let Some((&s, &l)) = self.by_start.range(..start).next_back() {
            if s + l == start {
                self.remove(s, l);
                start = s;
                count += l;
            }
        }
        if let Some(&l) = self.by_start.get(&(start + count)) {
            self.remove(start + count, l);
            count += l;
        }
        self.insert(start, count);
    }

    fn insert(&mut self, start: u32, len: u32) {
        self.by_start.insert(start, len);
        self.by_len.insert((len, start));
    }

    fn remove(&mut self, start: u32, len: u32) {
        self.by_start.remove(&start);
        self.by_len.remove(&(len, start));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn best_fit_and_merging() {
        let mut p = PoolRanges::new(0);
        let a = p.take(10).unwrap();
        let b = p.take(5).unwrap();
        let c = p.take(20).unwrap();
        assert_eq!((a, b, c, p.len()), (0, 10, 15, 35));
        p.give_back(a, 10);
        p.give_back(c, 20);
        // The smallest range that fits: a's, not c's.
        assert_eq!(p.take(4), Some(0));
        // c's range is at the end: a larger request extends it instead of appending.
        assert_eq!(p.take(30), Some(15));
        assert_eq!(p.len(), 45);
        p.give_back(b, 5);
        // b merged with what is left of a: 6 + 5 entries from 4.
        assert_eq!(p.take(11), Some(4));
        assert_eq!(p.free(), 0);
    }

    proptest! {
        /// Under churn of meshes of up to 1,000 entries with at most 50 live at once, the pool
        /// stays within the live entries plus a bounded slack, and no two live ranges overlap.
        #[test]
        fn churn_stays_bounded(ops in proptest::collection::vec((any::<bool>(), 1u32..1000, any::<prop::sample::Index>()), 1..3000)) {
            let mut p = PoolRanges::new(0);
            let mut live: Vec<(u32, u32)> = Vec::new();
            for (add, size, which) in ops {
                if add && live.len() < 50 {
                    let start = p.take(size).unwrap();
                    prop_assert!(live.iter().all(|&(s, n)| start + size <= s || s + n <= start));
                    live.push((start, size));
                } else if !live.is_empty() {
                    let (s, n) = live.swap_remove(which.index(live.len()));
                    p.give_back(s, n);
                }
                let used: u32 = live.iter().map(|&(_, n)| n).sum();
                prop_assert_eq!(p.free() + used, p.len());
                // Best fit never leaves the pool longer than live data plus 50 of the largest size
                // twice over.
                prop_assert!(p.len() <= used + 2 * 50 * 1000);
            }
        }
    }
}
