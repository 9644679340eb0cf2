//! Resources that exist only in some frames (`when`): only optional slots of built-in kinds may
//! bind them, and none may be an output, so a frame without one is still a whole frame.

use super::Validator;
use crate::graph::validated::ValidatedGraph;

/// Reports bindings and outputs that a conditional resource could leave empty.
pub(super) fn check(v: &mut Validator<'_>, graph: &ValidatedGraph) {
    for (r, res) in graph.resources.iter().enumerate() {
        let Some(when) = &res.when else { continue };
        let condition = format!("\"{}\"", when.expr.text());
        if let Some(at) = graph.outputs.iter().position(|&o| o == r) {
            let pos = graph.output_pos.get(at).copied().unwrap_or(res.pos);
            v.err(pos, format!("output '{}' exists only when {condition}: an output must always exist", res.name));
        }
        for pass in &graph.passes {
            for b in pass.bindings.iter().filter(|b| b.resource == r) {
                let info = graph.kinds.info(&pass.kind);
                let optional =
                    info.is_some_and(|k| !k.slots_from_shader && k.slot(&b.slot).is_some_and(|s| !s.required));
                if !optional {
                    v.err(
                        b.pos,
                        format!(
                            "pass '{}' binds slot \"{}\" to '{}', which exists only when {condition}: only an optional slot of a built-in kind may (it is then left unbound)",
                            pass.name, b.written_slot, res.name
                        ),
                    );
                }
            }
        }
    }
}
