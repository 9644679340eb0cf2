//! The library's CPU scopes reach a profiler through the `profiling` crate (here puffin, the
//! backend the tests enable): building the graph, compiling it and its shaders, the scene
//! upload, one scope per recorded frame with one per pass inside it, named after the pass, and
//! the waits on the GPU. An engine that enables a backend of its own gets the same scopes.

mod common;

use common::{city_view, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use profiling::puffin;

/// A scope as read back: nesting depth, name and data.
#[derive(Debug, Clone, PartialEq)]
struct Recorded {
    depth: usize,
    name: String,
    data: String,
}

/// Every scope of `frame`, depth first, all threads.
fn scopes_of(frame: &puffin::FrameData, names: &puffin::ScopeCollection) -> Vec<Recorded> {
    fn walk(
        stream: &puffin::Stream,
        reader: puffin::Reader<'_>,
        depth: usize,
        names: &puffin::ScopeCollection,
        out: &mut Vec<Recorded>,
    ) {
        for scope in reader {
            let scope = scope.expect("a well-formed puffin stream");
            let name = names.fetch_by_id(&scope.id).map(|d| d.name().to_string()).unwrap_or_default();
            out.push(Recorded { depth, name, data: scope.record.data.to_string() });
            let children = puffin::Reader::with_offset(stream, scope.child_begin_position).unwrap();
            walk(stream, children, depth + 1, names, out);
        }
    }
    let Ok(unpacked) = frame.unpacked();
    let mut out = Vec::new();
    for stream in unpacked.thread_streams.values() {
        walk(&stream.stream, puffin::Reader::from_start(&stream.stream), 0, names, &mut out);
    }
    out
}

#[test]
fn cpu_scopes_reach_the_profiler_with_one_per_pass() {
    puffin::set_scopes_on(true);
    let view = puffin::GlobalFrameView::default();
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (w, h) = (64, 36);
    let (scene, camera) = city_view(500, (w, h));
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let mut renderer = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(w, h), &spec).unwrap();
    puffin::GlobalProfiler::lock().new_frame();
    for _ in 0..2 {
        renderer.render(&camera).unwrap();
        puffin::GlobalProfiler::lock().new_frame();
    }
    let passes: Vec<String> = renderer.plan().passes.iter().map(|p| p.name.clone()).collect();
    assert!(passes.len() >= 4, "two_phase has its draws, pyramid, cull and lighting: {passes:?}");

    let view = view.lock();
    let frames: Vec<_> = view.recent_frames().cloned().collect();
    assert_eq!(frames.len(), 3, "the set-up and two rendered frames");
    let names = view.scope_collection();
    let setup = scopes_of(&frames[0], names);
    let named = |list: &[Recorded], name: &str| list.iter().filter(|s| s.name == name).count();
    assert_eq!(named(&setup, "cullgraph::Renderer::with_graph"), 1, "{setup:#?}");
    assert_eq!(named(&setup, "cullgraph::build_graph"), 1);
    assert_eq!(named(&setup, "cullgraph::upload_scene"), 1);
    let compiled: Vec<_> = setup.iter().filter(|s| s.name == "cullgraph::compile_graph").collect();
    assert_eq!(compiled.len(), 1);
    assert_eq!(compiled[0].data, "two_phase", "the compile scope names the graph");
    assert!(
        setup.iter().any(|s| s.name == "cullgraph::compile_shader" && s.data.ends_with(".comp")),
        "shader compiles are scoped with the shader's name"
    );
    assert_eq!(named(&setup, "cullgraph::record_pass"), 0, "nothing is recorded before the first frame");

    for frame in &frames[1..] {
        let scopes = scopes_of(frame, names);
        let graph: Vec<_> = scopes.iter().filter(|s| s.name == "cullgraph::record_graph").collect();
        assert_eq!(graph.len(), 1, "one recorded graph per frame: {scopes:#?}");
        assert_eq!(graph[0].data, "two_phase");
        // The passes are scoped inside the graph's scope, in execution order, each once.
        let recorded: Vec<_> = scopes
            .iter()
            .filter(|s| s.name == "cullgraph::record_pass")
            .inspect(|s| assert_eq!(s.depth, graph[0].depth + 1, "{s:?} nests in the graph's scope"))
            .map(|s| s.data.clone())
            .collect();
        assert_eq!(recorded, passes);
        assert_eq!(named(&scopes, "cullgraph::wait_gpu"), 1, "the frame waits for the GPU once");
    }
    puffin::set_scopes_on(false);
}
