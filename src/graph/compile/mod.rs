//! The compiler: a [`ValidatedGraph`] plus one frame configuration (output size, scene
//! quantities, param overrides) becomes a [`CompiledGraph`]: pruned ([`prune`]), ordered
//! ([`order`], from the dependencies of [`flow`]), with lifetimes ([`lifetimes`]), transient
//! memory placed ([`memory`]) and barriers planned ([`barriers`]); values come from [`resolve`].

pub mod barriers;
pub mod device_limits;
pub mod flow;
pub mod lifetimes;
pub mod memory;
pub mod order;
pub mod prune;
pub mod resolve;

use super::error::{GraphErrors, Sink};
use super::kinds::KindCheck;
use super::kinds::SettingOverride;
use super::plan::{Binding, CompiledGraph, MemoryPlan, PlannedPass, PlannedResource, ResolvedKind, ResourceClass};
use super::quantity::Quantities;
use super::validate::{apply_overrides, ParamOverride};
use super::validated::{ParamValue, ValidatedGraph};
use ash::vk;
use resolve::Resolved;
use std::collections::HashMap;

/// What a compiled graph depends on besides the file: the output size, the scene's quantities
/// (the variables of expressions) and param overrides on top of the ones given when loading.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameInputs {
    /// Output width in pixels (`width`).
    pub width: u32,
    /// Output height in pixels (`height`).
    pub height: u32,
    /// The scene's quantities by name (`instances`, `meshes`, ...), as the host counted them
    /// ([`crate::graph::KindRegistry::count`]). One the graph uses but the host did not give
    /// counts as 0.
    pub quantities: Quantities,
    /// `name=value` param overrides (applied after the load-time ones).
    pub params: Vec<ParamOverride>,
    /// Settings of passes to change (after the params), as a kind's adaptation asks
    /// ([`crate::graph::Adaptation`]).
    pub settings: Vec<SettingOverride>,
}

impl FrameInputs {
    /// An output size with an empty scene.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, ..Default::default() }
    }

    /// The output size with `quantities`.
    pub fn with_quantities(width: u32, height: u32, quantities: Quantities) -> Self {
        Self { width, height, quantities, ..Default::default() }
    }

    /// The value of quantity `name` (0 when the host gave none).
    pub fn quantity(&self, name: &str) -> u64 {
        self.quantities.get(name).unwrap_or(0)
    }
}

/// Compiles `graph` for one frame configuration. Errors (values out of range for this frame,
/// bad overrides) carry file positions like load errors.
pub fn compile(graph: &ValidatedGraph, frame: &FrameInputs) -> Result<CompiledGraph, GraphErrors> {
    profiling::scope!("cullgraph::compile_graph", graph.name.as_str());
    let mut sink = Sink::new(&graph.files);
    let max = resolve::MAX_IMAGE_DIMENSION;
    if frame.width == 0 || frame.height == 0 || frame.width > max || frame.height > max {
        sink.command_line(format!("output size {}x{} must be 1 to {max} in each dimension", frame.width, frame.height));
    }
    let mut params = graph.params.clone();
    apply_overrides(&mut params, &frame.params, &mut sink);
    let quantities: Vec<&str> = graph.kinds.quantities().map(|q| q.name).collect();
    let frame_vars = resolve::frame_variables(frame, &quantities);
    let vars = resolve::variables(&params, frame, &quantities);
    let mut errors = resolve::Errors { files: &graph.files, list: Vec::new() };
    // A resource absent in this frame takes its bindings with it (validation let only optional
    // slots bind it): the frame is compiled as if the graph never bound it.
    let present = resolve::present(graph, &vars, &mut errors);
    let trimmed;
    let graph = if present.iter().all(|&p| p) {
        graph
    } else {
        trimmed = without_absent(graph, &present);
        &trimmed
    };
    let param_values: HashMap<&str, &ParamValue> = params.iter().map(|p| (p.name.as_str(), &p.value)).collect();
    // Settings first: what a kind creates may be sized by its pass's settings.
    let mut settings: Vec<_> = (0..graph.passes.len())
        .map(|p| {
            let declared = graph.kind(p).map(|k| k.settings.as_slice()).unwrap_or(&[]);
            resolve::settings(&graph.passes[p], declared, &param_values, &vars, &mut errors)
        })
        .collect();
    resolve::setting_overrides(graph, &frame.settings, &mut settings, &mut sink);
    let resolved = resolve::resources(graph, &vars, &frame_vars, &settings, frame, &mut errors);
    let samples: Vec<u32> = resolved
        .iter()
        .map(|r| match r {
            Resolved::Image { samples, .. } => *samples,
            Resolved::Buffer(_) => 1,
        })
        .collect();
    for (pos, message) in super::validate::sample_errors(graph, &samples) {
        sink.at(pos, message);
    }

    let pruning = prune::prune(graph);
    let names: Vec<String> = graph.resources.iter().map(|r| r.name.clone()).collect();
    // Every kept pass as planned, its barriers still to come.
    let mut planned: Vec<Option<PlannedPass>> = (0..graph.passes.len())
        .map(|p| {
            let pass = &graph.passes[p];
            pruning.keep[p].then(|| PlannedPass {
                name: pass.name.clone(),
                kind: pass.kind.clone(),
                bindings: pass
                    .bindings
                    .iter()
                    .map(|b| Binding { slot: b.slot.clone(), resource: b.resource, version: b.version, usage: b.usage })
                    .collect(),
                settings: settings[p].clone(),
                shader: pass.shader.clone(),
                dispatch: resolve::dispatch(pass, &resolved, &names, &vars, &mut errors),
                barriers: Vec::new(),
                pos: pass.pos,
            })
        })
        .collect();
    // What the kept passes need of their resources. (Sizes that failed to resolve stand in as
    // 4 bytes: no size errors on top of those.)
    if errors.list.is_empty() {
        let errs = super::validate::slot_size_errors(graph, &pruning.keep, &resolved, &frame_vars, &settings);
        for (pos, message) in errs {
            sink.at(pos, message);
        }
        for (pos, message) in device_limits::limit_errors(graph, &pruning.keep, &resolved) {
            sink.at(pos, message);
        }
        for (pass, plan) in graph.passes.iter().zip(&planned) {
            let (Some(kind), Some(plan)) = (graph.kinds.get(&pass.kind), plan) else { continue };
            let check = KindCheck {
                graph,
                pass,
                samples: &samples,
                resolved: &resolved,
                planned: Some(plan),
                limits: graph.limits.as_ref(),
                quantities: Some(&frame.quantities),
            };
            for (pos, message) in kind.kind.check_compiled(&check) {
                sink.at(pos, message);
            }
        }
    }
    let kept: Vec<usize> = (0..graph.passes.len()).filter(|&p| pruning.keep[p]).collect();
    let flows = flow::flows(graph, &pruning.keep);
    let deps = flow::dependencies(&flows);
    let Some(order) = order::execution_order(&kept, &deps) else {
        sink.at(graph.passes.first().map_or_else(Default::default, |p| p.pos), "cycle among the passes");
        return Err(GraphErrors::sorted(sink.errors));
    };
    let lifetimes = lifetimes::lifetimes(graph, &order);

    let is_image: Vec<bool> = resolved.iter().map(|r| matches!(r, Resolved::Image { .. })).collect();
    let barriers = barriers::plan_barriers(graph, &order, &is_image);
    let mut passes = Vec::with_capacity(order.len());
    for (pos, &p) in order.iter().enumerate() {
        let Some(mut pass) = planned[p].take() else { continue };
        pass.barriers = barriers[pos].clone();
        passes.push(pass);
    }

    let mut resources = Vec::with_capacity(graph.resources.len());
    for (r, res) in graph.resources.iter().enumerate() {
        let class = if res.imported {
            ResourceClass::Imported
        } else if res.history {
            ResourceClass::History
        } else if graph.outputs.contains(&r) {
            ResourceClass::Output
        } else {
            ResourceClass::Transient
        };
        let users = order.iter().flat_map(|&p| &graph.passes[p].bindings).filter(|b| b.resource == r);
        let kind = match resolved[r] {
            Resolved::Image { format, extent, mips, samples } => {
                let mut usage = users.fold(vk::ImageUsageFlags::empty(), |u, b| u | b.usage.image_usage());
                if graph.outputs.contains(&r) {
                    usage |= vk::ImageUsageFlags::TRANSFER_SRC;
                }
                ResolvedKind::Image { format, extent, mip_levels: mips, samples: resolve::sample_flags(samples), usage }
            }
            Resolved::Buffer(size) => {
                let mut usage = users.fold(vk::BufferUsageFlags::empty(), |u, b| u | b.usage.buffer_usage());
                if graph.outputs.contains(&r) {
                    usage |= vk::BufferUsageFlags::TRANSFER_SRC;
                }
                ResolvedKind::Buffer { size, usage }
            }
        };
        let owner = res.owner.as_ref().map(|o| o.pass_name.clone());
        resources.push(PlannedResource {
            name: res.name.clone(),
            kind,
            class,
            lifetime: lifetimes[r],
            pos: res.pos,
            owner,
        });
    }

    let items: Vec<Option<memory::MemoryItem>> = resources
        .iter()
        .zip(&resolved)
        .map(|(r, res)| match (r.class, r.lifetime) {
            (ResourceClass::Transient, Some(l)) => Some(memory::estimate(res, l)),
            _ => None,
        })
        .collect();
    let (placements, heaps) = memory::plan_memory(&items);
    let memory = MemoryPlan {
        placements,
        // Each in memory of its own, at the same alignment.
        bytes_without_aliasing: items
            .iter()
            .flatten()
            .map(|i| i.size.div_ceil(i.alignment.max(1)) * i.alignment.max(1))
            .sum(),
        bytes_with_aliasing: heaps.iter().sum(),
        heaps,
    };

    sink.errors.extend(errors.list);
    sink.into_result(CompiledGraph {
        name: graph.name.clone(),
        file: graph.file.clone(),
        files: graph.files.clone(),
        passes,
        pruned: pruning.pruned,
        resources,
        outputs: graph.outputs.clone(),
        output_pos: graph.output_pos.clone(),
        memory,
        kinds: graph.kinds.clone(),
    })
}

/// `graph` without the bindings of the resources that `present` says are absent.
fn without_absent(graph: &ValidatedGraph, present: &[bool]) -> ValidatedGraph {
    let mut trimmed = graph.clone();
    for pass in &mut trimmed.passes {
        pass.bindings.retain(|b| present[b.resource]);
    }
    trimmed
}
