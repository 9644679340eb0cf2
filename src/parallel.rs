//! Work over many items spread over the machine's cores, where a list is long enough that
//! starting threads pays (bulk moves of a living world and their sync).

use std::ops::Range;

/// Below this many items the work stays on the calling thread: starting a thread costs some
/// tens of microseconds, which a short list does not repay.
pub const MIN_ITEMS_PER_THREAD: usize = 1 << 15;

/// The ranges `0..n` is cut into, one per thread: as many as the machine has cores, each of at
/// least [`MIN_ITEMS_PER_THREAD`] items (one range for a short list).
pub fn chunks(n: usize) -> Vec<Range<usize>> {
    let threads = match n / MIN_ITEMS_PER_THREAD {
        0 | 1 => 1,
        most => most.min(cores()),
    };
    let size = n.div_ceil(threads).max(1);
    (0..threads).map(|t| t * size..((t + 1) * size).min(n)).filter(|r| !r.is_empty()).collect()
}

/// The cores this process may use, asked once: the question reads the scheduler's affinity and
/// cgroup files, which costs more than a short list's work.
fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |c| c.get()))
}

/// `f` over each range of [`chunks`]`(n)`, on a thread each (the first on the calling one); the
/// results in range order.
pub fn map_chunks<T: Send>(n: usize, f: impl Fn(Range<usize>) -> T + Sync) -> Vec<T> {
    let ranges = chunks(n);
    if ranges.len() <= 1 {
        return ranges.into_iter().map(&f).collect();
    }
    let f = &f;
    std::thread::scope(|s| {
        let mut ranges = ranges.into_iter();
        let first = ranges.next().expect("more than one range");
        let handles: Vec<_> = ranges.map(|r| s.spawn(move || f(r))).collect();
        let mut out = vec![f(first)];
        // A panic in a worker is a bug in `f`: it goes on in the caller.
        out.extend(handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))));
        out
    })
}

/// The first item of `0..n`, in order, for which `f` says something, looked for on several
/// threads.
pub fn first<E: Send>(n: usize, f: impl Fn(usize) -> Option<E> + Sync) -> Option<E> {
    map_chunks(n, |range| range.into_iter().find_map(&f)).into_iter().flatten().next()
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

    #[test]
    fn the_first_finding_is_the_first_in_order_whichever_thread_finds_it() {
        let n = MIN_ITEMS_PER_THREAD * 8;
        let bad = [n - 3, n / 2 + 11, 5 * MIN_ITEMS_PER_THREAD + 1];
        let found = first(n, |i| bad.contains(&i).then_some(i));
        assert_eq!(found, Some(n / 2 + 11));
        assert_eq!(first(n, |_| None::<()>), None);
        let sums = map_chunks(n, |r| r.len());
        assert_eq!(sums.iter().sum::<usize>(), n);
    }
}
