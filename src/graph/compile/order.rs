//! Execution order: a topological order of the dependency graph that prefers declaration order
//! (Kahn's algorithm, always taking the ready pass declared first), and cycle reports.
//!
//! The order is computed here rather than with `petgraph::algo::toposort`, whose order depends
//! on node and edge insertion details; with this rule the same file always gives the same order,
//! and a file already written in a valid order runs exactly as written.

use super::flow::{DepKind, Dependency};
use petgraph::graph::{DiGraph, NodeIndex};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// The execution order of `passes` (declaration indices, ascending) under `deps`; `None` if the
/// dependencies contain a cycle.
pub fn execution_order(passes: &[usize], deps: &[Dependency]) -> Option<Vec<usize>> {
    let n = passes.iter().max().map_or(0, |m| m + 1);
    let mut member = vec![false; n];
    for &p in passes {
        member[p] = true;
    }
    let mut indegree = vec![0usize; n];
    let mut successors: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut seen = std::collections::HashSet::new();
    for d in deps {
        if member[d.from] && member[d.to] && seen.insert((d.from, d.to)) {
            successors[d.from].push(d.to);
            indegree[d.to] += 1;
        }
    }
    let mut ready: BinaryHeap<Reverse<usize>> =
        passes.iter().filter(|&&p| indegree[p] == 0).map(|&p| Reverse(p)).collect();
    let mut order = Vec::with_capacity(passes.len());
    while let Some(Reverse(p)) = ready.pop() {
        order.push(p);
        for &s in &successors[p] {
            indegree[s] -= 1;
            if indegree[s] == 0 {
                ready.push(Reverse(s));
            }
        }
    }
    (order.len() == passes.len()).then_some(order)
}

/// A dependency cycle: the passes on it, starting with the one declared first, and the
/// dependency behind each step (`steps[i]` leads from `passes[i]` to `passes[i + 1]`, the last
/// back to `passes[0]`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cycle {
    /// Passes on the cycle (declaration indices).
    pub passes: Vec<usize>,
    /// One dependency per step.
    pub steps: Vec<Dependency>,
}

/// One shortest cycle per strongly connected component with more than one pass (found with
/// `petgraph`'s Tarjan SCC), ordered by the first pass of each.
pub fn cycles(pass_count: usize, deps: &[Dependency]) -> Vec<Cycle> {
    let mut g: DiGraph<usize, Dependency> = DiGraph::with_capacity(pass_count, deps.len());
    let nodes: Vec<NodeIndex> = (0..pass_count).map(|p| g.add_node(p)).collect();
    for d in deps {
        if d.from != d.to {
            g.add_edge(nodes[d.from], nodes[d.to], *d);
        }
    }
    let mut out = Vec::new();
    for scc in petgraph::algo::tarjan_scc(&g) {
        if scc.len() < 2 {
            continue;
        }
        let mut in_scc = vec![false; pass_count];
        for n in &scc {
            in_scc[g[*n]] = true;
        }
        let start = scc.iter().map(|n| g[*n]).min().unwrap_or(0);
        // Breadth-first search inside the component from `start` back to `start`, preferring
        // the dependency kinds RAW, WAR, WAW and lower pass indices for a stable message.
        let mut edges: Vec<Vec<Dependency>> = vec![Vec::new(); pass_count];
        for d in deps {
            if in_scc[d.from] && in_scc[d.to] && d.from != d.to {
                edges[d.from].push(*d);
            }
        }
        for e in &mut edges {
            e.sort_by_key(|d| (d.to, kind_rank(d.kind), d.resource));
        }
        let mut came_from: Vec<Option<Dependency>> = vec![None; pass_count];
        let mut queue = VecDeque::from([start]);
        let mut closing = None;
        'bfs: while let Some(p) = queue.pop_front() {
            for d in &edges[p] {
                if d.to == start {
                    closing = Some(*d);
                    break 'bfs;
                }
                if came_from[d.to].is_none() && d.to != start {
                    came_from[d.to] = Some(*d);
                    queue.push_back(d.to);
                }
            }
        }
        let Some(last) = closing else { continue };
        let mut steps = vec![last];
        let mut p = last.from;
        while p != start {
            let Some(d) = came_from[p] else { break };
            steps.push(d);
            p = d.from;
        }
        steps.reverse();
        let passes = steps.iter().map(|d| d.from).collect();
        out.push(Cycle { passes, steps });
    }
    out.sort_by_key(|c| c.passes[0]);
    out
}

fn kind_rank(k: DepKind) -> u8 {
    match k {
        DepKind::ReadAfterWrite => 0,
        DepKind::WriteAfterRead => 1,
        DepKind::WriteAfterWrite => 2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dep(from: usize, to: usize) -> Dependency {
        Dependency { from, to, resource: 0, kind: DepKind::ReadAfterWrite }
    }

    #[test]
    fn prefers_declaration_order() {
        assert_eq!(execution_order(&[0, 1, 2, 3], &[dep(2, 0)]), Some(vec![1, 2, 0, 3]));
        assert_eq!(execution_order(&[0, 1, 2], &[]), Some(vec![0, 1, 2]));
        assert_eq!(execution_order(&[0, 1], &[dep(0, 1), dep(1, 0)]), None);
    }

    #[test]
    fn names_the_shortest_cycle_from_the_first_pass() {
        let c = cycles(4, &[dep(0, 1), dep(1, 2), dep(2, 0), dep(1, 0), dep(3, 3)]);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].passes, vec![0, 1]);
    }
}
