//! Every shipped graph compiles to the plan it compiled to before the graphs were composed from
//! one another and pass kinds began to create their own resources: the same passes in the same
//! order with the same settings, each slot bound to a resource of the same description, class
//! and lifetime, behind the same barriers. Resources are named by their first binding (pass and
//! slot), not by the name a graph gives them, so that a buffer a kind now creates for its slot
//! compares equal to the one the graph used to declare. `tests/plans/NAME.txt` holds each plan;
//! `CULLGRAPH_WRITE_PLANS=1 cargo test --test shipped_plans` writes them anew (review the diff).

use cullgraph::gpu::ShaderRoot;
use cullgraph::graph::plan::{PlannedBarrier, ResolvedKind, Version};
use cullgraph::graph::{self, CompiledGraph, NoDevice};
use cullgraph::passes::builtin_kinds;
use cullgraph::passes::shared::frame_inputs;
use cullgraph::passes::SHIPPED_GRAPHS;
use cullgraph::scene::procedural;
use cullgraph::scene::source::LoadOptions;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

/// A resource's canonical name: the first binding of its current contents in execution order
/// (`pass.slot`), else of its last frame's (`pass.slot.prev`).
fn canonical_names(plan: &CompiledGraph) -> Vec<String> {
    (0..plan.resources.len())
        .map(|r| {
            let first = |version: Version| {
                plan.passes.iter().find_map(|p| {
                    let mut slots: Vec<&str> = p
                        .bindings
                        .iter()
                        .filter(|b| b.resource == r && b.version == version)
                        .map(|b| b.slot.as_str())
                        .collect();
                    slots.sort_unstable();
                    slots.first().map(|s| format!("{}.{s}", p.name))
                })
            };
            first(Version::Current)
                .or_else(|| first(Version::Previous).map(|n| format!("{n}.prev")))
                .unwrap_or_else(|| format!("unused {}", plan.resources[r].name))
        })
        .collect()
}

fn describe(kind: &ResolvedKind) -> String {
    match kind {
        ResolvedKind::Image { format, extent, mip_levels, samples, usage } => format!(
            "image {format:?} {}x{} mips {mip_levels} samples {} usage {usage:?}",
            extent.width,
            extent.height,
            samples.as_raw()
        ),
        ResolvedKind::Buffer { size, usage } => format!("buffer {size} B usage {usage:?}"),
    }
}

fn barrier(names: &[String], b: &PlannedBarrier) -> String {
    let prev = if b.version == Version::Previous { ".prev" } else { "" };
    let src = b.src.map_or("first use".to_string(), |s| format!("{:?} {:?} {:?}", s.stage, s.access, s.layout));
    format!(
        "barrier {}{prev}: {src} -> {:?} {:?} {:?}{}",
        names[b.resource],
        b.dst.stage,
        b.dst.access,
        b.dst.layout,
        if b.discard { " discard" } else { "" }
    )
}

/// The plan in a form that does not depend on what the graph calls its resources.
fn canonical(plan: &CompiledGraph) -> String {
    let names = canonical_names(plan);
    let mut out = String::new();
    for (i, pass) in plan.passes.iter().enumerate() {
        let settings: Vec<String> = pass.settings.iter().map(|(k, v)| format!("{k}={v:?}")).collect();
        writeln!(out, "pass {i} {} ({}) {}", pass.name, pass.kind, settings.join(", ")).unwrap();
        let mut bindings: Vec<String> = pass
            .bindings
            .iter()
            .map(|b| {
                let prev = if b.version == Version::Previous { ".prev" } else { "" };
                format!("  slot {} = {}{prev} {:?}", b.slot, names[b.resource], b.usage)
            })
            .collect();
        bindings.sort();
        let mut barriers: Vec<String> = pass.barriers.iter().map(|b| format!("  {}", barrier(&names, b))).collect();
        barriers.sort();
        for line in bindings.iter().chain(&barriers) {
            writeln!(out, "{line}").unwrap();
        }
    }
    let mut resources: BTreeMap<&str, String> = BTreeMap::new();
    for (r, res) in plan.resources.iter().enumerate() {
        if res.lifetime.is_none() {
            continue;
        }
        let line = format!("{:?} {} lifetime {:?}", res.class, describe(&res.kind), res.lifetime);
        resources.insert(&names[r], line);
    }
    for (name, line) in resources {
        writeln!(out, "resource {name}: {line}").unwrap();
    }
    let outputs: Vec<&str> = plan.outputs.iter().map(|&r| names[r].as_str()).collect();
    writeln!(out, "outputs {}", outputs.join(", ")).unwrap();
    for p in &plan.pruned {
        writeln!(out, "pruned {} ({})", p.name, p.kind).unwrap();
    }
    out
}

#[test]
fn every_shipped_graph_compiles_to_its_recorded_plan() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/plans");
    let write = std::env::var_os("CULLGRAPH_WRITE_PLANS").is_some();
    let mut differ = Vec::new();
    for (name, plan) in shipped_plans() {
        let text = canonical(&plan);
        let file = dir.join(format!("{name}.txt"));
        if write {
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(&file, &text).unwrap();
            continue;
        }
        let recorded = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        if recorded != text {
            let first = recorded.lines().zip(text.lines()).find(|(a, b)| a != b);
            differ.push(format!("{name}: first difference {first:?}"));
        }
    }
    assert!(differ.is_empty(), "plans changed:\n{}", differ.join("\n"));
}

/// Graph examples that use only built-in kinds.
const EXAMPLES: [&str; 7] =
    ["msaa_overlay", "tint", "history", "hiz_debug", "host_target", "host_depth_and_pyramid", "user_tint"];

/// Every shipped graph and example compiled for a city of 1,000 instances at 320x240.
fn shipped_plans() -> Vec<(String, CompiledGraph)> {
    let env = NoDevice::new(ShaderRoot::Embedded).expect("shaderc");
    let options = LoadOptions { instances: Some(1000), ..Default::default() };
    let scene = procedural::generate("builtin:city", &options).unwrap();
    let inputs = frame_inputs(&builtin_kinds(), &scene, 320, 240).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources: Vec<(String, String, String)> =
        SHIPPED_GRAPHS.iter().map(|g| (g.name.to_string(), g.text.to_string(), g.file.to_string())).collect();
    for name in EXAMPLES {
        let file = format!("graph/examples/{name}.ron");
        sources.push((format!("examples-{name}"), std::fs::read_to_string(root.join(&file)).unwrap(), file));
    }
    sources
        .into_iter()
        .map(|(name, text, file)| {
            let path = root.join(&file);
            let g = graph::load_in(&text, &file, path.parent(), &[], &env, &builtin_kinds())
                .unwrap_or_else(|e| panic!("{e}"));
            (name, graph::compile(&g, &inputs).unwrap_or_else(|e| panic!("{e}")))
        })
        .collect()
}
