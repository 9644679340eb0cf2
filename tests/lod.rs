//! Levels of detail chosen on the GPU (lavapipe, validation on): the cull passes draw distant
//! props of `builtin:dense` coarser, each level through the same indirect-count draws; every
//! culling graph places the levels alike; the image stays close to full detail, and at 1 px no
//! further from a supersampled reference than full detail is; an instance whose bound holds the camera
//! is drawn whole; the choice depends on the eye-relative position only, so a world 10^7 units
//! from the origin looks the same.

mod common;

use common::dense::{dense, graph, near_camera, sphere};
use common::GpuTest;
use cullgraph::oracle::Verify;
use cullgraph::passes::instance_cull::CullPassStats;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::{Camera, Instance, Scene, Transform};
use cullgraph::stats::FrameStats;
use glam::{DVec3, Mat3};

const SIZE: (u32, u32) = (160, 90);

/// The last of `frames` frames of `camera` through `spec`: its stats and RGBA bytes; no frame
/// missed a visible instance.
fn render(gpu: &GpuTest, scene: &Scene, camera: &Camera, spec: &GraphSpec, frames: u32) -> (FrameStats, Vec<u8>) {
    render_sized(gpu, scene, camera, spec, frames, true, SIZE)
}

/// [`render`] at `size`, with the exact-visibility check or without (it casts rays through
/// every triangle of every instance: too slow for tens of thousands of dense props).
fn render_sized(
    gpu: &GpuTest,
    scene: &Scene,
    camera: &Camera,
    spec: &GraphSpec,
    frames: u32,
    verify: bool,
    size: (u32, u32),
) -> (FrameStats, Vec<u8>) {
    let shaders = gpu.shaders();
    let settings = RenderSettings::new(size.0, size.1);
    let mut renderer = Renderer::with_graph(gpu, shaders, scene.clone(), settings, spec).unwrap();
    if verify {
        renderer.enable_verification(shaders).unwrap();
    }
    let missed = |stats: &FrameStats| stats.verify.as_ref().map_or(0, |v| v.false_negatives);
    for _ in 1..frames {
        assert_eq!(missed(&renderer.render(camera).unwrap()), 0);
    }
    let (stats, image) = renderer.render_to_image(camera).unwrap();
    assert_eq!(missed(&stats), 0);
    (stats, image.into_raw())
}

/// Instances drawn at each level over the frame's cull passes and lists.
fn levels(stats: &FrameStats) -> Vec<u32> {
    CullPassStats::level_totals(stats)
}

/// `image` (RGBA, sRGB, `factor` times [`SIZE`] per axis) averaged over each `factor` x
/// `factor` block in linear light: a supersampled reference at [`SIZE`].
fn downsampled(image: &[u8], factor: u32) -> Vec<u8> {
    let to_linear = |c: u8| {
        let c = c as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let to_srgb = |l: f64| {
        let c = if l <= 0.0031308 { l * 12.92 } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
        (c * 255.0).round().clamp(0.0, 255.0) as u8
    };
    let width = (SIZE.0 * factor) as usize;
    let mut out = Vec::with_capacity((SIZE.0 * SIZE.1 * 4) as usize);
    for y in 0..SIZE.1 as usize {
        for x in 0..SIZE.0 as usize {
            for c in 0..4 {
                let mut sum = 0.0;
                for dy in 0..factor as usize {
                    for dx in 0..factor as usize {
                        let at = ((y * factor as usize + dy) * width + x * factor as usize + dx) * 4 + c;
                        sum += if c == 3 { image[at] as f64 / 255.0 } else { to_linear(image[at]) };
                    }
                }
                let mean = sum / (factor * factor) as f64;
                out.push(if c == 3 { (mean * 255.0).round() as u8 } else { to_srgb(mean) });
            }
        }
    }
    out
}

/// Mean and largest absolute channel difference (RGB) of two images.
fn difference(a: &[u8], b: &[u8]) -> (f64, u8) {
    let (mut sum, mut most, mut n) = (0u64, 0u8, 0u64);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = pa[c].abs_diff(pb[c]);
            sum += d as u64;
            most = most.max(d);
            n += 1;
        }
    }
    (sum as f64 / n as f64, most)
}

#[test]
fn levels_cut_the_triangles_and_keep_the_image_close() {
    let gpu = GpuTest::new();
    let scene = dense(40);
    let camera = near_camera();
    let (full, full_image) = render(&gpu, &scene, &camera, &graph("frustum", 0.0), 1);
    let (one, one_image) = render(&gpu, &scene, &camera, &graph("frustum", 1.0), 1);
    let (four, four_image) = render(&gpu, &scene, &camera, &graph("frustum", 4.0), 1);
    assert_eq!((one.drawn, four.drawn), (full.drawn, full.drawn), "levels change no culling decision");
    assert_eq!(levels(&full), [full.drawn], "threshold 0 draws every instance whole");
    for stats in [&one, &four] {
        assert_eq!(levels(stats).iter().sum::<u32>(), stats.drawn, "{:?}", levels(stats));
        assert!(levels(stats)[1..].iter().any(|&n| n > 0), "no coarser level drawn: {:?}", levels(stats));
    }
    // Close up, most props are a few hundred pixels tall: fewer triangles go than from afar.
    assert!(one.triangles * 3 <= full.triangles * 2, "{} triangles at 1 px, {} whole", one.triangles, full.triangles);
    assert!(four.triangles * 3 <= full.triangles, "{} triangles at 4 px, {} whole", four.triangles, full.triangles);
    let (mean_one, _) = difference(&one_image, &full_image);
    let (mean_four, _) = difference(&four_image, &full_image);
    // Against the supersampled full detail (the image without aliasing), levels at 1 px stay as
    // close as the full detail drawn at one sample per pixel: their normals show what the bumps
    // average to, which the full mesh's single sample per pixel aliases. At 4 px, where props
    // of this small image take levels whose surface may move by 4 pixels, within a tenth more.
    let (_, reference) =
        render_sized(&gpu, &scene, &camera, &graph("frustum", 0.0), 1, false, (SIZE.0 * 4, SIZE.1 * 4));
    let reference = downsampled(&reference, 4);
    let (full_error, one_error, four_error) = (
        difference(&full_image, &reference).0,
        difference(&one_image, &reference).0,
        difference(&four_image, &reference).0,
    );
    eprintln!("mean channel difference: {mean_one} at 1 px, {mean_four} at 4 px; from the reference: {full_error} whole, {one_error} at 1 px, {four_error} at 4 px");
    assert!(
        one_error <= full_error && four_error <= 1.1 * full_error,
        "levels drift from the reference: {one_error}, {four_error} against {full_error} whole"
    );
    // And from the full detail, less than a step of 255 on average at 1 px, less than one and a
    // half at 4 px, less at the lower threshold.
    assert!(
        mean_one <= mean_four && mean_one < 1.0 && mean_four < 1.5,
        "mean channel difference {mean_one} at 1 px, {mean_four} at 4 px"
    );
}

#[test]
fn every_culling_graph_places_the_levels_alike() {
    let gpu = GpuTest::new();
    let scene = dense(120);
    let camera = near_camera();
    let (frustum, image) = render(&gpu, &scene, &camera, &graph("frustum", 2.0), 1);
    // Two-phase: the early draw is last frame's visible list at its levels.
    for (name, frames) in [("two_phase", 3), ("one_phase", 3), ("occluder_prepass", 1)] {
        let (stats, other) = render(&gpu, &scene, &camera, &graph(name, 2.0), frames);
        assert!(other == image, "{name} drew another image than frustum culling at the same levels");
        assert!(
            stats.triangles <= frustum.triangles,
            "{name}: {} triangles, frustum {}",
            stats.triangles,
            frustum.triangles
        );
    }
}

#[test]
fn an_instance_whose_bound_holds_the_camera_is_drawn_whole() {
    let gpu = GpuTest::new();
    let mut scene = dense(4);
    // Two rocks (kind 0): one around the camera, one 300 units ahead of it.
    scene.instances.truncate(2);
    let rock = scene.instances[1].mesh;
    let at = |x: f64| Instance {
        transform: Transform { linear: Mat3::IDENTITY, translation: DVec3::new(x, 0.0, 0.0) },
        mesh: rock,
        material: 0,
        flags: 0,
    };
    scene.instances = vec![at(0.0), at(300.0)];
    let camera = Camera { eye: DVec3::new(0.3, 0.2, 0.0), target: DVec3::new(300.0, 0.0, 0.0), ..Default::default() };
    let (stats, _) = render(&gpu, &scene, &camera, &graph("frustum", 1.0), 1);
    let levels = levels(&stats);
    assert_eq!(stats.drawn, 2);
    assert_eq!(levels[0], 1, "the rock around the camera is drawn whole: {levels:?}");
    assert!(levels.len() > 1 && levels[1..].iter().sum::<u32>() == 1, "the far rock is drawn coarser: {levels:?}");
}

#[test]
fn a_world_far_from_the_origin_chooses_the_same_levels() {
    let gpu = GpuTest::new();
    let scene = dense(40);
    let camera = near_camera();
    let (near, image) = render(&gpu, &scene, &camera, &graph("frustum", 1.0), 1);
    let offset = DVec3::new(1.0e7, 0.0, -1.0e7);
    let mut far_scene = scene.clone();
    far_scene.translate(offset);
    let far_camera = Camera { eye: camera.eye + offset, target: camera.target + offset, ..camera };
    let (far, far_image) = render(&gpu, &far_scene, &far_camera, &graph("frustum", 1.0), 1);
    assert_eq!(levels(&far), levels(&near));
    assert_eq!(far.triangles, near.triangles);
    let (mean, _) = difference(&far_image, &image);
    assert!(mean < 0.05, "mean channel difference {mean} 10^7 units out");
}

#[test]
fn the_command_line_takes_a_threshold_and_refuses_bad_ones() {
    use common::cli::run;
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x.png");
    let stats = tmp.path().join("s.json");
    let (out, stats_path) = (out.to_str().unwrap(), stats.to_str().unwrap());
    let triangles = |threshold: &str| {
        let args = ["render", "--scene", "builtin:dense", "--instances", "12", "--size", "96x54", "--frames", "2"];
        let (code, _, err) =
            run(&[&args[..], &["--lod-threshold", threshold, "--out", out, "--stats", stats_path]].concat());
        assert_eq!(code, 0, "{err}");
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        json["frames"][1]["triangles"].as_u64().unwrap()
    };
    let (full, coarse) = (triangles("0"), triangles("2"));
    assert!(coarse * 3 <= full, "{coarse} triangles at 2 px, {full} whole");
    for bad in ["-1", "nan", "1e9", "x"] {
        let (code, _, err) = run(&["render", "--lod-threshold", bad, "--out", out]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("is not a threshold in pixels from 0 to"), "{err}");
    }
    // Atomic compaction has no order to place levels in: refused at the pass.
    let graph = tmp.path().join("atomic.ron");
    let text = "Graph(name: \"atomic_lod\", extends: \"frustum\", edits: [\n    Set(pass: \"cull\", settings: {\"compaction\": \"atomic\", \"lod_threshold\": 1.0}),\n])\n";
    std::fs::write(&graph, text).unwrap();
    let (code, _, err) = run(&["graph", "check", graph.to_str().unwrap(), "--size", "64x48"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("pass 'cull'") && err.contains("needs ordered compaction"), "{err}");
}

#[test]
fn mirrored_instances_choose_the_levels_of_their_twins() {
    let gpu = GpuTest::new();
    let scene = dense(40);
    let camera = near_camera();
    // The scene and the camera mirrored across x = 0: every instance's determinant flips.
    let mut mirrored = scene.clone();
    let flip = Mat3::from_diagonal(glam::Vec3::new(-1.0, 1.0, 1.0));
    for instance in &mut mirrored.instances {
        instance.transform.linear = flip * instance.transform.linear;
        instance.transform.translation.x = -instance.transform.translation.x;
    }
    let mirror = |p: DVec3| DVec3::new(-p.x, p.y, p.z);
    let mirrored_camera = Camera { eye: mirror(camera.eye), target: mirror(camera.target), ..camera.clone() };
    let (plain, _) = render(&gpu, &scene, &camera, &graph("frustum", 1.0), 1);
    let (twin, _) = render(&gpu, &mirrored, &mirrored_camera, &graph("frustum", 1.0), 1);
    assert_eq!(twin.drawn, plain.drawn);
    assert_eq!(levels(&twin), levels(&plain));
    assert_eq!(twin.triangles, plain.triangles);
}

#[test]
fn levels_are_placed_alike_over_many_superblocks() {
    let gpu = GpuTest::new();
    // 40 000 props: the slots span three superblocks of 16 384, so each block's levels start
    // where the superblocks before it leave off.
    let scene = dense(40_000);
    let camera =
        Camera { eye: DVec3::new(-20.0, 6.0, -30.0), target: DVec3::new(200.0, 0.0, 150.0), ..Default::default() };
    let shaders = gpu.shaders();
    // The instance ids frustum culling drew at `threshold`, sorted, with the frame's stats and image.
    let drawn = |name: &str, threshold: f64, frames: u32| {
        let settings = RenderSettings::new(SIZE.0, SIZE.1);
        let mut renderer =
            Renderer::with_graph(&gpu, shaders, scene.clone(), settings, &graph(name, threshold)).unwrap();
        renderer.capture_draw_lists(true).unwrap();
        for _ in 1..frames {
            renderer.render(&camera).unwrap();
        }
        let (stats, image) = renderer.render_to_image(&camera).unwrap();
        let mut ids: Vec<u32> = Vec::new();
        for pass in renderer.drawn().unwrap().unwrap() {
            if let cullgraph::render::DrawnInstances::Some(list) = pass {
                ids.extend(list);
            }
        }
        ids.sort_unstable();
        (ids, stats, image.into_raw())
    };
    let (ids, frustum, image) = drawn("frustum", 4.0, 1);
    assert!(frustum.drawn > 500, "{} drawn", frustum.drawn);
    assert!(levels(&frustum)[1..].iter().filter(|&&n| n > 0).count() >= 2, "{:?}", levels(&frustum));
    assert_eq!(levels(&frustum).iter().sum::<u32>(), frustum.drawn);
    // Each survivor placed once, whatever its level: the same set with every instance at its
    // coarsest level.
    assert_eq!(ids.len(), frustum.drawn as usize);
    assert!(ids.windows(2).all(|w| w[0] < w[1]), "an instance was placed twice");
    let (coarsest, _, _) = drawn("frustum", 1.0e6, 1);
    assert!(ids == coarsest, "the drawn set depends on the levels");
    // Two-phase culling places the next frame's early list the same way.
    let (_, late, other) = drawn("two_phase", 4.0, 3);
    assert!(other == image, "two-phase culling drew another image than frustum culling at the same levels");
    assert!(late.triangles <= frustum.triangles);
}

#[test]
fn the_threshold_changes_live_once_levels_are_chosen() {
    use cullgraph::render::ParamsApplied;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = dense(40);
    let camera = near_camera();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut renderer = Renderer::with_graph(&gpu, shaders, scene.clone(), settings, &graph("frustum", 0.0)).unwrap();
    let (whole, whole_image) = renderer.render_to_image(&camera).unwrap();
    // From none to some levels: the pass is made again with them.
    assert_eq!(renderer.set_graph_params(shaders, &[("lod_threshold", "1.0")]).unwrap(), ParamsApplied::Rebuilt);
    let (one, _) = renderer.render_to_image(&camera).unwrap();
    // Between thresholds, and back to 0, it takes them as they are.
    assert_eq!(renderer.set_graph_params(shaders, &[("lod_threshold", "4.0")]).unwrap(), ParamsApplied::Live);
    let (four, four_image) = renderer.render_to_image(&camera).unwrap();
    assert_eq!(renderer.set_graph_params(shaders, &[("lod_threshold", "0.0")]).unwrap(), ParamsApplied::Live);
    let (zero, zero_image) = renderer.render_to_image(&camera).unwrap();
    assert!(four.triangles < one.triangles && one.triangles < whole.triangles);
    // Each as a renderer loaded with that threshold draws it.
    let (loaded, loaded_image) = render(&gpu, &scene, &camera, &graph("frustum", 4.0), 1);
    assert_eq!(four.triangles, loaded.triangles);
    assert!(four_image.into_raw() == loaded_image);
    assert_eq!(zero.triangles, whole.triangles);
    assert!(zero_image.into_raw() == whole_image.into_raw(), "threshold 0 set live draws every mesh whole");
}

#[test]
fn a_live_world_draws_its_meshes_at_levels_as_a_loaded_scene_does() {
    use cullgraph::scene::merge::SceneMerge;
    use cullgraph::scene::world::World;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let camera = near_camera();
    let spec = graph("two_phase", 1.0);
    let (mut world, _) = World::new(dense(40)).unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut renderer = Renderer::from_world(&gpu, shaders, &world, settings, &spec).unwrap();
    // The world's frame after `frames` frames, beside a renderer loaded with its live scene.
    let compare = |world: &World, renderer: &mut Renderer, what: &str| {
        let synced = renderer.sync(shaders, world).unwrap();
        for _ in 1..3 {
            renderer.render(&camera).unwrap();
        }
        let (stats, image) = renderer.render_to_image(&camera).unwrap();
        let (loaded, loaded_image) = render_sized(&gpu, &world.live_scene(), &camera, &spec, 3, false, SIZE);
        assert_eq!(levels(&stats), levels(&loaded), "{what}");
        assert_eq!(stats.triangles, loaded.triangles, "{what}");
        let (mean, _) = difference(&image.into_raw(), &loaded_image);
        assert!(mean == 0.0, "{what}: mean channel difference {mean} from the loaded scene");
        (stats, synced.relayout)
    };
    let (first, _) = compare(&world, &mut renderer, "the world as loaded");
    assert!(levels(&first)[1..].iter().any(|&n| n > 0), "{:?}", levels(&first));
    // A second copy of the props streamed in beside the first: their meshes come with chains.
    let placement = Transform { linear: Mat3::IDENTITY, translation: DVec3::new(-12.0, 0.0, 6.0) };
    let mut merge = SceneMerge::new(dense(40), placement).unwrap();
    merge.add_all(&mut world).unwrap();
    let (merged, relayout) = compare(&world, &mut renderer, "a scene merged in");
    assert!(!relayout, "the merged meshes' levels fit the layout's room");
    assert!(merged.drawn > first.drawn);
    // A mesh registered by the engine gets its chain, and its pool space back when unregistered.
    let ball = world.add_mesh("ball", &sphere(96, 192)).unwrap();
    assert!(!world.scene().meshes[ball as usize].lods.is_empty());
    let at = |x: f64, z: f64| Instance {
        transform: Transform {
            linear: Mat3::from_diagonal(glam::Vec3::splat(1.5)),
            translation: DVec3::new(x, 2.0, z),
        },
        mesh: ball,
        material: 0,
        flags: 0,
    };
    let balls: Vec<_> = [(4.0, 4.0), (-30.0, -30.0)].iter().map(|&(x, z)| world.insert(at(x, z)).unwrap()).collect();
    let (with_balls, _) = compare(&world, &mut renderer, "a registered mesh");
    assert!(with_balls.drawn > merged.drawn);
    let indices = world.scene().indices.len();
    for handle in balls {
        world.remove(handle).unwrap();
    }
    world.remove_mesh(ball).unwrap();
    let again = world.add_mesh("ball again", &sphere(96, 192)).unwrap();
    assert_eq!(world.scene().indices.len(), indices, "the new chain takes the old one's place");
    world.insert(at(4.0, 4.0)).unwrap();
    let _ = again;
    compare(&world, &mut renderer, "a mesh registered in a freed place");
    gpu.assert_clean();
}

/// Shadow casters take the level of detail their camera view takes (`ShadowSettings::
/// lod_threshold`): the triangles the sun's cascade draws follow the camera view's pixels, not
/// the map's (a larger view draws finer casters into the same map), and without a threshold
/// every caster is whole at any size.
#[test]
fn shadow_casters_take_the_levels_of_their_camera_view() {
    use cullgraph::render::ShadowSettings;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = dense(16);
    let camera = near_camera();
    // The first frame's cascade: its early list is empty, so levels change no culling decision.
    let cascade = |threshold: f64, (w, h): (u32, u32)| -> (u32, u64) {
        let spec = GraphSpec::builtin("two_phase").unwrap();
        let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
        let shadows = ShadowSettings {
            cascades: 1,
            resolution: 256,
            local_lights: 0,
            lod_threshold: threshold,
            ..Default::default()
        };
        r.set_shadows(shaders, Some(shadows)).unwrap();
        let stats = r.render(&camera).unwrap();
        let drawn = &stats.shadow_cascades[0];
        (drawn.drawn, drawn.triangles)
    };
    let (small, large) = ((64, 36), (256, 144));
    let whole = cascade(0.0, small);
    assert_eq!(cascade(0.0, large), whole, "every caster whole at any size");
    let (coarse, fine) = (cascade(2.0, small), cascade(2.0, large));
    assert_eq!((coarse.0, fine.0), (whole.0, whole.0), "levels change no culling decision");
    assert!(coarse.1 < fine.1, "{} triangles for the small view, {} for the large one", coarse.1, fine.1);
    assert!(fine.1 < whole.1, "{} triangles at 2 px, {} whole", fine.1, whole.1);
    gpu.assert_clean();
}

/// Views culled together choose each view's levels in its own pixels: a near view and smaller,
/// farther ones get the images, counts, levels and triangles they get culled one at a time,
/// frame after frame, for one-pass and two-phase culling.
#[test]
fn views_culled_together_choose_each_views_own_levels() {
    use cullgraph::render::ViewId;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = dense(300);
    let far = Camera { eye: DVec3::new(-30.0, 12.0, -40.0), target: DVec3::new(20.0, 0.0, 20.0), ..Default::default() };
    let cameras = [near_camera(), far, Camera { eye: DVec3::new(40.0, 3.0, 5.0), ..near_camera() }];
    let sizes = [SIZE, (64, 36), (96, 54)];
    for name in ["frustum", "two_phase"] {
        let spec = graph(name, 2.0);
        let mut renderers = Vec::new();
        for together in [true, false] {
            let mut r =
                Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
            let mut ids = vec![ViewId::MAIN];
            for size in &sizes[1..] {
                ids.push(r.add_view(shaders, RenderSettings::new(size.0, size.1), &spec).unwrap());
            }
            r.set_views_culled_together(together);
            renderers.push((r, ids));
        }
        // The cull passes of the views can be recorded together.
        let runtime = renderers[0].0.view_runtime(ViewId::MAIN).unwrap();
        let culls: Vec<usize> =
            (0..runtime.plan().passes.len()).filter(|&i| runtime.together_key(i).is_some()).collect();
        assert!(!culls.is_empty(), "{name}: no pass culls views together");
        for frame in 0..3 {
            let results = common::render_each_views(&mut renderers, &cameras);
            for (v, (together, apart)) in results[0].iter().zip(&results[1]).enumerate() {
                assert!(together.1 == apart.1, "{name}, frame {frame}, view {v}: the image differs");
                assert_eq!(levels(&together.0), levels(&apart.0), "{name}, frame {frame}, view {v}");
                assert_eq!(
                    (together.0.drawn, together.0.triangles, together.0.frustum_culled, together.0.occlusion_culled),
                    (apart.0.drawn, apart.0.triangles, apart.0.frustum_culled, apart.0.occlusion_culled),
                    "{name}, frame {frame}, view {v}"
                );
            }
            // Each view at its own levels: the near view draws props finer than the far ones.
            let coarse = |s: &FrameStats| levels(s)[1..].iter().sum::<u32>() as f64 / s.drawn.max(1) as f64;
            let (near, far) = (&results[0][0].0, &results[0][1].0);
            assert!(near.drawn > 0 && far.drawn > 0, "{name}: {} and {} drawn", near.drawn, far.drawn);
            assert!(
                coarse(far) > coarse(near),
                "{name}, frame {frame}: {:?} near, {:?} far",
                levels(near),
                levels(far)
            );
        }
    }
    gpu.assert_clean();
}
