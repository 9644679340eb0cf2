//! Buffers too small for the slot they are bound to, for the output size and scene a graph is
//! compiled for (a draw command per draw group, an id per instance, 64-byte counters...), as each
//! slot declares ([`Bytes`]), or not exactly the size of a fixed record (counters). Reported at
//! the binding, instead of by the pass when it is built or first recorded. What a kind derives
//! beyond that (a pyramid's size from its depth's) it checks itself
//! ([`crate::graph::PassKind::check_compiled`]).

use super::super::compile::resolve::Resolved;
use super::super::error::Pos;
use super::super::expr::{Expr, Num};
use super::super::kinds::Bytes;
use super::super::plan::SettingValue;
use super::super::validated::{PassBinding, ValidatedGraph};
use std::collections::BTreeMap;

/// The variables of a kind's size expressions for one pass: the output size and quantities
/// (`frame`), and the pass's numeric settings.
pub(crate) fn kind_variables(
    frame: &BTreeMap<String, Num>,
    settings: &BTreeMap<String, SettingValue>,
) -> BTreeMap<String, Num> {
    let mut vars = frame.clone();
    for (name, value) in settings {
        match value {
            SettingValue::Int(i) => vars.insert(name.clone(), Num::Int(*i)),
            SettingValue::Float(f) => vars.insert(name.clone(), Num::Float(*f)),
            _ => None,
        };
    }
    vars
}

/// The bytes `bytes` asks for with `vars`; `None` for no requirement (or one that cannot be
/// evaluated, which the kind's registration rules out).
pub(crate) fn required_bytes(bytes: Bytes, vars: &BTreeMap<String, Num>) -> Option<u64> {
    let expr = Expr::parse(bytes.expr()?).ok()?;
    let n = expr.eval(vars).ok()?.as_f64().ceil();
    (n.is_finite() && n >= 0.0).then_some(n as u64)
}

/// `(position, message)` for every binding of a kept pass (`keep[p]`) whose resource is smaller
/// than its slot takes; `resolved[r]` is resource `r` as compiled, `frame` the output size and
/// quantities as variables and `settings[p]` pass `p`'s resolved settings.
pub(crate) fn slot_size_errors(
    graph: &ValidatedGraph,
    keep: &[bool],
    resolved: &[Resolved],
    frame: &BTreeMap<String, Num>,
    settings: &[BTreeMap<String, SettingValue>],
) -> Vec<(Pos, String)> {
    let mut out = Vec::new();
    for (p, pass) in graph.passes.iter().enumerate().filter(|(p, _)| keep.get(*p).copied().unwrap_or(true)) {
        let Some(kind) = graph.kinds.info(&pass.kind) else { continue };
        let vars = kind_variables(frame, &settings[p]);
        for binding in &pass.bindings {
            let Some(Resolved::Buffer(bytes)) = resolved.get(binding.resource) else { continue };
            let Some(slot) = kind.slot(&binding.slot) else { continue };
            let Some(need) = required_bytes(slot.bytes, &vars) else { continue };
            let exact = matches!(slot.bytes, Bytes::Exactly(_));
            if *bytes < need || (exact && *bytes != need) {
                let resource = &graph.resources[binding.resource].name;
                let scene = scene_of(slot.bytes, frame);
                let message = too_small(&pass.name, binding, resource, *bytes, slot.bytes, need, &scene);
                out.push((binding.pos, message));
            }
        }
    }
    out
}

/// ` for this scene (instances = 10, meshes = 4)`: the quantities a requirement uses, or
/// nothing when it uses none.
fn scene_of(bytes: Bytes, frame: &BTreeMap<String, Num>) -> String {
    let Some(expr) = bytes.expr().and_then(|e| Expr::parse(e).ok()) else { return String::new() };
    let mut used: Vec<String> =
        expr.variables().into_iter().filter_map(|(name, _)| frame.get(name).map(|v| format!("{name} = {v}"))).collect();
    used.dedup();
    if used.is_empty() {
        String::new()
    } else {
        format!(" for this scene ({})", used.join(", "))
    }
}

/// What a binding whose buffer holds `bytes` where its slot takes `rule` (`need` bytes, `scene`
/// saying for what when that depends on the scene) is told.
pub(crate) fn too_small(
    pass: &str,
    binding: &PassBinding,
    resource: &str,
    bytes: u64,
    rule: Bytes,
    need: u64,
    scene: &str,
) -> String {
    let dir = if binding.in_writes { "writes" } else { "reads" };
    let text = rule.expr().unwrap_or("");
    let rule = match rule {
        Bytes::Exactly(_) if text.trim() == need.to_string() => "exactly ".to_string(),
        Bytes::Exactly(_) => format!("exactly {text} = "),
        _ if text.trim() == need.to_string() => String::new(),
        _ => format!("{text} = "),
    };
    format!(
        "pass '{pass}' {dir} \"{}\": '{resource}' holds {bytes} bytes; the slot takes {rule}{need} bytes{scene}",
        binding.written_slot
    )
}
