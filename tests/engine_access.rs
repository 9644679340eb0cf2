//! What an engine reaches without the command line or the `verify` feature: the queue of a
//! device cullgraph created, a graph from text, and the visible set of each frame as world
//! handles.

mod common;

use ash::vk;
use common::GpuTest;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer, ViewId};
use cullgraph::scene::world::World;

#[test]
fn the_queue_is_lent_under_its_lock() {
    let gpu = GpuTest::new();
    let queue = gpu.with_queue(|q| {
        // SAFETY: the queue is held for the call; waiting on an idle queue is harmless.
        unsafe { gpu.device().queue_wait_idle(q) }.unwrap();
        q
    });
    assert_ne!(queue, vk::Queue::null());
}

#[test]
fn a_graph_from_text_renders_and_its_errors_name_its_place() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = common::city_view(300, (32, 24));
    let text = r#"Graph(name: "brighter", extends: "two_phase", params: {"exposure": 1.6})"#;
    let spec = GraphSpec::from_text("brighter.ron", text);
    let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(32, 24), &spec).unwrap();
    let image = r.render_to_rgba8(&camera).unwrap().1;
    let loaded = GraphSpec::default_graph().with_overrides([("exposure".to_string(), "1.6".to_string())]);
    let mut same = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(32, 24), &loaded).unwrap();
    assert!(image == same.render_to_rgba8(&camera).unwrap().1);

    let bad =
        GraphSpec::from_text("variant.ron", "Graph(name: \"v\",\n  extends: \"two_phase\", passes: [Pass(name: 1)])");
    let e = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(32, 24), &bad).err().unwrap().to_string();
    assert!(e.contains("variant.ron:2:"), "{e}");
    gpu.assert_clean();
}

#[test]
fn the_visible_set_reads_back_as_world_handles() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, _) = common::city_view(800, (48, 32));
    let camera = scene.default_camera(48.0 / 32.0);
    let (world, handles) = World::new(scene).unwrap();
    for (graph, all) in [("no_cull", true), ("default", false)] {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(48, 32), &spec).unwrap();
        assert_eq!(r.drawn_handles(ViewId::MAIN).unwrap(), None, "nothing captured yet");
        r.capture_draw_lists(true).unwrap();
        r.render(&camera).unwrap();
        let stats = r.render(&camera).unwrap();
        let drawn = r.drawn_handles(ViewId::MAIN).unwrap().expect("captured");
        if all {
            let mut every = handles.clone();
            every.sort_unstable_by_key(|h| r.slot_of(h.index()));
            let mut got = drawn.clone();
            got.sort_unstable_by_key(|h| r.slot_of(h.index()));
            assert_eq!(got, every, "{graph}: every instance");
        } else {
            assert_eq!(drawn.len() as u32, stats.drawn, "{graph}: the frame's drawn instances");
            assert!(!drawn.is_empty() && drawn.len() < handles.len(), "{graph}: {} of {}", drawn.len(), handles.len());
        }
        assert!(drawn.iter().all(|h| world.instance(*h).is_ok()), "{graph}: live handles of this world");
    }
    let plain = Renderer::new(&gpu, shaders, world.live_scene(), RenderSettings::new(48, 32)).unwrap();
    assert!(plain.drawn_handles(ViewId::MAIN).unwrap_err().to_string().contains("made from a scene"));
    gpu.assert_clean();
}
