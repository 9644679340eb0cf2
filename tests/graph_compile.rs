//! The compiler on CPU: the default graph and its exact barrier plan, pruning with reasons,
//! history reads without edges, deterministic order, aliasing, read-after-read and layout
//! changes, compile-time errors, the printed plan and graphviz, and a 200-pass graph.

mod graph_kinds;

use ash::vk;
use cullgraph::gpu::{Access, ShaderRoot};
use cullgraph::graph::plan::{Placement, PlannedBarrier, SettingValue, Version};
use cullgraph::graph::{self, CompiledGraph, FrameInputs, NoDevice, ResourceClass, Stages, Usage, ValidatedGraph};
use cullgraph::passes::builtin_kinds;
use std::path::Path;

fn env() -> NoDevice {
    NoDevice::new(ShaderRoot::Embedded).expect("shaderc")
}

/// The simplest shipped frame (G-buffer, lighting): `graph/no_cull.ron`.
fn default_graph() -> ValidatedGraph {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("graph/no_cull.ron");
    graph::load_file(&path, &[], &env(), &builtin_kinds()).unwrap_or_else(|e| panic!("{e}"))
}

fn load_test(text: &str) -> ValidatedGraph {
    graph::load(text, "test.ron", &[], &env(), &graph_kinds::test_kinds()).unwrap_or_else(|e| panic!("{e}"))
}

fn compile(g: &ValidatedGraph) -> CompiledGraph {
    graph::compile(g, &FrameInputs::new(1280, 720)).unwrap_or_else(|e| panic!("{e}"))
}

fn order(c: &CompiledGraph) -> Vec<&str> {
    c.passes.iter().map(|p| p.name.as_str()).collect()
}

const COLOR_OUT: Access = Access {
    stage: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    access: vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
    layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
};

#[test]
fn default_graph_compiles_to_the_fixed_frame() {
    let g = default_graph();
    let c = compile(&g);
    assert_eq!(order(&c), ["gbuffer", "lighting", "tonemap", "transparent_sort", "transparent"]);
    assert!(c.pruned.is_empty());
    let lighting = &c.passes[1];
    assert_eq!(lighting.settings.get("exposure"), Some(&SettingValue::Float(0.8)));
    assert_eq!(lighting.settings.get("debug_view"), Some(&SettingValue::Choice("none".into())));
    let names: Vec<&str> = c.outputs.iter().map(|&r| c.resources[r].name.as_str()).collect();
    assert_eq!(names, ["color"]);
    let color = c.resources.iter().find(|r| r.name == "color").expect("color");
    assert_eq!(color.class, ResourceClass::Output);
    match &color.kind {
        graph::plan::ResolvedKind::Image { format, extent, usage, .. } => {
            assert_eq!(*format, vk::Format::R8G8B8A8_UNORM);
            assert_eq!((extent.width, extent.height), (1280, 720));
            // Tone-mapped in compute, blended over by the transparent pass, copied out.
            assert_eq!(
                *usage,
                vk::ImageUsageFlags::STORAGE
                    | vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::TRANSFER_SRC
            );
        }
        other => panic!("color is {other:?}"),
    }
    // Params overridden at compile time reach the settings.
    let mut frame = FrameInputs::new(640, 480);
    frame.params = vec![("exposure".into(), "1.5".into()), ("debug_view".into(), "normals".into())];
    let c = graph::compile(&g, &frame).expect("compiles");
    assert_eq!(c.passes[1].settings.get("exposure"), Some(&SettingValue::Float(1.5)));
    assert_eq!(c.passes[1].settings.get("debug_view"), Some(&SettingValue::Choice("normals".into())));
    // A bad override is an error with a position, not a panic.
    frame.params = vec![("debug_view".into(), "wireframe".into())];
    let e = graph::compile(&g, &frame).expect_err("bad choice").to_string();
    assert!(e.contains("param 'debug_view' is \"wireframe\", not one of none, normals, albedo, depth"), "{e}");
}

#[test]
fn shipped_graphs_load_and_compile() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (file, passes) in [
        ("graph/default.ron", 8),
        ("graph/no_cull.ron", 5),
        ("graph/frustum.ron", 6),
        ("graph/two_phase.ron", 8),
        ("graph/one_phase.ron", 7),
        ("graph/occluder_prepass.ron", 9),
        ("graph/examples/tint.ron", 3),
        ("graph/examples/history.ron", 3),
        ("graph/examples/host_target.ron", 3),
        ("graph/examples/host_depth_and_pyramid.ron", 3),
    ] {
        let g = graph::load_file(&root.join(file), &[], &env(), &builtin_kinds()).unwrap_or_else(|e| panic!("{e}"));
        let c = compile(&g);
        assert_eq!((c.passes.len(), c.pruned.len()), (passes, 0), "{file}");
    }
    // The compute pass of tint.ron: binding 0 sampled, binding 1 written, 8x8 workgroups.
    let tint = graph::load_file(&root.join("graph/examples/tint.ron"), &[], &env(), &builtin_kinds()).expect("tint");
    let c = compile(&tint);
    let pass = &c.passes[2];
    let slots: Vec<(&str, Usage)> = pass.bindings.iter().map(|b| (b.slot.as_str(), b.usage)).collect();
    assert_eq!(slots, [("0", Usage::Sampled(Stages::Compute)), ("1", Usage::StorageImageWrite(Stages::Compute))]);
    assert_eq!(pass.dispatch, Some([160, 90, 1]));
    assert_eq!(pass.shader.as_deref(), Some(root.join("graph/examples/tint.comp").as_path()));
}

/// `g` compiled for a scene with emission or occlusion (the `emissive_occlusion` target exists).
fn compile_with_emission(g: &ValidatedGraph) -> CompiledGraph {
    let quantities = cullgraph::graph::Quantities::new().with("emission_or_occlusion", 1);
    graph::compile(g, &FrameInputs::with_quantities(1280, 720, quantities)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_scene_without_emission_or_occlusion_gets_no_emissive_occlusion_target() {
    let g = default_graph();
    let (with, without) = (compile_with_emission(&g), compile(&g));
    let bound = |c: &CompiledGraph| {
        c.passes
            .iter()
            .flat_map(|p| &p.bindings)
            .filter(|b| c.resources[b.resource].name == "emissive_occlusion")
            .count()
    };
    // Written by the G-buffer, read by the lighting; in neither without it.
    assert_eq!((bound(&with), bound(&without)), (2, 0));
    let target = |c: &CompiledGraph| c.resources.iter().find(|r| r.name == "emissive_occlusion").unwrap().lifetime;
    assert!(target(&with).is_some());
    assert_eq!(target(&without), None, "a resource no pass uses is not created");
    // The rest of the frame is the same.
    assert_eq!(order(&with), order(&without));
    assert_eq!(with.passes[0].barriers.len(), without.passes[0].barriers.len() + 1);
}

#[test]
fn default_graph_barrier_plan_is_exactly_this() {
    let c = compile_with_emission(&default_graph());
    let id = |n: &str| c.resources.iter().position(|r| r.name == n).expect("resource");
    let depth_write = Access {
        stage: vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
        access: vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
        layout: vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
    };
    let sampled = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::SHADER_SAMPLED_READ,
        layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    };
    let storage_write = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::SHADER_STORAGE_WRITE,
        layout: vk::ImageLayout::GENERAL,
    };
    let b = |r: &str, src: Option<Access>, dst: Access, discard: bool| PlannedBarrier {
        resource: id(r),
        version: Version::Current,
        src,
        dst,
        discard,
    };
    // gbuffer: every target is first used here; contents are discarded.
    assert_eq!(
        c.passes[0].barriers,
        vec![
            b("albedo", None, COLOR_OUT, true),
            b("normal", None, COLOR_OUT, true),
            b("emissive_occlusion", None, COLOR_OUT, true),
            b("depth", None, depth_write, true)
        ]
    );
    // lighting: the G-buffer becomes readable in compute (read after write, layout change);
    // the output is first used here. The depth is read again by the transparent pass's fragment
    // shader, so its one barrier covers both readers.
    let sampled_by_both =
        Access { stage: vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COMPUTE_SHADER, ..sampled };
    assert_eq!(
        c.passes[1].barriers,
        vec![
            b("depth", Some(depth_write), sampled_by_both, false),
            b("albedo", Some(COLOR_OUT), sampled, false),
            b("normal", Some(COLOR_OUT), sampled, false),
            b("emissive_occlusion", Some(COLOR_OUT), sampled, false),
            b("hdr", None, storage_write, true),
        ]
    );
}

#[test]
fn pruning_says_which_and_why() {
    let c = compile(&load_test(
        r#"Graph(
    name: "prune",
    resources: {
        "a": Image(format: R8G8B8A8_UNORM),
        "debug": Image(format: R8G8B8A8_UNORM),
        "scratch": Image(format: R8G8B8A8_UNORM),
        "hist": Image(format: R8G8B8A8_UNORM, history: true),
        "out": Image(format: R8G8B8A8_UNORM),
        "host": Imported(Buffer(size: 64)),
    },
    passes: [
        Pass(name: "make", kind: "img", writes: {"storage_write": "a"}),
        Pass(name: "debug_view", kind: "img", reads: {"sampled": "a"}, writes: {"storage_write": "debug"}),
        Pass(name: "dead_write", kind: "img", writes: {"storage_write": "scratch"}),
        Pass(name: "overwrite", kind: "img", writes: {"storage_write": "scratch"}),
        Pass(name: "use_scratch", kind: "img", reads: {"sampled": "scratch"}, writes: {"storage_write": "out"}),
        Pass(name: "feed_debug", kind: "img", reads: {"sampled": "debug"}, writes: {"color": "hist"}),
        Pass(name: "history_user", kind: "img", reads: {"sampled": "hist.prev"}, writes: {"storage_write": "debug"}),
        Pass(name: "to_host", kind: "buf", writes: {"storage_write": "host"}),
        Pass(name: "final", kind: "img", reads: {"sampled": "a"}, writes: {"storage_rw": "out"}),
    ],
    outputs: ["out"],
)"#,
    ));
    assert_eq!(order(&c), ["make", "overwrite", "use_scratch", "to_host", "final"]);
    let pruned: Vec<(&str, &str)> = c.pruned.iter().map(|p| (p.name.as_str(), p.reason.as_str())).collect();
    assert_eq!(
        pruned,
        [
            ("debug_view", "'debug' is read only by pruned 'feed_debug'"),
            ("dead_write", "'scratch' is overwritten by 'overwrite' before anything reads it"),
            ("feed_debug", "'hist' is read next frame only by pruned 'history_user'"),
            ("history_user", "'debug' is never read"),
        ]
    );
    // Pruned passes keep their bindings for reports and graphviz.
    assert_eq!(c.pruned[0].kind, "img");
    assert_eq!(c.pruned[0].bindings.len(), 2);
}

/// The two-phase occlusion shape: `cull` reads last frame's Hi-Z, `draw` uses its result,
/// `hiz` builds this frame's pyramid from the depth. Reading `hiz.prev` creates no edge.
const HISTORY: &str = r#"Graph(
    name: "history",
    resources: {
        "hiz": Image(format: R32_SFLOAT, mips: All, history: true),
        "visible": Buffer(size: "ceil_div(instances, 32) * 4"),
        "depth": Image(format: R32_SFLOAT),
        "out": Image(format: R8G8B8A8_UNORM),
    },
    passes: [
        Pass(name: "hiz", kind: "mix", reads: {"i_sampled": "depth"}, writes: {"i_write": "hiz"}),
        Pass(name: "cull", kind: "mix", reads: {"i_sampled": "hiz.prev"}, writes: {"b_write": "visible"}),
        Pass(name: "draw", kind: "mix", reads: {"b_read": "visible"}, writes: {"i_write": "depth", "i_write2": "out"}),
    ],
    outputs: ["out"],
)"#;

#[test]
fn history_prev_reads_are_valid_and_create_no_edge() {
    let g = load_test(HISTORY);
    let hiz = g.resource_id("hiz").expect("hiz");
    let c = compile(&g);
    // Declared first but it reads the depth `draw` writes: runs last, after `cull`, which reads
    // its `.prev`: that read made no edge from `hiz` to `cull`.
    assert_eq!(order(&c), ["cull", "draw", "hiz"]);
    assert!(c.pruned.is_empty(), "hiz is kept because a kept pass reads hiz.prev: {:?}", c.pruned);
    assert_eq!(c.resources[hiz].class, ResourceClass::History);
    assert_eq!(c.resources[hiz].lifetime, Some((2, 2)));
    match &c.resources[hiz].kind {
        graph::plan::ResolvedKind::Image { mip_levels, .. } => assert_eq!(*mip_levels, 11),
        other => panic!("{other:?}"),
    }
    // Last frame's copy is first used by `cull` (src filled by the executor, contents kept).
    let prev = c.passes[0].barriers.iter().find(|b| b.resource == hiz).expect("barrier for hiz.prev");
    assert_eq!((prev.version, prev.src, prev.discard), (Version::Previous, None, false));
}

#[test]
fn order_is_deterministic_and_prefers_declaration_order() {
    let text = r#"Graph(
    name: "order",
    resources: {
        "a": Image(format: R8G8B8A8_UNORM),
        "b": Image(format: R8G8B8A8_UNORM),
        "c": Image(format: R8G8B8A8_UNORM),
        "out": Image(format: R8G8B8A8_UNORM),
    },
    passes: [
        Pass(name: "use_b", kind: "mix", reads: {"i_sampled": "b"}, writes: {"i_write": "c"}),
        Pass(name: "make_a", kind: "mix", writes: {"i_write": "a"}),
        Pass(name: "make_b", kind: "mix", reads: {"i_sampled": "a"}, writes: {"i_write": "b"}),
        Pass(name: "independent", kind: "mix", writes: {"i_write": "out"}),
        Pass(name: "finish", kind: "mix", reads: {"i_sampled": "c", "i_sampled2": "a"}, writes: {"i_rw": "out"}),
    ],
    outputs: ["out"],
)"#;
    let first = compile(&load_test(text));
    assert_eq!(order(&first), ["make_a", "make_b", "use_b", "independent", "finish"]);
    for _ in 0..20 {
        assert_eq!(compile(&load_test(text)), first);
    }
}

#[test]
fn write_after_read_and_write_after_write_are_ordered() {
    // `early_reader` is declared before any writer of `x`, so it sees the first write (w1);
    // `late_reader` sees the latest write declared before it (w2).
    let c = compile(&load_test(
        r#"Graph(
    name: "hazards",
    resources: {
        "x": Image(format: R8G8B8A8_UNORM),
        "out": Image(format: R8G8B8A8_UNORM),
    },
    passes: [
        Pass(name: "early_reader", kind: "mix", reads: {"i_sampled": "x"}, writes: {"i_write": "out"}),
        Pass(name: "w1", kind: "mix", writes: {"i_write": "x"}),
        Pass(name: "w2", kind: "mix", writes: {"i_rw": "x"}),
        Pass(name: "late_reader", kind: "mix", reads: {"i_sampled": "x"}, writes: {"i_rw": "out"}),
    ],
    outputs: ["out"],
)"#,
    ));
    // early_reader sees the first write (w1), so it runs after w1 and before w2 (WAR).
    assert_eq!(order(&c), ["w1", "early_reader", "w2", "late_reader"]);
    let x = c.resources.iter().position(|r| r.name == "x").expect("x");
    let barrier = |pass: usize| c.passes[pass].barriers.iter().find(|b| b.resource == x).cloned();
    // w2 after a read: execution dependency on the reader's stage, layout change to GENERAL.
    let war = barrier(2).expect("WAR barrier");
    let src = war.src.expect("src");
    assert_eq!(src.stage, vk::PipelineStageFlags2::COMPUTE_SHADER);
    assert_eq!(src.access, vk::AccessFlags2::NONE);
    assert_eq!(src.layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
    assert_eq!(war.dst.layout, vk::ImageLayout::GENERAL);
}

#[test]
fn read_after_read_needs_no_barrier_but_a_layout_change_does() {
    let c = compile(&load_test(
        r#"Graph(
    name: "reads",
    resources: {
        "x": Image(format: R8G8B8A8_UNORM),
        "o1": Image(format: R8G8B8A8_UNORM),
        "o2": Image(format: R8G8B8A8_UNORM),
        "o3": Image(format: R8G8B8A8_UNORM),
    },
    passes: [
        Pass(name: "write", kind: "img", writes: {"storage_write": "x"}),
        Pass(name: "read1", kind: "img", reads: {"sampled": "x"}, writes: {"storage_write": "o1"}),
        Pass(name: "read2", kind: "img", reads: {"sampled_fs": "x"}, writes: {"color": "o2"}),
        Pass(name: "read3", kind: "img", reads: {"storage_read": "x"}, writes: {"storage_write": "o3"}),
    ],
    outputs: ["o1", "o2", "o3"],
)"#,
    ));
    assert_eq!(order(&c), ["write", "read1", "read2", "read3"]);
    let x = c.resources.iter().position(|r| r.name == "x").expect("x");
    let barriers =
        |pass: usize| c.passes[pass].barriers.iter().filter(|b| b.resource == x).cloned().collect::<Vec<_>>();
    // The barrier before the first reader makes the write visible to both samplers' stages...
    let raw = barriers(1);
    assert_eq!(raw.len(), 1);
    assert_eq!(raw[0].src.map(|s| s.access), Some(vk::AccessFlags2::SHADER_STORAGE_WRITE));
    assert_eq!(raw[0].dst.stage, vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER);
    assert_eq!(raw[0].dst.layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
    // ...so the second sampled read (same layout) needs none.
    assert!(barriers(2).is_empty());
    // A storage read needs GENERAL: one barrier, read -> read with a layout change.
    let change = barriers(3);
    assert_eq!(change.len(), 1);
    let src = change[0].src.expect("src");
    assert_eq!(src.layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
    assert_eq!(src.stage, vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER);
    assert_eq!(change[0].dst.layout, vk::ImageLayout::GENERAL);
    assert_eq!(change[0].dst.access, vk::AccessFlags2::SHADER_STORAGE_READ);
    // Buffers have no layouts: two reads after a write need one barrier.
    let c = compile(&load_test(
        r#"Graph(
    name: "buffer reads",
    resources: { "b": Buffer(size: 1024), "o": Image(format: R8G8B8A8_UNORM) },
    passes: [
        Pass(name: "fill", kind: "mix", writes: {"b_write": "b"}),
        Pass(name: "r1", kind: "mix", reads: {"b_read": "b"}, writes: {"i_write": "o"}),
        Pass(name: "r2", kind: "mix", reads: {"b_indirect": "b"}, writes: {"i_rw": "o"}),
    ],
    outputs: ["o"],
)"#,
    ));
    let count = |pass: usize| c.passes[pass].barriers.iter().filter(|b| b.resource == 0).count();
    assert_eq!((count(0), count(1), count(2)), (1, 1, 0));
    assert_eq!(
        c.passes[1].barriers[0].dst.stage,
        vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::DRAW_INDIRECT
    );
}

#[test]
fn aliasing_saves_memory_of_transients_that_do_not_overlap() {
    // A chain: t1 lives in passes 0..=1, t2 in 1..=2, t3 in 2..=3; t1 and t3 can share memory.
    let c = compile(&load_test(
        r#"Graph(
    name: "chain",
    resources: {
        "t1": Image(format: R8G8B8A8_UNORM),
        "t2": Image(format: R8G8B8A8_UNORM),
        "t3": Image(format: R8G8B8A8_UNORM),
        "out": Image(format: R8G8B8A8_UNORM),
        "imported": Imported(Image(format: R8G8B8A8_UNORM)),
    },
    passes: [
        Pass(name: "p0", kind: "img", reads: {"sampled": "imported"}, writes: {"storage_write": "t1"}),
        Pass(name: "p1", kind: "img", reads: {"sampled": "t1"}, writes: {"storage_write": "t2"}),
        Pass(name: "p2", kind: "img", reads: {"sampled": "t2"}, writes: {"storage_write": "t3"}),
        Pass(name: "p3", kind: "img", reads: {"sampled": "t3"}, writes: {"storage_write": "out"}),
    ],
    outputs: ["out"],
)"#,
    ));
    let bytes = 1280 * 720 * 4u64; // 3,686,400: 57 x 64 KiB rounded up is 3,735,552
    let aligned = bytes.div_ceil(65536) * 65536;
    let life = |n: &str| c.resources.iter().find(|r| r.name == n).and_then(|r| r.lifetime);
    assert_eq!((life("t1"), life("t2"), life("t3")), (Some((0, 1)), Some((1, 2)), Some((2, 3))));
    let p = &c.memory.placements;
    assert_eq!(p[0], Some(Placement { heap: 0, offset: 0 }));
    assert_eq!(p[1], Some(Placement { heap: 0, offset: aligned }));
    assert_eq!(p[2], Some(Placement { heap: 0, offset: 0 }), "t3 reuses t1's memory");
    assert_eq!((p[3], p[4]), (None, None), "outputs and imported resources are not aliased");
    assert_eq!(c.memory.bytes_without_aliasing, 3 * aligned);
    // The heap is allocated in whole alignment units.
    assert_eq!(c.memory.bytes_with_aliasing, 2 * aligned);
    assert_eq!(c.memory.heaps, vec![2 * aligned]);
    let report = c.to_string();
    assert!(
        report.contains("transient memory (estimated): 10.69 MiB without aliasing, 7.12 MiB with aliasing"),
        "{report}"
    );
}

#[test]
fn values_out_of_range_for_a_frame_are_errors_with_positions() {
    let g = load_test(
        r#"Graph(
    name: "sizes",
    resources: {
        "lights": Buffer(size: "(lights - 4) * 32"),
        "big": Image(format: R8_UNORM, size: Fixed("width * 20", 1)),
        "out": Image(format: R8G8B8A8_UNORM),
    },
    passes: [
        Pass(name: "p", kind: "mix", reads: {"b_read": "lights", "i_sampled": "big"}, writes: {"i_write": "out"}),
        Pass(name: "q", kind: "mix", writes: {"b_write": "lights", "i_write": "big"}),
    ],
    outputs: ["out"],
)"#,
    );
    let e = graph::compile(&g, &FrameInputs::new(1280, 720)).expect_err("negative size").to_string();
    assert_eq!(
        e,
        "test.ron:4:32: size of buffer 'lights' is negative (-128)\n\
         test.ron:5:52: width of image 'big' is 25600 (must be 1 to 16384)"
    );
    let mut frame = FrameInputs::new(640, 480);
    frame.quantities.set("lights", 10);
    let c = graph::compile(&g, &frame).expect("fits");
    assert!(matches!(c.resources[0].kind, graph::plan::ResolvedKind::Buffer { size: 192, .. }));
}

#[test]
fn plan_report_and_graphviz_show_everything() {
    let c = compile(&load_test(HISTORY));
    let text = c.to_string();
    for needle in [
        "graph 'history': 3 passes (0 pruned), 4 resources",
        "  0: cull (mix)",
        "barrier hiz.prev: first use in frame -> COMPUTE_SHADER SHADER_SAMPLED_READ, current -> SHADER_READ_ONLY_OPTIMAL",
        "barrier visible: COMPUTE_SHADER SHADER_STORAGE_WRITE -> COMPUTE_SHADER SHADER_STORAGE_READ",
        "hiz      history   image R32_SFLOAT 1280x720 mips 11 samples 1, passes 2..=2",
    ] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
    let dot = graph::to_dot(&c);
    assert!(dot.starts_with("digraph \"history\" {"));
    assert!(dot.contains("\"res:hiz\" -> \"pass:cull\" [label=\"read i_sampled (.prev)\", style=dashed];"), "{dot}");
    assert!(dot.contains("\"pass:draw\" -> \"res:depth\" [label=\"write i_write\"];"), "{dot}");
    let extra = "        Pass(name: \"unused\", kind: \"mix\", reads: {\"i_sampled\": \"depth\"}, writes: {\"b_write\": \"visible\"}),\n    ],";
    let pruned = compile(&load_test(&HISTORY.replacen("    ],", extra, 1)));
    assert_eq!(pruned.pruned.len(), 1, "{pruned}");
    let dot = graph::to_dot(&pruned);
    assert!(dot.contains("fillcolor=gray90"), "pruned passes are grey:\n{dot}");
}

/// A generated graph of 200 passes: a main chain with side branches, some history reads and
/// buffers. Prints the compile time (not asserted).
#[test]
fn compiles_a_200_pass_graph() {
    let n = 200;
    let mut resources = String::new();
    let mut passes = String::new();
    for i in 0..n {
        resources.push_str(&format!("        \"r{i}\": Image(format: R16G16B16A16_SFLOAT, size: Scaled(0.5)),\n"));
        resources.push_str(&format!("        \"b{i}\": Buffer(size: \"instances * 4 + {i}\"),\n"));
    }
    resources.push_str("        \"h\": Image(format: R32_SFLOAT, history: true),\n");
    for i in 0..n {
        let mut reads = Vec::new();
        if i > 0 {
            reads.push(format!("\"i_sampled\": \"r{}\"", i - 1));
        }
        if i > 3 {
            reads.push(format!("\"b_read\": \"b{}\"", (i * 7) % (i - 1)));
        }
        if i % 10 == 5 {
            reads.push("\"i_sampled2\": \"h.prev\"".to_string());
        }
        let mut writes = vec![format!("\"i_write\": \"r{i}\""), format!("\"b_write\": \"b{i}\"")];
        if i == n / 2 {
            writes.push("\"i_write2\": \"h\"".to_string());
        }
        passes.push_str(&format!(
            "        Pass(name: \"p{i}\", kind: \"mix\", reads: {{{}}}, writes: {{{}}}),\n",
            reads.join(", "),
            writes.join(", ")
        ));
    }
    let text = format!(
        "Graph(\n    name: \"big\",\n    resources: {{\n{resources}    }},\n    passes: [\n{passes}    ],\n    outputs: [\"r{}\"],\n)",
        n - 1
    );
    let start = std::time::Instant::now();
    let g = load_test(&text);
    let loaded = start.elapsed();
    let mut frame = FrameInputs::new(1920, 1080);
    frame.quantities.set("instances", 100_000);
    let start = std::time::Instant::now();
    let runs = 10;
    let mut c = None;
    for _ in 0..runs {
        c = Some(graph::compile(&g, &frame).unwrap_or_else(|e| panic!("{e}")));
    }
    let per = start.elapsed() / runs;
    let c = c.expect("compiled");
    assert_eq!(c.passes.len() + c.pruned.len(), n);
    println!(
        "200-pass graph: load+validate {loaded:?}, compile {per:?} per run; {} kept, {} pruned, memory {} -> {} bytes",
        c.passes.len(),
        c.pruned.len(),
        c.memory.bytes_without_aliasing,
        c.memory.bytes_with_aliasing
    );
    let start = std::time::Instant::now();
    let d = default_graph();
    for _ in 0..100 {
        graph::compile(&d, &frame).expect("default");
    }
    println!("no_cull.ron: compile {:?} per run", start.elapsed() / 100);
}
