//! Printing a compiled graph: the plan as text (`Display`, `cullgraph graph plan`) and as
//! graphviz ([`to_dot`], `cullgraph graph dot`).

use super::formats;
use super::plan::{CompiledGraph, PlannedBarrier, ResolvedKind, ResourceClass, SettingValue, Version};
use crate::gpu::Access;
use std::fmt::{self, Write as _};

/// `a|b|c` from ash's `a | b | c` flag names.
fn flags(f: impl fmt::Debug) -> String {
    format!("{f:?}").replace(" | ", "|")
}

fn bytes(n: u64) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    if n >= 1 << 20 {
        format!("{:.2} MiB", n as f64 / MIB)
    } else if n >= 1 << 10 {
        format!("{:.1} KiB", n as f64 / 1024.0)
    } else {
        format!("{n} B")
    }
}

fn version_name(graph: &CompiledGraph, resource: usize, version: Version) -> String {
    let name = graph.resources.get(resource).map_or("?", |r| r.name.as_str());
    match version {
        Version::Current => name.to_string(),
        Version::Previous => format!("{name}.prev"),
    }
}

fn scope(a: &Access) -> String {
    let access = if a.access.is_empty() { "(execution only)".to_string() } else { flags(a.access) };
    format!("{} {access}", flags(a.stage))
}

/// One barrier as a line: `resource: src -> dst, old layout -> new layout`.
pub fn barrier_line(graph: &CompiledGraph, b: &PlannedBarrier) -> String {
    let is_image = matches!(graph.resources.get(b.resource).map(|r| &r.kind), Some(ResolvedKind::Image { .. }));
    let mut s = format!("{}: ", version_name(graph, b.resource, b.version));
    match &b.src {
        None => s.push_str("first use in frame"),
        Some(src) => s.push_str(&scope(src)),
    }
    let _ = write!(s, " -> {}", scope(&b.dst));
    if is_image {
        let old = match (&b.src, b.discard) {
            (_, true) => "UNDEFINED".to_string(),
            (None, false) => "current".to_string(),
            (Some(src), false) => format!("{:?}", src.layout),
        };
        let _ = write!(s, ", {old} -> {:?}", b.dst.layout);
    }
    if b.discard {
        s.push_str(" (discard)");
    }
    s
}

fn setting(v: &SettingValue) -> String {
    match v {
        SettingValue::Bool(b) => b.to_string(),
        SettingValue::Int(i) => i.to_string(),
        SettingValue::Float(f) => format!("{f:?}"),
        SettingValue::Choice(c) => c.clone(),
    }
}

fn describe(kind: &ResolvedKind) -> String {
    match kind {
        ResolvedKind::Image { format, extent, mip_levels, samples, .. } => format!(
            "image {} {}x{} mips {} samples {}",
            formats::name(*format),
            extent.width,
            extent.height,
            mip_levels,
            samples.as_raw()
        ),
        ResolvedKind::Buffer { size, .. } => format!("buffer {}", bytes(*size)),
    }
}

fn class(c: ResourceClass) -> &'static str {
    match c {
        ResourceClass::Transient => "transient",
        ResourceClass::History => "history",
        ResourceClass::Imported => "imported",
        ResourceClass::Output => "output",
    }
}

impl fmt::Display for CompiledGraph {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "graph '{}': {} passes ({} pruned), {} resources",
            self.name,
            self.passes.len(),
            self.pruned.len(),
            self.resources.len()
        )?;
        if self.files.len() > 1 {
            writeln!(f, "composed from: {}", self.files.join(", "))?;
        }
        writeln!(f, "passes in execution order:")?;
        for (i, p) in self.passes.iter().enumerate() {
            write!(f, "  {i}: {} ({})", p.name, p.kind)?;
            if self.files.len() > 1 {
                write!(f, " at {}:{}", super::error::file_of(&self.files, p.pos), p.pos)?;
            }
            if !p.settings.is_empty() {
                let s: Vec<String> = p.settings.iter().map(|(k, v)| format!("{k}={}", setting(v))).collect();
                write!(f, " settings {}", s.join(", "))?;
            }
            if let Some([x, y, z]) = p.dispatch {
                write!(f, " dispatch {x}x{y}x{z}")?;
            }
            if let Some(shader) = &p.shader {
                write!(f, " shader {}", shader.display())?;
            }
            writeln!(f)?;
            if p.barriers.is_empty() {
                writeln!(f, "       no barriers")?;
            }
            for b in &p.barriers {
                writeln!(f, "       barrier {}", barrier_line(self, b))?;
            }
        }
        if !self.pruned.is_empty() {
            writeln!(f, "pruned:")?;
            for p in &self.pruned {
                writeln!(f, "  {} ({}): {}", p.name, p.kind, p.reason)?;
            }
        }
        writeln!(f, "resources:")?;
        let width = self.resources.iter().map(|r| r.name.len()).max().unwrap_or(0);
        for (i, r) in self.resources.iter().enumerate() {
            write!(f, "  {:width$}  {:<9} {}", r.name, class(r.class), describe(&r.kind))?;
            match r.lifetime {
                Some((a, b)) => write!(f, ", passes {a}..={b}")?,
                None => write!(f, ", unused")?,
            }
            if let Some(Some(p)) = self.memory.placements.get(i) {
                write!(f, ", heap {} offset {}", p.heap, p.offset)?;
            }
            if let Some(owner) = &r.owner {
                write!(f, ", created by pass '{owner}'")?;
            }
            writeln!(f)?;
        }
        let (without, with) = (self.memory.bytes_without_aliasing, self.memory.bytes_with_aliasing);
        let saved = without.saturating_sub(with);
        let percent = if without > 0 { saved as f64 * 100.0 / without as f64 } else { 0.0 };
        write!(
            f,
            "transient memory (estimated): {} without aliasing, {} with aliasing in {} heap(s), saves {} ({percent:.0}%)",
            bytes(without),
            bytes(with),
            self.memory.heaps.len(),
            bytes(saved)
        )
    }
}

fn quote(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n"))
}

/// Graphviz of a compiled graph: passes as boxes (pruned ones grey), resources as ellipses,
/// edges labelled `read SLOT` / `write SLOT`, reads of last frame's contents dashed.
pub fn to_dot(graph: &CompiledGraph) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "digraph {} {{", quote(&graph.name));
    s.push_str(
        "  rankdir=LR;\n  node [fontname=\"Helvetica\", fontsize=11];\n  edge [fontname=\"Helvetica\", fontsize=9];\n",
    );
    for (i, r) in graph.resources.iter().enumerate() {
        let mut label = format!("{}\n{}", r.name, describe(&r.kind));
        if r.class != ResourceClass::Transient {
            let _ = write!(label, "\n{}", class(r.class));
        }
        let style = if graph.outputs.contains(&i) { ", peripheries=2" } else { "" };
        let _ = writeln!(s, "  {} [shape=ellipse, label={}{style}];", quote(&format!("res:{}", r.name)), quote(&label));
    }
    let edges = |s: &mut String, pass: &str, bindings: &[super::plan::Binding], grey: bool| {
        for b in bindings {
            let res = quote(&format!("res:{}", graph.resources.get(b.resource).map_or("?", |r| r.name.as_str())));
            let mut attrs = String::new();
            if b.version == Version::Previous {
                attrs.push_str(", style=dashed");
            }
            if grey {
                attrs.push_str(", color=gray60, fontcolor=gray60");
            }
            let prev = if b.version == Version::Previous { " (.prev)" } else { "" };
            if b.usage.reads() {
                let _ = writeln!(s, "  {res} -> {pass} [label={}{attrs}];", quote(&format!("read {}{prev}", b.slot)));
            }
            if b.usage.writes() {
                let _ = writeln!(s, "  {pass} -> {res} [label={}{attrs}];", quote(&format!("write {}", b.slot)));
            }
        }
    };
    for (i, p) in graph.passes.iter().enumerate() {
        let id = quote(&format!("pass:{}", p.name));
        let label = format!("{}: {}\n({})", i, p.name, p.kind);
        let _ = writeln!(
            s,
            "  {id} [shape=box, style=\"rounded,filled\", fillcolor=\"#dde8f5\", label={}];",
            quote(&label)
        );
        edges(&mut s, &id, &p.bindings, false);
    }
    for p in &graph.pruned {
        let id = quote(&format!("pass:{}", p.name));
        let label = format!("{}\n({}, pruned)\n{}", p.name, p.kind, p.reason);
        let _ = writeln!(
            s,
            "  {id} [shape=box, style=\"rounded,filled\", fillcolor=gray90, color=gray60, fontcolor=gray45, label={}];",
            quote(&label)
        );
        edges(&mut s, &id, &p.bindings, true);
    }
    s.push_str("}\n");
    s
}
