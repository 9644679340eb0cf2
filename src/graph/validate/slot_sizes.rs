//! Resources too small for the slot they are bound to, for the output size and scene a graph is
//! compiled for: buffers (a draw command per draw group, an id per instance, 64-byte counters...)
//! and the Hi-Z pyramid (half its depth's size). Reported at
//! the binding, instead of by the pass when it is built or first recorded.

use super::super::compile::resolve::Resolved;
use super::super::error::Pos;
use super::super::kinds::MinBytes;
use super::super::validated::{Pass, PassBinding, ValidatedGraph};
use crate::passes::hiz_build::pyramid_size;
use ash::vk;

/// `(position, message)` for every binding of a kept pass (`keep[p]`) whose resource is smaller
/// than its slot takes; `resolved[r]` is resource `r` as compiled.
pub(crate) fn slot_size_errors(
    graph: &ValidatedGraph,
    keep: &[bool],
    resolved: &[Resolved],
    instances: u64,
    meshes: u64,
) -> Vec<(Pos, String)> {
    let mut out = Vec::new();
    for (_, pass) in graph.passes.iter().enumerate().filter(|(p, _)| keep.get(*p).copied().unwrap_or(true)) {
        let Some(kind) = graph.kinds.iter().find(|k| k.name == pass.kind) else { continue };
        for binding in &pass.bindings {
            let Some(Resolved::Buffer(bytes)) = resolved.get(binding.resource) else { continue };
            let min = kind.slot(&binding.slot).map_or(MinBytes::Any, |s| s.min_bytes);
            let need = min.bytes(instances, meshes);
            if *bytes < need {
                let resource = &graph.resources[binding.resource].name;
                let scene = format!(" for this scene ({instances} instances, {meshes} meshes)");
                let message = too_small(&pass.name, binding, resource, *bytes, min, need, &scene);
                out.push((binding.pos, message));
            }
        }
        if pass.kind == "hiz_build" {
            out.extend(pyramid_error(graph, pass, resolved));
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
        _ => format!("{} = ", min.rule()),
    };
    format!(
        "pass '{pass}' {dir} \"{}\": '{resource}' holds {bytes} bytes; the slot takes {rule}{need} bytes{scene}",
        binding.written_slot
    )
}

/// The pyramid of a `hiz_build` pass must be half its depth's size: level 0 of the chain is not
/// stored.
fn pyramid_error(graph: &ValidatedGraph, pass: &Pass, resolved: &[Resolved]) -> Option<(Pos, String)> {
    let image = |slot: &str| {
        let b = pass.bindings.iter().find(|b| b.slot == slot)?;
        match resolved.get(b.resource)? {
            Resolved::Image { extent, .. } => Some((b, *extent)),
            Resolved::Buffer(_) => None,
        }
    };
    let ((_, depth), (hiz_binding, hiz)) = (image("depth")?, image("hiz")?);
    let want: vk::Extent2D = pyramid_size(depth);
    if (hiz.width, hiz.height) == (want.width, want.height) {
        // (A pyramid of this size cannot have more mips than the depth has levels below its own.)
        return None;
    }
    let name = &graph.resources[hiz_binding.resource].name;
    let message = format!(
        "pass '{}': the pyramid '{name}' is {}x{}; it must be {}x{}, half the depth's size {}x{} (size: \
         Fixed(\"max(1, width / 2)\", \"max(1, height / 2)\") for a full-screen depth)",
        pass.name, hiz.width, hiz.height, want.width, want.height, depth.width, depth.height
    );
    Some((hiz_binding.pos, message))
}
