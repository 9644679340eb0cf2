//! Lifetimes: for each resource, the first and last position in execution order of a pass that
//! uses its current version (`.prev` reads use the other copy of a history resource).

use crate::graph::plan::Version;
use crate::graph::validated::ValidatedGraph;

/// Per resource, `(first, last)` execution position of a use of the current version.
pub fn lifetimes(graph: &ValidatedGraph, order: &[usize]) -> Vec<Option<(usize, usize)>> {
    let mut out: Vec<Option<(usize, usize)>> = vec![None; graph.resources.len()];
    for (pos, &p) in order.iter().enumerate() {
        for b in graph.passes[p].bindings.iter().filter(|b| b.version == Version::Current) {
            let l = &mut out[b.resource];
            *l = Some(match *l {
                None => (pos, pos),
                Some((first, last)) => (first.min(pos), last.max(pos)),
            });
        }
    }
    out
}
