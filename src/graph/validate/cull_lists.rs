//! Draw-list bindings of `instance_cull` passes: whether they fit together (the late phase
//! writes the next frame's early draw list whole, ids, commands, count and counters, with the
//! visibility). The rule is
//! [`crate::passes::instance_cull::list_binding_error`]; here it is reported at the binding.

use super::Validator;
use crate::graph::validated::ValidatedGraph;

pub(super) fn check(v: &mut Validator<'_>, graph: &ValidatedGraph) {
    for pass in graph.passes.iter().filter(|p| p.kind == "instance_cull") {
        let bound = |slot: &str| pass.bindings.iter().any(|b| b.slot == slot);
        if let Some((slot, message)) = crate::passes::instance_cull::list_binding_error(bound) {
            let pos = pass.bindings.iter().find(|b| b.slot == slot).map_or(pass.pos, |b| b.pos);
            v.err(pos, format!("pass '{}' (instance_cull): {message}", pass.name));
        }
    }
}
