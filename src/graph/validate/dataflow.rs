//! Outputs and data flow: every read has a writer (or is imported, or last frame's), history
//! resources read as `.prev` are written, outputs are written, and the passes have no cycle.

use super::{resource_list, Validator};
use crate::graph::compile::flow::{self, DepKind};
use crate::graph::compile::order;
use crate::graph::error::Pos;
use crate::graph::locate::Seg;
use crate::graph::plan::{ResourceId, Version};
use crate::graph::schema::GraphFile;
use crate::graph::validated::{Resource, ValidatedGraph};
use std::collections::HashMap;

impl Validator<'_> {
    pub(super) fn outputs(&mut self, file: &GraphFile, resources: &[Resource]) -> (Vec<ResourceId>, Vec<Pos>) {
        let names: HashMap<String, usize> = resources.iter().enumerate().map(|(i, r)| (r.name.clone(), i)).collect();
        let hint = "add outputs: [\"name\"] (the first is the image the host shows)";
        let Some(list) = &file.outputs else {
            self.err(self.pos(&[]), format!("graph '{}' has no outputs; {hint}", file.name));
            return (Vec::new(), Vec::new());
        };
        if list.is_empty() {
            self.err(self.pos(&[Seg::Field("outputs")]), format!("graph '{}' has no outputs; {hint}", file.name));
        }
        let mut out: Vec<ResourceId> = Vec::new();
        let mut at = Vec::new();
        for (k, name) in list.iter().enumerate() {
            let pos = self.pos(&[Seg::Field("outputs"), Seg::Index(k)]);
            if let Some(base) = name.strip_suffix(".prev") {
                self.err(pos, format!("outputs name this frame's resources, not '{base}.prev'"));
                continue;
            }
            let Some(&r) = names.get(name) else {
                self.err(pos, format!("unknown resource '{name}' in outputs (resources: {})", resource_list(&names)));
                continue;
            };
            if out.contains(&r) {
                self.err(pos, format!("output '{name}' is listed twice"));
                continue;
            }
            out.push(r);
            at.push(pos);
        }
        (out, at)
    }
}

/// Reads without writers, `.prev` of unwritten history, unwritten outputs, cycles.
pub(super) fn check(v: &mut Validator<'_>, graph: &ValidatedGraph, file: &GraphFile) {
    let all = vec![true; graph.passes.len()];
    let flows = flow::flows(graph, &all);
    for (r, f) in flows.iter().enumerate() {
        let res = &graph.resources[r];
        if res.imported || v.uncertain_writes.contains(&r) {
            continue;
        }
        for u in &f.uses {
            let pass = &graph.passes[u.pass];
            let b = &pass.bindings[u.binding];
            if u.reads.is_none() && b.usage.reads() {
                let message = if u.writes.is_some() {
                    format!(
                        "pass '{}' loads the previous contents of '{}' (slot \"{}\") before any pass writes it",
                        pass.name, res.name, b.written_slot
                    )
                } else {
                    format!(
                        "resource '{}' is read by pass '{}' but written by no pass (only imported resources and \
                         'name.prev' of history resources can be read without a writer)",
                        res.name, pass.name
                    )
                };
                v.err(b.pos, message);
            }
        }
    }
    for pass in &graph.passes {
        for b in pass.bindings.iter().filter(|b| b.version == Version::Previous) {
            let r = b.resource;
            if flows[r].writers.is_empty() && !v.uncertain_writes.contains(&r) {
                let name = &graph.resources[r].name;
                v.err(
                    b.pos,
                    format!(
                        "'{name}.prev' is read by pass '{}' but no pass writes '{name}', so last frame's contents \
                         are never produced",
                        pass.name
                    ),
                );
            }
        }
    }
    content_errors(v, graph);
    if let Some(list) = &file.outputs {
        for (k, name) in list.iter().enumerate() {
            let Some(r) = graph.resource_id(name) else { continue };
            if flows[r].writers.is_empty() && !v.uncertain_writes.contains(&r) && graph.outputs.contains(&r) {
                v.err(v.pos(&[Seg::Field("outputs"), Seg::Index(k)]), format!("output '{name}' is written by no pass"));
            }
        }
    }
    let deps = flow::dependencies(&flows);
    for cycle in order::cycles(graph.passes.len(), &deps) {
        let mut names: Vec<String> = cycle.passes.iter().map(|&p| format!("'{}'", graph.passes[p].name)).collect();
        names.push(names[0].clone());
        let why: Vec<String> = cycle
            .steps
            .iter()
            .map(|d| {
                let (from, to) = (&graph.passes[d.from].name, &graph.passes[d.to].name);
                let res = &graph.resources[d.resource].name;
                match d.kind {
                    DepKind::ReadAfterWrite => format!("'{to}' reads '{res}' written by '{from}'"),
                    DepKind::WriteAfterRead => format!("'{to}' overwrites '{res}' read by '{from}'"),
                    DepKind::WriteAfterWrite => format!("'{to}' writes '{res}' after '{from}'"),
                }
            })
            .collect();
        let first = &graph.passes[cycle.passes[0]];
        v.err(first.pos, format!("cycle: {} ({})", names.join(" -> "), why.join("; ")));
    }
}

/// Reads of a content a pass trusts ([`crate::graph::SlotDecl::content`], draw commands above
/// all) from resources written as anything else: a draw that took its indirect commands from a
/// buffer of visibility bits could run without end.
fn content_errors(v: &mut Validator<'_>, graph: &ValidatedGraph) {
    let slot_of = |pass: &crate::graph::validated::Pass, slot: &str| graph.kinds.info(&pass.kind)?.slot(slot).copied();
    for pass in &graph.passes {
        for b in pass.bindings.iter().filter(|b| !b.in_writes) {
            let Some(content) = slot_of(pass, &b.slot).and_then(|s| s.content) else { continue };
            if graph.resources[b.resource].imported {
                continue;
            }
            let writers = graph.passes.iter().flat_map(|w| w.bindings.iter().map(move |wb| (w, wb)));
            let wrong = writers
                .filter(|(_, wb)| wb.in_writes && wb.resource == b.resource)
                .find(|(w, wb)| slot_of(w, &wb.slot).and_then(|s| s.content) != Some(content));
            if let Some((w, wb)) = wrong {
                let name = &graph.resources[b.resource].name;
                v.err(
                    b.pos,
                    format!(
                        "pass '{}' reads {content} from '{name}' (slot \"{}\"), but pass '{}' writes '{name}' \
                         through \"{}\", which does not write {content}: only a pass whose kind writes {content} \
                         may feed this slot",
                        pass.name, b.written_slot, w.name, wb.written_slot
                    ),
                );
            }
        }
    }
}
