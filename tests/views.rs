//! Many views over one world: each view renders exactly what a renderer of its camera alone
//! renders (images and counts), views are added, resized and removed at any frame without
//! disturbing the others, and bad view input is an error naming the view.

mod common;

use common::{city_view, GpuTest};
use cullgraph::oracle::Verify;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer, ViewId, MAX_VIEWS};
use cullgraph::scene::Camera;
use cullgraph::stats::FrameStats;
use glam::DVec3;

/// A street-level camera looking along the city from one corner: mostly occluded.
fn street_camera(scene: &cullgraph::scene::Scene) -> Camera {
    let (min, max) = scene.world_bounds().expect("the city has instances");
    Camera {
        eye: DVec3::new(min.x + 2.0, 2.0, min.z + 2.0),
        target: DVec3::new(max.x, 1.0, max.z),
        ..Default::default()
    }
}

/// What the counts of two renders of the same camera must share.
fn counts(s: &FrameStats) -> (u32, u32, u32, u32) {
    (s.drawn, s.frustum_culled, s.occlusion_culled, s.draws)
}

#[test]
fn views_rendered_together_match_each_camera_rendered_alone() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, overview) = city_view(1500, (64, 48));
    let street = street_camera(&scene);
    let mut together = Renderer::new(&gpu, shaders, scene.clone(), RenderSettings::new(64, 48)).unwrap();
    let second = together.add_view(shaders, RenderSettings::new(40, 30), &GraphSpec::default_graph()).unwrap();
    together.enable_verification(shaders).unwrap();
    let mut alone_main = Renderer::new(&gpu, shaders, scene.clone(), RenderSettings::new(64, 48)).unwrap();
    let mut alone_second = Renderer::new(&gpu, shaders, scene, RenderSettings::new(40, 30)).unwrap();
    // The cameras move a little each frame, so that each view's history matters.
    let orbit = cullgraph::scene::CameraPath::Orbit;
    for frame in 0..4 {
        let (a, b) = (orbit.camera_at(&overview, frame), orbit.camera_at(&street, frame));
        let both = together.render_views_to_rgba8(&[(ViewId::MAIN, &a), (second, &b)]).unwrap();
        let (main_stats, main_image) = alone_main.render_to_rgba8(&a).unwrap();
        let (second_stats, second_image) = alone_second.render_to_rgba8(&b).unwrap();
        assert!(both[0].1 == main_image, "frame {frame}: the main view's image differs from its camera alone");
        assert!(both[1].1 == second_image, "frame {frame}: the second view's image differs from its camera alone");
        assert_eq!(counts(&both[0].0), counts(&main_stats), "frame {frame}, main view");
        assert_eq!(counts(&both[1].0), counts(&second_stats), "frame {frame}, second view");
        for (view, (stats, _)) in both.iter().enumerate() {
            let verify = stats.verify.as_ref().expect("verification is on");
            assert_eq!(verify.false_negatives, 0, "frame {frame}, view {view}: {:?}", verify.missed);
        }
    }
    // Both cameras see different parts of the city: the views really are different.
    let last = together.render_views(&[(ViewId::MAIN, &overview), (second, &street)]).unwrap();
    assert_ne!(last[0].drawn, last[1].drawn);
    gpu.assert_clean();
}

#[test]
fn a_view_skipped_for_some_frames_keeps_its_history_and_the_others_are_untouched() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, overview) = city_view(1500, (64, 48));
    let street = street_camera(&scene);
    let mut r = Renderer::new(&gpu, shaders, scene.clone(), RenderSettings::new(64, 48)).unwrap();
    let mut alone = Renderer::new(&gpu, shaders, scene, RenderSettings::new(64, 48)).unwrap();
    let side = r.add_view(shaders, RenderSettings::new(64, 48), &GraphSpec::default_graph()).unwrap();
    for frame in 0..5 {
        // The side view renders only every other frame; the main view every frame.
        let frames: Vec<(ViewId, &Camera)> = if frame % 2 == 0 {
            vec![(ViewId::MAIN, &overview), (side, &street)]
        } else {
            vec![(ViewId::MAIN, &overview)]
        };
        let stats = r.render_views(&frames).unwrap();
        let expected = alone.render(&overview).unwrap();
        assert_eq!(counts(&stats[0]), counts(&expected), "frame {frame}");
    }
    // Removing the side view leaves the main view's history as it was.
    r.remove_view(side).unwrap();
    let (stats, image) = r.render_to_rgba8(&overview).unwrap();
    let (expected, expected_image) = alone.render_to_rgba8(&overview).unwrap();
    assert_eq!(counts(&stats), counts(&expected));
    assert!(image == expected_image);
    gpu.assert_clean();
}

#[test]
fn a_resized_view_renders_what_a_view_made_at_that_size_renders() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(800, (64, 48));
    let mut r = Renderer::new(&gpu, shaders, scene.clone(), RenderSettings::new(64, 48)).unwrap();
    r.enable_verification(shaders).unwrap();
    let other = r.add_view(shaders, RenderSettings::new(32, 24), &GraphSpec::default_graph()).unwrap();
    let mut other_alone = Renderer::new(&gpu, shaders, scene.clone(), RenderSettings::new(32, 24)).unwrap();
    let street = street_camera(&scene);
    r.render_views(&[(ViewId::MAIN, &camera), (other, &street)]).unwrap();
    other_alone.render(&street).unwrap();
    let pipelines = gpu.pipelines_made();
    // Up, down, odd, one pixel, and back: each right after the resize, then a frame later.
    for (w, h) in [(64, 48), (96, 72), (33, 17), (1, 1), (7, 1), (64, 48)] {
        r.resize(shaders, w, h).unwrap();
        let mut fresh = Renderer::new(&gpu, shaders, scene.clone(), RenderSettings::new(w, h)).unwrap();
        for _ in 0..2 {
            let frames = r.render_views_to_rgba8(&[(ViewId::MAIN, &camera), (other, &street)]).unwrap();
            let (_, expected) = fresh.render_to_rgba8(&camera).unwrap();
            assert_eq!(r.settings(), &RenderSettings::new(w, h));
            assert!(frames[0].1 == expected, "{w}x{h}: the resized view's image differs from a view made at that size");
            let verify = frames[0].0.verify.as_ref().expect("verification is on");
            assert_eq!(verify.false_negatives, 0, "{w}x{h}: {:?}", verify.missed);
            // The other view is not disturbed by the resizes.
            let expected_other = other_alone.render(&street).unwrap();
            assert_eq!(counts(&frames[1].0), counts(&expected_other), "{w}x{h}: the other view");
        }
    }
    // The fresh renderers made none either: they share the pipelines that are alive.
    assert_eq!(gpu.pipelines_made(), pipelines, "resizing made pipelines");
    gpu.assert_clean();
}

#[test]
fn bad_view_input_is_an_error_naming_the_view() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(200, (32, 24));
    let mut r = Renderer::new(&gpu, shaders, scene, RenderSettings::new(32, 24)).unwrap();
    let spec = GraphSpec::default_graph();
    let err = r.add_view(shaders, RenderSettings::new(0, 24), &spec).unwrap_err().to_string();
    assert!(err.contains("view 1") && err.contains("0x24"), "{err}");
    let view = r.add_view(shaders, RenderSettings::new(16, 16), &spec).unwrap();
    assert_eq!(view.to_string(), "view 1", "a refused view takes no id");
    let err = r.resize_view(shaders, view, 16, 0).unwrap_err().to_string();
    assert!(err.contains("view 1") && err.contains("16x0"), "{err}");
    let err = r.render_views(&[(view, &camera), (view, &camera)]).unwrap_err().to_string();
    assert!(err.contains("view 1") && err.contains("twice"), "{err}");
    let nan = Camera { eye: DVec3::NAN, ..camera.clone() };
    let err = r.render_views(&[(ViewId::MAIN, &camera), (view, &nan)]).unwrap_err().to_string();
    assert!(err.contains("view 1") && err.contains("not finite"), "{err}");
    r.remove_view(view).unwrap();
    let next = r.add_view(shaders, RenderSettings::new(16, 16), &spec).unwrap();
    assert_eq!(next.to_string(), "view 2", "ids are never given twice");
    r.remove_view(next).unwrap();
    for err in [
        r.render_views(&[(view, &camera)]).unwrap_err().to_string(),
        r.remove_view(view).unwrap_err().to_string(),
        r.resize_view(shaders, view, 8, 8).unwrap_err().to_string(),
    ] {
        assert!(err.contains("view 1") && err.contains("removed"), "{err}");
    }
    let err = r.remove_view(ViewId::MAIN).unwrap_err().to_string();
    assert!(err.contains("view 0") && err.contains("main view"), "{err}");
    // Up to the limit, then refused; the views that exist still render.
    let mut views = Vec::new();
    while r.views().count() < MAX_VIEWS {
        views.push(r.add_view(shaders, RenderSettings::new(2, 2), &spec).unwrap());
    }
    let err = r.add_view(shaders, RenderSettings::new(2, 2), &spec).unwrap_err().to_string();
    assert!(err.contains(&format!("at most {MAX_VIEWS} views")), "{err}");
    let frames: Vec<(ViewId, &Camera)> = views.iter().map(|&v| (v, &camera)).collect();
    assert_eq!(r.render_views(&frames).unwrap().len(), MAX_VIEWS - 1);
    gpu.assert_clean();
}

#[test]
fn a_second_view_shares_the_scene() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(400, (32, 24));
    let mut r = Renderer::new(&gpu, shaders, scene, RenderSettings::new(32, 24)).unwrap();
    r.render(&camera).unwrap();
    let instances = r.gpu_scene().instances.handle();
    let view = r.add_view(shaders, RenderSettings::new(32, 24), &GraphSpec::default_graph()).unwrap();
    // Same size and graph: the second view costs what the first costs besides the scene.
    assert_eq!(r.view_runtime(view).unwrap().memory(), r.runtime().memory());
    r.render_views(&[(ViewId::MAIN, &camera), (view, &camera)]).unwrap();
    assert_eq!(r.gpu_scene().instances.handle(), instances, "the scene was not uploaded again");
    gpu.assert_clean();
}

#[test]
fn views_of_a_growing_world_each_match_their_camera_alone() {
    use common::{boxes_camera, boxes_scene};
    use cullgraph::scene::world::World;
    use cullgraph::scene::{Instance, Transform};
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    // Three views with different sizes and graphs: each compiles for the world's quantities as
    // its own kinds count them, and each must follow the world's growth.
    let views = [
        (RenderSettings::new(64, 48), "two_phase", boxes_camera()),
        (RenderSettings::new(40, 30), "no_cull", Camera { eye: DVec3::new(-4.0, 2.0, 5.0), ..boxes_camera() }),
        (RenderSettings::new(32, 32), "one_phase", Camera { eye: DVec3::new(0.5, 6.0, 1.0), ..boxes_camera() }),
    ];
    let spec = |g: &str| GraphSpec::builtin(g).unwrap();
    let mut r = Renderer::from_world(&gpu, shaders, &world, views[0].0.clone(), &spec(views[0].1)).unwrap();
    let mut ids = vec![ViewId::MAIN];
    for (settings, graph, _) in &views[1..] {
        ids.push(r.add_view(shaders, settings.clone(), &spec(graph)).unwrap());
    }
    r.enable_verification(shaders).unwrap();
    let mut alone: Vec<Renderer> = views
        .iter()
        .map(|(settings, graph, _)| {
            Renderer::from_world(&gpu, shaders, &world, settings.clone(), &spec(graph)).unwrap()
        })
        .collect();
    for round in 0..5 {
        for k in 0..8 {
            let t = Transform {
                linear: glam::Mat3::from_diagonal(glam::Vec3::splat(0.5)),
                translation: DVec3::new(-3.0 + k as f64 * 0.8, 0.25, -2.0 - round as f64 * 0.9),
            };
            world.insert(Instance { transform: t, mesh: 0, material: 2, flags: 0 }).unwrap();
        }
        r.sync(shaders, &world).unwrap();
        let frame: Vec<(ViewId, &Camera)> = ids.iter().copied().zip(views.iter().map(|v| &v.2)).collect();
        let together = r.render_views_to_rgba8(&frame).unwrap();
        for (v, ((stats, image), renderer)) in together.iter().zip(&mut alone).enumerate() {
            renderer.sync(shaders, &world).unwrap();
            let (expected_stats, expected) = renderer.render_to_rgba8(&views[v].2).unwrap();
            assert!(*image == expected, "round {round}, view {v}: the image differs from its camera alone");
            assert_eq!(counts(stats), counts(&expected_stats), "round {round}, view {v}");
            assert_eq!(stats.verify.as_ref().unwrap().false_negatives, 0, "round {round}, view {v}");
        }
    }
    gpu.assert_clean();
}

/// More views than one dispatch culls (16): the views culled together give each view the image
/// and the figures of the views culled one at a time, frame after frame.
#[test]
fn views_culled_together_match_views_culled_one_at_a_time() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, overview) = city_view(600, (16, 12));
    let street = street_camera(&scene);
    let orbit = cullgraph::scene::CameraPath::Orbit;
    // Every phase and test of the pass: two phases against this frame's pyramid (more views than
    // one dispatch takes), frustum only, occluders then the rest, one phase against last frame's.
    for (graph, views) in [("default", 18), ("frustum", 5), ("occluder_prepass", 5), ("one_phase", 5)] {
        let spec = GraphSpec::builtin(graph).unwrap();
        let cameras: Vec<Camera> =
            (0..views).map(|i| orbit.camera_at(if i % 2 == 0 { &overview } else { &street }, i as u32 * 7)).collect();
        let mut renderers = Vec::new();
        for together in [true, false] {
            let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(16, 12), &spec).unwrap();
            let mut ids = vec![ViewId::MAIN];
            for i in 1..cameras.len() {
                // Sizes differ, so that each view's pyramid has its own size.
                let size = RenderSettings::new(12 + i as u32, 10 + (i as u32 % 3));
                ids.push(r.add_view(shaders, size, &spec).unwrap());
            }
            r.set_views_culled_together(together);
            renderers.push((r, ids));
        }
        let mut culled = 0;
        for frame in 0..3 {
            let results = common::render_each_views(&mut renderers, &cameras);
            for (v, (together, apart)) in results[0].iter().zip(&results[1]).enumerate() {
                assert!(together.1 == apart.1, "{graph}, frame {frame}, view {v}: the image differs");
                assert_eq!(counts(&together.0), counts(&apart.0), "{graph}, frame {frame}, view {v}");
            }
            culled += results[0].iter().map(|(s, _)| s.occlusion_culled + s.frustum_culled).sum::<u32>();
            if graph == "default" {
                let occluded: u32 = results[0].iter().map(|(s, _)| s.occlusion_culled).sum();
                assert!(frame == 0 || occluded > 0, "frame {frame}: the views cull by occlusion");
            }
        }
        assert!(culled > 0, "{graph}: the views cull");
    }
    gpu.assert_clean();
}

/// Orthographic views from above, each over one tile of a `grid` x `grid` partition of the
/// scene's bound, as shadow maps see a city.
fn tile_cameras(scene: &cullgraph::scene::Scene, grid: usize) -> Vec<Camera> {
    let (min, max) = scene.world_bounds().expect("the city has instances");
    let size = (max - min) / grid as f64;
    let height = (max.y - min.y).max(1.0) + 10.0;
    (0..grid * grid)
        .map(|tile| {
            let (tx, tz) = ((tile % grid) as f64, (tile / grid) as f64);
            let at = DVec3::new(min.x + (tx + 0.5) * size.x, (min.y + max.y) * 0.5, min.z + (tz + 0.5) * size.z);
            Camera {
                eye: at + DVec3::new(0.0, height, 0.0),
                target: at,
                up: glam::Vec3::Z,
                projection: cullgraph::scene::Projection::Orthographic {
                    height: size.x.max(size.z) as f32,
                    far: (2.0 * height) as f32,
                },
                near: 1.0,
                ..Default::default()
            }
        })
        .collect()
}

#[test]
fn tile_views_culled_together_cull_exactly_what_each_culls_alone() {
    // Views that each see one part of the world, as shadow maps of a city do, and instances on
    // their edges: each view's counts and image must equal its own run's. The city is large
    // enough that a block of one mesh's slots spans a few tiles, not the whole city.
    const INSTANCES: usize = 30000;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, _) = city_view(INSTANCES, (16, 16));
    let mut cameras = tile_cameras(&scene, 5);
    cameras.insert(0, street_camera(&scene));
    let spec = GraphSpec::builtin("frustum").unwrap();
    let mut renderers = Vec::new();
    for together in [true, false] {
        let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(16, 16), &spec).unwrap();
        let mut ids = vec![ViewId::MAIN];
        for _ in 1..cameras.len() {
            ids.push(r.add_view(shaders, RenderSettings::new(16, 16), &spec).unwrap());
        }
        r.set_views_culled_together(together);
        renderers.push((r, ids));
    }
    let mut results = Vec::new();
    for (r, ids) in &mut renderers {
        let frames: Vec<(ViewId, &Camera)> = ids.iter().copied().zip(&cameras).collect();
        results.push(r.render_views_to_rgba8(&frames).unwrap());
    }
    let mut drawn_by_tiles = 0;
    for (v, (together, apart)) in results[0].iter().zip(&results[1]).enumerate() {
        assert!(together.1 == apart.1, "view {v}: the image differs");
        assert_eq!(counts(&together.0), counts(&apart.0), "view {v}");
        if v > 0 {
            // Each tile draws its part of the city and culls the rest by frustum.
            assert!(
                together.0.drawn > 0 && together.0.frustum_culled > together.0.drawn,
                "view {v}: {:?}",
                counts(&together.0)
            );
            drawn_by_tiles += together.0.drawn;
        }
    }
    // The tiles cover the city: instances on their edges are drawn by several.
    assert!(drawn_by_tiles >= INSTANCES as u32, "the tiles drew {drawn_by_tiles} of {INSTANCES}");
    gpu.assert_clean();
}

/// A scene whose last 32-slot word holds two draw groups (four boxes, then a double-sided
/// quad) and ends before the word does: culled together, each view counts each instance in its
/// own group. (The slots past the end once read as group 0, so the word was taken for one
/// group's, and the quad was drawn as a box with the boxes' command.)
#[test]
fn views_culled_together_count_each_group_of_a_scene_ending_mid_word() {
    use cullgraph::scene::{Instance, Material, Transform};
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = common::boxes_scene();
    let quad = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    let two_sided = scene.add_material(Material {
        name: "two-sided".into(),
        albedo: glam::Vec3::new(0.1, 0.8, 0.2),
        double_sided: true,
        ..Default::default()
    });
    scene.instances.push(Instance {
        transform: Transform {
            linear: glam::Mat3::from_rotation_x(-1.2) * glam::Mat3::from_diagonal(glam::Vec3::splat(2.0)),
            translation: DVec3::new(0.0, 1.0, -1.5),
        },
        mesh: quad,
        material: two_sided,
        flags: 0,
    });
    let above = Camera { eye: DVec3::new(0.0, 12.0, 0.5), target: DVec3::ZERO, ..Default::default() };
    let mut images = Vec::new();
    for together in [true, false] {
        let spec = GraphSpec::default_graph();
        let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(96, 64), &spec).unwrap();
        r.set_views_culled_together(together);
        let second = r.add_view(shaders, RenderSettings::new(64, 64), &spec).unwrap();
        let frames = [(ViewId::MAIN, &common::boxes_camera()), (second, &above)];
        r.render_views_to_rgba8(&frames).unwrap();
        let out = r.render_views_to_rgba8(&frames).unwrap();
        images.push(out.into_iter().map(|(_, image)| image).collect::<Vec<_>>());
    }
    assert!(images[0][0] == images[1][0], "the first view's image differs when culled together");
    assert!(images[0][1] == images[1][1], "the second view's image differs when culled together");
    gpu.assert_clean();
}
