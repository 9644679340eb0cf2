//! Pruning: keep only the passes whose results reach an output, an imported resource (the host
//! sees it after the frame) or a later frame (a history resource whose `.prev` a kept pass
//! reads), transitively; list the others with the reason.
//!
//! Works on versions, not names: a pass whose write is overwritten before anything reads it is
//! pruned even if the resource is an output, because its contents never reach the output.

use super::flow::{self, Flow};
use crate::graph::plan::{Binding, PrunedPass, Version};
use crate::graph::validated::ValidatedGraph;
use std::collections::HashSet;

/// Which passes stay, and why the others go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pruning {
    /// Per pass (declaration order): kept?
    pub keep: Vec<bool>,
    /// The removed passes, in declaration order.
    pub pruned: Vec<PrunedPass>,
}

/// Decides which passes are needed.
pub fn prune(graph: &ValidatedGraph) -> Pruning {
    let n = graph.passes.len();
    let flows = flow::flows(graph, &vec![true; n]);
    // For each pass, the versions it reads: (resource, version), and the history resources it
    // reads as `.prev`.
    let mut reads: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    for (r, f) in flows.iter().enumerate() {
        for u in &f.uses {
            if let Some(v) = u.reads {
                reads[u.pass].push((r, v));
            }
        }
    }
    let mut needed: HashSet<(usize, usize)> = HashSet::new();
    let mut queue: Vec<(usize, usize)> = Vec::new();
    for (r, f) in flows.iter().enumerate() {
        if graph.outputs.contains(&r) || graph.resources[r].imported {
            need(r, f, &mut queue, &mut needed);
        }
    }
    let mut keep = vec![false; n];
    while let Some((r, v)) = queue.pop() {
        let p = flows[r].writers[v];
        if keep[p] {
            continue;
        }
        keep[p] = true;
        for &(r2, v2) in &reads[p] {
            if needed.insert((r2, v2)) {
                queue.push((r2, v2));
            }
        }
        for b in graph.passes[p].bindings.iter().filter(|b| b.version == Version::Previous) {
            need(b.resource, &flows[b.resource], &mut queue, &mut needed);
        }
    }
    let pruned = (0..n).filter(|&p| !keep[p]).map(|p| pruned_pass(graph, &flows, &keep, p)).collect();
    Pruning { keep, pruned }
}

fn names(graph: &ValidatedGraph, passes: &[usize]) -> String {
    passes.iter().map(|&p| format!("'{}'", graph.passes[p].name)).collect::<Vec<_>>().join(", ")
}

fn pruned_pass(graph: &ValidatedGraph, flows: &[Flow], keep: &[bool], p: usize) -> PrunedPass {
    let pass = &graph.passes[p];
    let mut why = Vec::new();
    for (r, f) in flows.iter().enumerate() {
        let Some(v) = f.writers.iter().position(|&w| w == p) else { continue };
        let res = &graph.resources[r].name;
        let readers: Vec<usize> = f.uses.iter().filter(|u| u.reads == Some(v) && u.pass != p).map(|u| u.pass).collect();
        let prev_readers: Vec<usize> = graph
            .passes
            .iter()
            .enumerate()
            .filter(|(_, q)| q.bindings.iter().any(|b| b.resource == r && b.version == Version::Previous))
            .map(|(q, _)| q)
            .collect();
        if !readers.is_empty() {
            why.push(format!("'{res}' is read only by pruned {}", names(graph, &readers)));
        } else if let Some(&next) = f.writers.get(v + 1) {
            why.push(format!("'{res}' is overwritten by '{}' before anything reads it", graph.passes[next].name));
        } else if !prev_readers.is_empty() && prev_readers.iter().all(|&q| !keep[q]) {
            why.push(format!("'{res}' is read next frame only by pruned {}", names(graph, &prev_readers)));
        } else {
            why.push(format!("'{res}' is never read"));
        }
    }
    let reason = if why.is_empty() { "it writes nothing".to_string() } else { why.join("; ") };
    PrunedPass {
        name: pass.name.clone(),
        kind: pass.kind.clone(),
        reason,
        bindings: pass
            .bindings
            .iter()
            .map(|b| Binding { slot: b.slot.clone(), resource: b.resource, version: b.version, usage: b.usage })
            .collect(),
    }
}

/// Marks the last version of resource `r` needed.
fn need(r: usize, f: &Flow, queue: &mut Vec<(usize, usize)>, needed: &mut HashSet<(usize, usize)>) {
    if let Some(v) = f.last_version() {
        if needed.insert((r, v)) {
            queue.push((r, v));
        }
    }
}
