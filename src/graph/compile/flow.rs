//! Which version of a resource each pass sees, and the dependencies that follow.
//!
//! Per resource (this frame's contents only; `name.prev` reads are last frame's and create no
//! edge), the writers in declaration order produce versions 0, 1, 2, ... A pass that only reads
//! sees the latest write declared before it, or version 0 if none is declared before it. A pass
//! that reads and writes (a read-modify-write usage) is a writer that sees the previous version.
//!
//! Dependencies: version k's writer before its readers (RAW), writer k before writer k+1 (WAW),
//! readers of version k before writer k+1 (WAR).

use crate::graph::plan::{ResourceId, Version};
use crate::graph::validated::ValidatedGraph;

/// A use of a resource's current contents by a pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Use {
    /// The pass (declaration index).
    pub pass: usize,
    /// The binding index in the pass.
    pub binding: usize,
    /// The version read: `None` when the pass does not read, or reads contents from before the
    /// frame (nothing writes the resource, or it is the first writer and reads).
    pub reads: Option<usize>,
    /// The version written (index in [`Flow::writers`]).
    pub writes: Option<usize>,
}

/// The uses of one resource.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Flow {
    /// Passes writing it, in declaration order; version k is written by `writers[k]`.
    pub writers: Vec<usize>,
    /// Every use by an included pass, in declaration order.
    pub uses: Vec<Use>,
}

impl Flow {
    /// The last version, if anything writes it.
    pub fn last_version(&self) -> Option<usize> {
        self.writers.len().checked_sub(1)
    }
}

/// Why one pass must run before another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DepKind {
    /// `to` reads what `from` wrote.
    ReadAfterWrite,
    /// `to` overwrites what `from` read.
    WriteAfterRead,
    /// `to` writes after `from` wrote.
    WriteAfterWrite,
}

/// `from` must run before `to` because of `resource`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Dependency {
    /// Earlier pass.
    pub from: usize,
    /// Later pass.
    pub to: usize,
    /// The resource.
    pub resource: ResourceId,
    /// Why.
    pub kind: DepKind,
}

/// Per resource, its flow over the passes with `include[pass]` true.
pub fn flows(graph: &ValidatedGraph, include: &[bool]) -> Vec<Flow> {
    let mut flows = vec![Flow::default(); graph.resources.len()];
    for (p, pass) in graph.passes.iter().enumerate() {
        if !include[p] {
            continue;
        }
        for b in pass.bindings.iter().filter(|b| b.version == Version::Current) {
            if b.usage.writes() {
                flows[b.resource].writers.push(p);
            }
        }
    }
    for (p, pass) in graph.passes.iter().enumerate() {
        if !include[p] {
            continue;
        }
        for (bi, b) in pass.bindings.iter().enumerate().filter(|(_, b)| b.version == Version::Current) {
            let flow = &mut flows[b.resource];
            let u = if b.usage.writes() {
                let k = flow.writers.iter().position(|&w| w == p).unwrap_or(0);
                Use { pass: p, binding: bi, reads: (b.usage.reads() && k > 0).then(|| k - 1), writes: Some(k) }
            } else {
                let before = flow.writers.iter().rposition(|&w| w < p);
                let seen = before.or(if flow.writers.is_empty() { None } else { Some(0) });
                Use { pass: p, binding: bi, reads: seen, writes: None }
            };
            flow.uses.push(u);
        }
    }
    flows
}

/// Every dependency between included passes, sorted and without duplicates.
pub fn dependencies(flows: &[Flow]) -> Vec<Dependency> {
    let mut deps = Vec::new();
    for (r, flow) in flows.iter().enumerate() {
        for pair in flow.writers.windows(2) {
            deps.push(Dependency { from: pair[0], to: pair[1], resource: r, kind: DepKind::WriteAfterWrite });
        }
        for u in &flow.uses {
            let Some(v) = u.reads else { continue };
            let writer = flow.writers[v];
            if writer != u.pass && u.writes.is_none() {
                deps.push(Dependency { from: writer, to: u.pass, resource: r, kind: DepKind::ReadAfterWrite });
            }
            if u.writes.is_none() {
                if let Some(&next) = flow.writers.get(v + 1) {
                    if next != u.pass {
                        deps.push(Dependency { from: u.pass, to: next, resource: r, kind: DepKind::WriteAfterRead });
                    }
                }
            }
        }
    }
    deps.sort();
    deps.dedup();
    deps
}
