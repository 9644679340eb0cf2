//! Buffers too small for the slot they are bound to, for the output size and scene a graph is
//! compiled for (a draw command per draw group, an id per instance, 64-byte counters...), as each
//! slot declares ([`MinBytes`]), or not exactly the size of a fixed record (counters). Reported at the binding, instead of by the pass when it is built
//! or first recorded. What a kind derives beyond that (a pyramid's size from its depth's) it
//! checks itself ([`crate::graph::PassKind::check_sizes`]).

use super::super::compile::resolve::Resolved;
use super::super::compile::FrameInputs;
use super::super::error::Pos;
use super::super::kinds::MinBytes;
use super::super::validated::{PassBinding, ValidatedGraph};

/// `(position, message)` for every binding of a kept pass (`keep[p]`) whose resource is smaller
/// than its slot takes; `resolved[r]` is resource `r` as compiled.
pub(crate) fn slot_size_errors(
    graph: &ValidatedGraph,
    keep: &[bool],
    resolved: &[Resolved],
    frame: &FrameInputs,
) -> Vec<(Pos, String)> {
    let (instances, meshes, blended) = (frame.instances, frame.meshes, frame.blended);
    let mut out = Vec::new();
    for (_, pass) in graph.passes.iter().enumerate().filter(|(p, _)| keep.get(*p).copied().unwrap_or(true)) {
        let Some(kind) = graph.kinds.info(&pass.kind) else { continue };
        for binding in &pass.bindings {
            let Some(Resolved::Buffer(bytes)) = resolved.get(binding.resource) else { continue };
            let min = kind.slot(&binding.slot).map_or(MinBytes::Any, |s| s.min_bytes);
            let need = min.bytes(instances, meshes, blended);
            if *bytes < need || (matches!(min, MinBytes::Exact(_)) && *bytes != need) {
                let resource = &graph.resources[binding.resource].name;
                let scene = if matches!(min, MinBytes::PerBlended(_)) {
                    format!(" for this scene ({blended} transparent instances)")
                } else {
                    format!(" for this scene ({instances} instances, {meshes} meshes)")
                };
                let message = too_small(&pass.name, binding, resource, *bytes, min, need, &scene);
                out.push((binding.pos, message));
            }
        }
    }
    out
}

/// What a binding whose buffer holds `bytes` where its slot takes `min` (`need` bytes, `scene`
/// saying for what when that depends on the scene) is told.
pub(crate) fn too_small(
    pass: &str,
    binding: &PassBinding,
    resource: &str,
    bytes: u64,
    min: MinBytes,
    need: u64,
    scene: &str,
) -> String {
    let dir = if binding.in_writes { "writes" } else { "reads" };
    let rule = match min {
        MinBytes::Fixed(_) => String::new(),
        MinBytes::Exact(_) => "exactly ".into(),
        _ => format!("{} = ", min.rule()),
    };
    format!(
        "pass '{pass}' {dir} \"{}\": '{resource}' holds {bytes} bytes; the slot takes {rule}{need} bytes{scene}",
        binding.written_slot
    )
}
