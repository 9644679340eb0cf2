//! Property tests of the compiler on random valid graphs (test-only pass kinds, no device):
//! the order gives every read the version the declaration semantics promise, writers run in
//! declaration order, aliased memory never overlaps for overlapping lifetimes and respects
//! alignment, every barrier answers a real hazard or layout change, and a simulation of
//! synchronization2 (execution chains, availability, visibility, layouts) finds no access left
//! unsynchronized.

mod graph_kinds;

use ash::vk;
use cullgraph::gpu::ShaderRoot;
use cullgraph::graph::plan::{ResolvedKind, ResourceClass, Version};
use cullgraph::graph::SlotDecl;
use cullgraph::graph::{self, formats, CompiledGraph, FrameInputs, NoDevice, Usage, ValidatedGraph};
use graph_kinds::{BUFFER_READS, BUFFER_WRITES, IMAGE_READS, IMAGE_WRITES};
use proptest::prelude::*;
use std::collections::{BTreeMap, HashMap};

/// Whether a slot is bound, which resource (modulo the candidates), and `.prev` if possible.
type SlotChoice = (bool, u8, bool);

/// Raw random choices; [`build`] turns them into a valid graph file.
#[derive(Clone, Debug)]
struct Raw {
    /// Per resource: is image, lifetime class (0 transient, 1 history, 2 imported), size choice.
    resources: Vec<(bool, u8, u8)>,
    /// Per pass: is image kind; per slot (reads then writes): bound?, resource choice, `.prev`?
    passes: Vec<(bool, Vec<SlotChoice>)>,
    /// Output choices.
    outputs: Vec<u8>,
}

fn raw() -> impl Strategy<Value = Raw> {
    (
        prop::collection::vec((any::<bool>(), 0u8..4, any::<u8>()), 1..9),
        prop::collection::vec(
            (any::<bool>(), prop::collection::vec((prop::bool::weighted(0.3), any::<u8>(), any::<bool>()), 9)),
            1..14,
        ),
        prop::collection::vec(any::<u8>(), 1..3),
    )
        .prop_map(|(resources, passes, outputs)| Raw { resources, passes, outputs })
}

/// Builds RON text from the raw choices, keeping it valid: reads only of resources something
/// writes (or imported ones, or `.prev` of written history), read-modify-writes only after a
/// write (or of imported resources), one binding per resource version and pass, outputs that
/// are written (the first one an image). `None` when no image is written.
fn build(raw: &Raw) -> Option<String> {
    let res: Vec<(bool, u8, u8)> = raw.resources.clone();
    let kind = |image: bool| if image { "img" } else { "buf" };
    let slots = |image: bool| -> (&[SlotDecl], &[SlotDecl]) {
        if image {
            (IMAGE_READS, IMAGE_WRITES)
        } else {
            (BUFFER_READS, BUFFER_WRITES)
        }
    };
    let of_type: HashMap<bool, Vec<usize>> =
        [true, false].into_iter().map(|t| (t, (0..res.len()).filter(|&i| res[i].0 == t).collect())).collect();
    // Writes first (in declaration order), so that reads can be checked against all writers.
    let mut written_by: Vec<Vec<usize>> = vec![Vec::new(); res.len()];
    let mut writes: Vec<Vec<(&str, usize)>> = Vec::new();
    for (p, (image, choices)) in raw.passes.iter().enumerate() {
        let (reads_decl, writes_decl) = slots(*image);
        let mut w = Vec::new();
        for (k, s) in writes_decl.iter().enumerate() {
            let (bound, choice, _) = choices[reads_decl.len() + k];
            let candidates = &of_type[image];
            if !bound || candidates.is_empty() {
                continue;
            }
            let r = candidates[choice as usize % candidates.len()];
            let imported = res[r].1 == 2;
            if w.iter().any(|&(_, x)| x == r) || (s.usage.reads() && written_by[r].is_empty() && !imported) {
                continue;
            }
            w.push((s.name, r));
            written_by[r].push(p);
        }
        writes.push(w);
    }
    let mut passes = String::new();
    for (p, (image, choices)) in raw.passes.iter().enumerate() {
        let (reads_decl, _) = slots(*image);
        let mut r_entries = Vec::new();
        let mut used: Vec<(usize, bool)> = writes[p].iter().map(|&(_, r)| (r, false)).collect();
        for (k, s) in reads_decl.iter().enumerate() {
            let (bound, choice, prev) = choices[k];
            let candidates = &of_type[image];
            if !bound || candidates.is_empty() {
                continue;
            }
            let r = candidates[choice as usize % candidates.len()];
            let (history, imported) = (res[r].1 == 1, res[r].1 == 2);
            let prev = prev && history;
            if written_by[r].is_empty() && !imported || used.contains(&(r, prev)) {
                continue;
            }
            used.push((r, prev));
            r_entries.push(format!("\"{}\": \"r{r}{}\"", s.name, if prev { ".prev" } else { "" }));
        }
        let w_entries: Vec<String> = writes[p].iter().map(|(s, r)| format!("\"{s}\": \"r{r}\"")).collect();
        passes.push_str(&format!(
            "        Pass(name: \"p{p}\", kind: \"{}\", reads: {{{}}}, writes: {{{}}}),\n",
            kind(*image),
            r_entries.join(", "),
            w_entries.join(", ")
        ));
    }
    let written: Vec<usize> = (0..res.len()).filter(|&r| !written_by[r].is_empty()).collect();
    let images: Vec<usize> = written.iter().copied().filter(|&r| res[r].0).collect();
    if images.is_empty() {
        return None;
    }
    let mut outputs = vec![images[raw.outputs[0] as usize % images.len()]];
    for &o in &raw.outputs[1..] {
        let r = written[o as usize % written.len()];
        if !outputs.contains(&r) {
            outputs.push(r);
        }
    }
    let mut resources = String::new();
    for (i, (image, class, size)) in res.iter().enumerate() {
        let decl = if *image {
            let size =
                ["", ", size: Scaled(0.5)", ", size: Fixed(300, 200), mips: All", ", mips: 3"][*size as usize % 4];
            format!("Image(format: R8G8B8A8_UNORM{size}")
        } else {
            format!("Buffer(size: {}", 100 + *size as u32 * 1000)
        };
        let decl = match class {
            1 => format!("{decl}, history: true)"),
            2 => format!("Imported({decl}))"),
            _ => format!("{decl})"),
        };
        resources.push_str(&format!("        \"r{i}\": {decl},\n"));
    }
    let outputs: Vec<String> = outputs.iter().map(|r| format!("\"r{r}\"")).collect();
    Some(format!(
        "Graph(\n    name: \"random\",\n    resources: {{\n{resources}    }},\n    passes: [\n{passes}    ],\n    outputs: [{}],\n)\n",
        outputs.join(", ")
    ))
}

fn env() -> NoDevice {
    NoDevice::new(ShaderRoot::Embedded).expect("shaderc")
}

/// Loads; `None` for a dependency cycle (random graphs may have one), panics on other errors.
fn load(text: &str) -> Option<ValidatedGraph> {
    match graph::load(text, "random.ron", &[], &env(), &graph_kinds::test_kinds()) {
        Ok(g) => Some(g),
        Err(e) if e.iter().all(|e| e.message.starts_with("cycle: ")) => None,
        Err(e) => panic!("generated graph is invalid:\n{e}\n{text}"),
    }
}

/// Each read sees the version the declaration semantics promise; writers run in declaration order.
fn check_order(g: &ValidatedGraph, c: &CompiledGraph) {
    let kept: Vec<usize> = c.passes.iter().map(|p| g.pass_index(&p.name).expect("kept pass")).collect();
    let pos: HashMap<usize, usize> = kept.iter().enumerate().map(|(i, &p)| (p, i)).collect();
    for r in 0..g.resources.len() {
        // Uses of this frame's contents by kept passes, in declaration order.
        let mut uses: Vec<(usize, Usage)> = Vec::new();
        for &p in kept.iter().collect::<std::collections::BTreeSet<_>>() {
            for b in g.passes[p].bindings.iter().filter(|b| b.resource == r && b.version == Version::Current) {
                uses.push((p, b.usage));
            }
        }
        let writers: Vec<usize> = uses.iter().filter(|u| u.1.writes()).map(|u| u.0).collect();
        let exec_writers: Vec<usize> = {
            let mut w = writers.clone();
            w.sort_by_key(|p| pos[p]);
            w
        };
        assert_eq!(exec_writers, writers, "writers of '{}' must run in declaration order", g.resources[r].name);
        for &(p, usage) in &uses {
            if usage.writes() {
                continue;
            }
            let promised = writers.iter().rev().find(|&&w| w < p).or(writers.first()).copied();
            let seen = exec_writers.iter().rev().find(|&&w| pos[&w] < pos[&p]).copied();
            assert_eq!(
                seen, promised,
                "pass '{}' must see the write of {:?} to '{}'",
                g.passes[p].name, promised, g.resources[r].name
            );
        }
    }
}

fn estimate(kind: &ResolvedKind) -> (u64, u64) {
    match kind {
        ResolvedKind::Image { format, extent, mip_levels, samples, .. } => {
            let texel = formats::info(*format).expect("format").bytes as u64;
            let texels: u64 =
                (0..*mip_levels).map(|l| (extent.width >> l).max(1) as u64 * (extent.height >> l).max(1) as u64).sum();
            (texels * texel * samples.as_raw() as u64, 65536)
        }
        ResolvedKind::Buffer { size, .. } => (*size, 256),
    }
}

fn check_memory(c: &CompiledGraph) {
    let mut placed = Vec::new();
    for (i, r) in c.resources.iter().enumerate() {
        let p = c.memory.placements[i];
        match (r.class, r.lifetime) {
            (ResourceClass::Transient, Some(l)) => {
                let p = p.unwrap_or_else(|| panic!("transient '{}' has no placement", r.name));
                let (size, align) = estimate(&r.kind);
                assert_eq!(p.offset % align, 0, "'{}' misaligned", r.name);
                assert!(p.offset + size <= c.memory.heaps[p.heap], "'{}' outside its heap", r.name);
                placed.push((i, p, size, l));
            }
            _ => assert!(p.is_none(), "'{}' ({:?}) must not be placed", r.name, r.class),
        }
    }
    for (a, pa, sa, la) in &placed {
        for (b, pb, sb, lb) in &placed {
            if a < b && pa.heap == pb.heap && la.0 <= lb.1 && lb.0 <= la.1 {
                let disjoint = pa.offset + sa <= pb.offset || pb.offset + sb <= pa.offset;
                assert!(
                    disjoint,
                    "'{}' and '{}' live together but overlap in memory",
                    c.resources[*a].name, c.resources[*b].name
                );
            }
        }
    }
    assert_eq!(c.memory.bytes_with_aliasing, c.memory.heaps.iter().sum::<u64>());
    assert!(c.memory.bytes_with_aliasing <= c.memory.bytes_without_aliasing);
}

fn check_lifetimes(c: &CompiledGraph) {
    for (i, r) in c.resources.iter().enumerate() {
        let positions: Vec<usize> = c
            .passes
            .iter()
            .enumerate()
            .filter(|(_, p)| p.bindings.iter().any(|b| b.resource == i && b.version == Version::Current))
            .map(|(n, _)| n)
            .collect();
        let expected = positions.first().map(|&f| (f, *positions.last().expect("last")));
        assert_eq!(r.lifetime, expected, "lifetime of '{}'", r.name);
    }
}

const WRITES: vk::AccessFlags2 = vk::AccessFlags2::from_raw(
    vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw()
        | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags2::TRANSFER_WRITE.as_raw(),
);

/// Something that touched a resource version earlier in the frame.
#[derive(Clone, Debug)]
struct Event {
    what: String,
    stage: vk::PipelineStageFlags2,
    access: vk::AccessFlags2,
    write: bool,
    /// Stages that a chain of barriers orders after it.
    after: vk::PipelineStageFlags2,
    /// Whether its writes were made available.
    available: bool,
    /// Scopes its writes were made visible to.
    visible: Vec<(vk::PipelineStageFlags2, vk::AccessFlags2)>,
}

#[derive(Default)]
struct State {
    touched: bool,
    layout: vk::ImageLayout,
    events: Vec<Event>,
}

fn transition(dst: &cullgraph::gpu::Access, what: String) -> Event {
    Event {
        what,
        stage: vk::PipelineStageFlags2::NONE,
        access: vk::AccessFlags2::NONE,
        write: true,
        after: dst.stage,
        available: true,
        visible: vec![(dst.stage, dst.access)],
    }
}

/// Barriers answer real hazards only, and a simulation finds every access synchronized.
fn check_barriers(c: &CompiledGraph) {
    let is_image: Vec<bool> = c.resources.iter().map(|r| matches!(r.kind, ResolvedKind::Image { .. })).collect();
    let mut states: BTreeMap<(usize, Version), State> = BTreeMap::new();
    let mut last_use: BTreeMap<(usize, Version), Usage> = BTreeMap::new();
    for (pos, pass) in c.passes.iter().enumerate() {
        let mut seen = std::collections::BTreeSet::new();
        for b in &pass.barriers {
            let key = (b.resource, b.version);
            assert!(seen.insert(key), "two barriers for one resource version before '{}'", pass.name);
            let binding = pass
                .bindings
                .iter()
                .find(|x| x.resource == b.resource && x.version == b.version)
                .unwrap_or_else(|| panic!("barrier before '{}' for a resource it does not bind", pass.name));
            let image = is_image[b.resource];
            let what = format!("'{}' {:?} before '{}'", c.resources[b.resource].name, b.version, pass.name);
            // Justification: first use, a write on either side, or a layout change.
            match (b.src, last_use.get(&key)) {
                (None, None) => {}
                (None, Some(_)) => panic!("{what}: src None but not the first use"),
                (Some(_), None) => panic!("{what}: first use needs src None"),
                (Some(_), Some(prev)) => {
                    let layout_change = image && prev.access().layout != binding.usage.access().layout;
                    assert!(
                        prev.writes() || binding.usage.writes() || layout_change,
                        "{what}: read after read without layout change"
                    );
                }
            }
            assert_eq!(b.discard, b.src.is_none() && !binding.usage.reads(), "{what}: discard");
            let st = states.entry(key).or_default();
            match b.src {
                None => {
                    st.touched = true;
                    st.events.clear();
                    if image {
                        st.layout = b.dst.layout;
                        st.events.push(transition(&b.dst, format!("first-use transition of {what}")));
                    }
                }
                Some(src) => {
                    let in_scope: Vec<bool> =
                        st.events.iter().map(|e| (e.stage | e.after).intersects(src.stage)).collect();
                    for (e, &scoped) in st.events.iter_mut().zip(&in_scope) {
                        if scoped {
                            e.after |= b.dst.stage;
                            if e.write && (e.available || src.access.contains(e.access & WRITES)) {
                                e.available = true;
                                e.visible.push((b.dst.stage, b.dst.access));
                            }
                        }
                    }
                    if image && b.dst.layout != st.layout {
                        assert_eq!(src.layout, st.layout, "{what}: old layout");
                        for (e, scoped) in st.events.iter().zip(in_scope) {
                            assert!(scoped, "{what}: layout transition races with {}", e.what);
                            assert!(!e.write || e.available, "{what}: transition before {} is available", e.what);
                        }
                        st.layout = b.dst.layout;
                        st.events.push(transition(&b.dst, format!("transition {what}")));
                    }
                }
            }
        }
        for binding in &pass.bindings {
            let key = (binding.resource, binding.version);
            let what = format!("'{}' {:?} in '{}'", c.resources[binding.resource].name, binding.version, pass.name);
            let st = states.get(&key).unwrap_or_else(|| panic!("{what}: used without any barrier"));
            assert!(st.touched, "{what}: first use without barrier");
            let a = binding.usage.access();
            if is_image[binding.resource] {
                assert_eq!(st.layout, a.layout, "{what}: layout");
            }
            for e in &st.events {
                if e.write || binding.usage.writes() {
                    assert!(e.after.contains(a.stage), "{what}: not ordered after {} (stage {:?})", e.what, a.stage);
                }
                if e.write {
                    let visible = e.visible.iter().any(|(s, acc)| s.contains(a.stage) && acc.contains(a.access));
                    assert!(visible, "{what}: {} not visible to {:?}/{:?}", e.what, a.stage, a.access);
                }
            }
            let _ = pos;
        }
        for binding in &pass.bindings {
            let key = (binding.resource, binding.version);
            let a = binding.usage.access();
            let st = states.get_mut(&key).expect("state");
            st.events.push(Event {
                what: format!("'{}' in '{}'", c.resources[binding.resource].name, pass.name),
                stage: a.stage,
                access: a.access,
                write: binding.usage.writes(),
                after: vk::PipelineStageFlags2::NONE,
                available: false,
                visible: Vec::new(),
            });
            last_use.insert(key, binding.usage);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, ..ProptestConfig::default() })]

    #[test]
    fn random_graphs_compile_to_correct_plans(raw in raw()) {
        let Some(text) = build(&raw) else { return Ok(()) };
        let Some(g) = load(&text) else { return Ok(()) };
        if std::env::var_os("GRAPH_PROP_STATS").is_some() {
            eprintln!("case: {} passes, {} resources", g.passes.len(), g.resources.len());
        }
        let mut frame = FrameInputs::new(640, 360);
        frame.quantities.set("instances", 1000);
        // Random sizes may give one pass attachments of different sizes, which compiling
        // refuses (no device renders that); anything else must compile.
        let c = match graph::compile(&g, &frame) {
            Err(e) if e.iter().all(|e| e.message.contains("attachments of one pass must be the same size")) => {
                return Ok(());
            }
            other => other.unwrap_or_else(|e| panic!("{e}\n{text}")),
        };
        check_order(&g, &c);
        check_lifetimes(&c);
        check_memory(&c);
        check_barriers(&c);
        // The same input gives the same plan.
        prop_assert_eq!(graph::compile(&g, &frame).expect("again"), c);
    }

}
