//! Frames whose commands would not change replay an earlier frame's recording
//! (`graph::executor::replay`): the image and the counters are those of a renderer that records
//! every frame, while the camera moves, instances move, and a setting changes live.

mod common;

use common::{city_view, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::world::World;
use cullgraph::scene::Camera;
use glam::DVec3;

const SIZE: (u32, u32) = (128, 96);
const FRAMES: usize = 30;

/// The camera of frame `i`: turning and sliding a little every frame.
fn camera_at(start: &Camera, i: usize) -> Camera {
    let t = i as f64 * 0.07;
    Camera { eye: start.eye + DVec3::new(t.sin() * 3.0, 0.0, t * 2.0), ..start.clone() }
}

/// Renders `FRAMES` frames of the world with `replaying` and `recording` (the latter records
/// every frame: capturing draw lists rules replay out), moving instances between some frames
/// and changing the exposure live at one; every frame's image and counts must agree.
#[test]
fn replayed_frames_draw_what_recorded_ones_draw() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(3000, SIZE);
    let (mut world, handles) = World::new(scene).unwrap();
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut replaying = Renderer::from_world(&gpu, shaders, &world, settings.clone(), &spec).unwrap();
    let mut recording = Renderer::from_world(&gpu, shaders, &world, settings, &spec).unwrap();
    recording.capture_draw_lists(true).unwrap();
    for i in 0..FRAMES {
        if i % 5 == 3 {
            // A few instances move: the world's update is recorded before the graph.
            let moved: Vec<_> = handles
                .iter()
                .step_by(97)
                .map(|&h| {
                    let mut t = world.instance(h).unwrap().transform;
                    t.translation += DVec3::new(0.0, 0.5, 0.0);
                    (h, t)
                })
                .collect();
            world.set_transforms(&moved).unwrap();
            replaying.sync(shaders, &world).unwrap();
            recording.sync(shaders, &world).unwrap();
        }
        if i == 15 {
            for r in [&mut replaying, &mut recording] {
                r.set_graph_params(shaders, &[("exposure", "2.5")]).unwrap();
            }
        }
        // Step timing on for a few frames: more timestamp scopes, which frames replayed later
        // must not report.
        if i == 8 || i == 11 {
            for r in [&mut replaying, &mut recording] {
                r.set_step_timing(i == 8);
            }
        }
        let camera = camera_at(&camera, i);
        let (a_stats, a) = replaying.render_to_image(&camera).unwrap();
        let (b_stats, b) = recording.render_to_image(&camera).unwrap();
        assert!(a == b, "frame {i}: the replayed image differs");
        assert_eq!((a_stats.drawn, a_stats.triangles), (b_stats.drawn, b_stats.triangles), "frame {i}");
        assert_eq!(a_stats.passes, b_stats.passes, "frame {i}: pass counters");
        let scopes = |s: &cullgraph::stats::FrameStats| s.gpu_ms.iter().map(|t| t.name.clone()).collect::<Vec<_>>();
        assert_eq!(scopes(&a_stats), scopes(&b_stats), "frame {i}: timed scopes");
    }
    // Frames replay once each slot's recording met a steady state: most of them here.
    let replayed = replaying.runtime().frames_replayed();
    assert!(replayed >= (FRAMES / 4) as u64, "{replayed} of {FRAMES} frames replayed");
    assert_eq!(recording.runtime().frames_replayed(), 0);
    gpu.assert_clean();
}

/// The other shipped pipelines that replay (MSAA through the compressed and per-sample
/// G-buffers, cluster culling, the visibility buffer) draw with replay what they draw without,
/// frame after frame of a moving camera over a scene that does not change.
#[test]
fn every_replaying_graph_draws_what_it_draws_recorded() {
    use cullgraph::scene::CameraPath;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(500, SIZE);
    let graphs = [
        ("msaa_compressed", Some("4")),
        ("msaa_per_sample", Some("4")),
        ("two_phase_clusters", None),
        ("visibility_buffer", None),
    ];
    for (graph, msaa) in graphs {
        let mut spec = GraphSpec::builtin(graph).unwrap();
        if let Some(samples) = msaa {
            spec = spec.with_overrides([("msaa".to_string(), samples.to_string())]);
        }
        let settings = RenderSettings::new(SIZE.0, SIZE.1);
        let mut replaying = Renderer::with_graph(&gpu, shaders, scene.clone(), settings.clone(), &spec).unwrap();
        let mut recording = Renderer::with_graph(&gpu, shaders, scene.clone(), settings, &spec).unwrap();
        recording.set_frame_replay(false);
        let frames = 15;
        for f in 0..frames {
            let camera = CameraPath::Orbit.camera_at(&camera, f);
            let (a_stats, a) = replaying.render_to_image(&camera).unwrap();
            let (b_stats, b) = recording.render_to_image(&camera).unwrap();
            assert!(a == b, "{graph}, frame {f}: the replayed image differs");
            assert_eq!(a_stats.passes, b_stats.passes, "{graph}, frame {f}: pass counters");
        }
        let replayed = replaying.runtime().frames_replayed();
        assert!(replayed >= 3, "{graph}: {replayed} of {frames} frames replayed");
        assert_eq!(recording.runtime().frames_replayed(), 0, "{graph}");
    }
    gpu.assert_clean();
}

/// A world with per-instance user data hands its graphs that data as an import of the
/// renderer's own, which the renderer's replay key covers: its frames replay too.
#[test]
fn a_world_with_user_data_replays() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(400, SIZE);
    let (mut world, handles) = World::with_user_data(scene, 2).unwrap();
    world.set_user_data(&[(handles[5], &[7, 9][..])]).unwrap();
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut replaying = Renderer::from_world(&gpu, shaders, &world, settings.clone(), &spec).unwrap();
    let mut recording = Renderer::from_world(&gpu, shaders, &world, settings, &spec).unwrap();
    recording.set_frame_replay(false);
    for i in 0..12 {
        let camera = camera_at(&camera, i);
        let (_, a) = replaying.render_to_image(&camera).unwrap();
        let (_, b) = recording.render_to_image(&camera).unwrap();
        assert!(a == b, "frame {i}: the replayed image differs");
    }
    let replayed = replaying.runtime().frames_replayed();
    assert!(replayed >= 3, "{replayed} of 12 frames replayed");
    gpu.assert_clean();
}

/// Two views of one world culled together (split screen), each camera moving and instances
/// moving too: the renderer keeps such a frame's commands whole and replays them, and both
/// views draw what a renderer recording every frame draws.
#[test]
fn frames_of_several_views_replay_whole() {
    use cullgraph::render::ViewId;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(1500, SIZE);
    let (mut world, handles) = World::new(scene).unwrap();
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let make = |world: &World| {
        let mut r = Renderer::from_world(&gpu, shaders, world, settings.clone(), &spec).unwrap();
        let second = r.add_view(shaders, RenderSettings::new(96, 64), &spec).unwrap();
        (r, second)
    };
    let (mut replaying, second) = make(&world);
    let (mut recording, other) = make(&world);
    assert_eq!(second, other);
    recording.set_frame_replay(false);
    for i in 0..20 {
        if i % 6 == 4 {
            let moved: Vec<_> = handles
                .iter()
                .step_by(53)
                .map(|&h| {
                    let mut t = world.instance(h).unwrap().transform;
                    t.translation += DVec3::new(0.3, 0.0, 0.0);
                    (h, t)
                })
                .collect();
            world.set_transforms(&moved).unwrap();
            replaying.sync(shaders, &world).unwrap();
            recording.sync(shaders, &world).unwrap();
        }
        let (a, b) = (camera_at(&camera, i), camera_at(&camera, i + 7));
        let views: [(ViewId, &Camera); 2] = [(ViewId::MAIN, &a), (second, &b)];
        let replayed = replaying.render_views_to_rgba8(&views).unwrap();
        let recorded = recording.render_views_to_rgba8(&views).unwrap();
        for (v, ((a_stats, a), (b_stats, b))) in replayed.iter().zip(&recorded).enumerate() {
            assert!(a == b, "frame {i}, view {v}: the replayed image differs");
            assert_eq!((a_stats.drawn, a_stats.triangles), (b_stats.drawn, b_stats.triangles), "frame {i}, view {v}");
        }
    }
    for view in [ViewId::MAIN, second] {
        let replayed = replaying.view_runtime(view).unwrap().frames_replayed();
        assert!(replayed >= 5, "view {view:?}: {replayed} of 20 frames replayed");
        assert_eq!(recording.view_runtime(view).unwrap().frames_replayed(), 0);
    }
    gpu.assert_clean();
}

/// A frame with the sun's shadow cascades (each cascade a view drawing a layer of the
/// renderer's map array, which it imports): kept and replayed whole as the camera moves, with
/// every map redrawn every frame (maps are not kept), and the image what a renderer recording
/// every frame draws. Shadows switched off and on again make new maps: frames recorded for the
/// old ones never replay against the new. Then the camera stops and the maps are kept: the
/// camera view's frames alone, sampling the kept maps, replay too.
#[test]
fn frames_with_shadow_views_replay_whole() {
    use cullgraph::render::ShadowSettings;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(800, SIZE);
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let shadows = ShadowSettings { resolution: 256, distance: Some(60.0), ..Default::default() };
    let make = || {
        let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), settings.clone(), &spec).unwrap();
        r.set_shadows(shaders, Some(shadows.clone())).unwrap();
        r.set_shadow_maps_kept(false);
        r
    };
    let (mut replaying, mut recording) = (make(), make());
    recording.set_frame_replay(false);
    for i in 0..24 {
        if i == 12 {
            for r in [&mut replaying, &mut recording] {
                r.set_shadows(shaders, None).unwrap();
                r.set_shadows(shaders, Some(ShadowSettings { resolution: 128, ..shadows.clone() })).unwrap();
            }
        }
        let camera = camera_at(&camera, i);
        let (a_stats, a) = replaying.render_to_image(&camera).unwrap();
        let (b_stats, b) = recording.render_to_image(&camera).unwrap();
        assert!(a == b, "frame {i}: the replayed image differs");
        assert_eq!((a_stats.drawn, a_stats.triangles), (b_stats.drawn, b_stats.triangles), "frame {i}");
    }
    let moving = replaying.runtime().frames_replayed();
    assert!(moving >= 6, "{moving} of 24 frames replayed");
    let still = camera_at(&camera, 30);
    for i in 0..12 {
        for r in [&mut replaying, &mut recording] {
            r.set_shadow_maps_kept(i > 0);
        }
        let (_, a) = replaying.render_to_image(&still).unwrap();
        let (_, b) = recording.render_to_image(&still).unwrap();
        assert!(a == b, "still frame {i}: the replayed image differs");
    }
    let replayed = replaying.runtime().frames_replayed() - moving;
    assert!(replayed >= 4, "{replayed} of 12 still frames replayed");
    gpu.assert_clean();
}
