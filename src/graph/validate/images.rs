//! Image checks: the formats each slot accepts, sample counts within a pass, and the device's
//! support for each image's format with the union of its usages and its sample count.

use super::Validator;
use crate::graph::compile::resolve::sample_flags;
use crate::graph::error::Pos;
use crate::graph::formats;
use crate::graph::kinds::FormatRule;
use crate::graph::usage::Usage;
use crate::graph::validated::{ResourceDesc, ValidatedGraph};
use ash::vk;

pub(super) fn check(v: &mut Validator<'_>, graph: &ValidatedGraph, samples: &[u32]) {
    for (pos, message) in format_errors(graph) {
        v.err(pos, message);
    }
    for (pos, message) in sample_errors(graph, samples) {
        v.err(pos, message);
    }
    for (r, res) in graph.resources.iter().enumerate() {
        let ResourceDesc::Image { format, format_pos, .. } = &res.desc else { continue };
        if *format == vk::Format::UNDEFINED {
            continue;
        }
        let usage = image_usage(graph, r);
        if usage.is_empty() {
            continue;
        }
        let count = samples.get(r).copied().unwrap_or(1);
        if let Err(reason) = v.env.check_image_format(*format, usage, sample_flags(count)) {
            v.err(
                *format_pos,
                format!(
                    "'{}' ({}, {count} sample(s), usage {usage:?}) is not supported by the device: {reason}",
                    res.name,
                    formats::name(*format)
                ),
            );
        }
    }
}

/// Every usage of image `r` by any pass, plus transfer source for outputs (the host copies them)
/// and transfer destination for history images (cleared before their first frame).
pub(crate) fn image_usage(graph: &ValidatedGraph, r: usize) -> vk::ImageUsageFlags {
    let mut usage = vk::ImageUsageFlags::empty();
    for b in graph.passes.iter().flat_map(|p| &p.bindings).filter(|b| b.resource == r) {
        usage |= b.usage.image_usage();
    }
    if graph.outputs.contains(&r) {
        usage |= vk::ImageUsageFlags::TRANSFER_SRC;
    }
    if graph.resources[r].history {
        usage |= vk::ImageUsageFlags::TRANSFER_DST;
    }
    usage
}

fn is_storage_image(u: Usage) -> bool {
    matches!(u, Usage::StorageImageRead(_) | Usage::StorageImageWrite(_) | Usage::StorageImageReadWrite(_))
}

/// Formats that a slot's rule (or its usage) does not accept.
fn format_errors(graph: &ValidatedGraph) -> Vec<(Pos, String)> {
    let mut out = Vec::new();
    for (p, pass) in graph.passes.iter().enumerate() {
        let kind = graph.kind(p);
        for b in &pass.bindings {
            let res = &graph.resources[b.resource];
            let ResourceDesc::Image { format, .. } = res.desc else { continue };
            if format == vk::Format::UNDEFINED {
                continue;
            }
            let rule = kind.and_then(|k| k.slot(&b.slot)).map_or(FormatRule::Any, |s| s.format);
            let depth = formats::is_depth(format);
            let needs = match rule {
                FormatRule::Exact(f) if f != format => Some(formats::name(f)),
                FormatRule::OneOf(fs) if !fs.contains(&format) => {
                    Some(fs.iter().map(|&f| formats::name(f)).collect::<Vec<_>>().join(" or "))
                }
                FormatRule::Depth if !depth => Some("a depth format".to_string()),
                FormatRule::DepthStencil if !formats::has_stencil(format) => {
                    Some("a depth format with stencil (D24_UNORM_S8_UINT or D32_SFLOAT_S8_UINT)".to_string())
                }
                FormatRule::Color if depth => Some("a color format".to_string()),
                _ if b.usage.needs_depth_format() && !depth => Some("a depth format".to_string()),
                _ if (b.usage.is_attachment() || is_storage_image(b.usage))
                    && !b.usage.needs_depth_format()
                    && depth =>
                {
                    Some("a color format".to_string())
                }
                _ => None,
            };
            if let Some(needs) = needs {
                let dir = if b.in_writes { "writes" } else { "reads" };
                out.push((
                    b.pos,
                    format!(
                        "pass '{}' {dir} \"{}\": '{}' is {} but the slot needs {needs}",
                        pass.name,
                        b.written_slot,
                        res.name,
                        formats::name(format)
                    ),
                ));
            }
        }
    }
    out
}

/// Attachments of one pass with different sample counts, multisampled inputs of a built-in
/// pass (whose shader is compiled for one sample count) with different sample counts, and
/// multisampled images in slots that take single-sampled ones. A pass may read multisampled
/// inputs while drawing single-sampled attachments (a resolve, or a forward pass that tests
/// against a multisampled depth in its shader).
pub(crate) fn sample_errors(graph: &ValidatedGraph, samples: &[u32]) -> Vec<(Pos, String)> {
    let mut out = Vec::new();
    for pass in &graph.passes {
        // The first attachment, and the first multisampled input.
        let mut firsts: [Option<(&str, u32)>; 2] = [None, None];
        for b in &pass.bindings {
            let res = &graph.resources[b.resource];
            if !res.is_image() {
                continue;
            }
            let n = samples.get(b.resource).copied().unwrap_or(1);
            let group = if b.usage.is_attachment() {
                Some(0)
            } else if b.multisample_ok && pass.kind != crate::graph::kinds::COMPUTE_KIND {
                Some(1)
            } else {
                None
            };
            if let Some(group) = group {
                let first = &mut firsts[group];
                match *first {
                    None => *first = Some((&res.name, n)),
                    Some((name, m)) if m != n => {
                        out.push((
                            b.pos,
                            format!(
                                "pass '{}' mixes sample counts: '{name}' has {m}, '{}' has {n} \
                                 (its attachments need one sample count, and so do its multisampled inputs)",
                                pass.name, res.name
                            ),
                        ));
                        continue;
                    }
                    _ => {}
                }
            }
            if n == 1 && b.multisample_ok && pass.kind == crate::graph::kinds::COMPUTE_KIND {
                let dir = if b.in_writes { "writes" } else { "reads" };
                out.push((
                    b.pos,
                    format!(
                        "pass '{}' {dir} \"{}\": the shader declares a multisampled image (sampler2DMS) but '{}' \
                         has 1 sample",
                        pass.name, b.written_slot, res.name
                    ),
                ));
                continue;
            }
            if n > 1 && !b.multisample_ok {
                let dir = if b.in_writes { "writes" } else { "reads" };
                out.push((
                    b.pos,
                    format!(
                        "pass '{}' {dir} \"{}\": '{}' has {n} samples but the slot takes single-sampled images",
                        pass.name, b.written_slot, res.name
                    ),
                ));
            }
        }
    }
    out
}
