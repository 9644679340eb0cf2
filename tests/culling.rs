//! GPU culling on lavapipe with validation on: every culling graph must draw every visible
//! instance (exact visibility from an unculled id render is the oracle) and give the same image,
//! pixel for pixel, as no culling. Named hard cases (the occlusion test's variants, the MSAA
//! graphs against themselves with culling off, one_phase's misses counted exactly), then property
//! tests over random scenes, cameras, sizes and occlusion-test params.

mod common;

use common::{cube_mesh, GpuTest};
use cullgraph::gpu::ShaderCompiler;
use cullgraph::oracle::raycast::{RaycastOracle, SamplePattern};
use cullgraph::oracle::Verify;
use cullgraph::passes::instance_cull::CullPassStats;
use cullgraph::render::output::RgbaImage;
use cullgraph::render::DrawnInstances;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, CameraPath, Instance, Material, MeshData, Projection, Scene, SceneSource, Transform};
use cullgraph::stats::FrameStats;
use glam::{DVec3, Mat3, Vec3};
use proptest::prelude::*;
use std::cell::Cell;
use std::collections::BTreeSet;
use std::time::Instant;

/// Graphs that must never miss a visible instance.
const EXACT_GRAPHS: [&str; 3] = ["frustum", "two_phase", "occluder_prepass"];

/// A built-in graph with param overrides.
fn graph(name: &str, params: &[(&str, &str)]) -> GraphSpec {
    GraphSpec::builtin(name).unwrap().with_overrides(params.iter().map(|(k, v)| (k.to_string(), v.to_string())))
}

/// A graph's name and overrides, for messages.
fn label(spec: &GraphSpec) -> String {
    let params: Vec<String> = spec.overrides.iter().map(|(k, v)| format!("{k}={v}")).collect();
    format!("{} [{}]", spec.file, params.join(" "))
}

/// A scene seen from `camera` moving along `path`, at `size`, for `frames` frames.
#[derive(Clone, Copy)]
struct Shot<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    size: (u32, u32),
    frames: u32,
    path: CameraPath,
}

/// Renders `shot` through `spec`, with verification on if `verify`: each frame's image and stats.
fn render_path(
    gpu: &GpuTest,
    shaders: &ShaderCompiler,
    shot: Shot<'_>,
    spec: &GraphSpec,
    verify: bool,
) -> (Vec<RgbaImage>, Vec<FrameStats>) {
    let settings = RenderSettings::new(shot.size.0, shot.size.1);
    let mut r = Renderer::with_graph(gpu, shaders, shot.scene.clone(), settings, spec).unwrap();
    if verify {
        r.enable_verification(shaders).unwrap();
    }
    (0..shot.frames)
        .map(|f| {
            let (stats, image) = r.render_to_image(&shot.path.camera_at(shot.camera, f)).unwrap();
            (image, stats)
        })
        .unzip()
}

/// Renders `shot` through `reference` (a graph that culls nothing) and through each of
/// `graphs`, and checks every frame of each graph against the reference: no false negatives and
/// the same image, pixel for pixel. Returns the reference's stats (it is not verified), then
/// each graph's.
fn check_graphs(
    gpu: &GpuTest,
    shaders: &ShaderCompiler,
    shot: Shot<'_>,
    reference: &GraphSpec,
    graphs: &[GraphSpec],
) -> (Vec<FrameStats>, Vec<Vec<FrameStats>>) {
    let render = |spec: &GraphSpec, verify| render_path(gpu, shaders, shot, spec, verify);
    let (reference_images, reference_stats) = render(reference, false);
    let all = graphs
        .iter()
        .map(|spec| {
            let (images, stats) = render(spec, true);
            let graph = label(spec);
            for (f, (image, s)) in images.iter().zip(&stats).enumerate() {
                let v = s.verify.as_ref().unwrap();
                assert_eq!(
                    v.false_negatives, 0,
                    "{graph}, frame {f}: visible instances culled: {:?} ({s:?})",
                    v.missed
                );
                assert!(
                    image.as_raw() == reference_images[f].as_raw(),
                    "{graph}, frame {f}: the image differs from {}",
                    label(reference)
                );
            }
            stats
        })
        .collect();
    (reference_stats, all)
}

/// Renders `frames` frames of each exact graph along `path` and checks them against no culling:
/// identical images and no false negatives. Returns the culled graphs' last-frame stats.
fn check(
    gpu: &GpuTest,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    frames: u32,
    path: CameraPath,
) -> Vec<FrameStats> {
    let graphs = EXACT_GRAPHS.map(|g| graph(g, &[]));
    let (_, stats) =
        check_graphs(gpu, gpu.shaders(), Shot { scene, camera, size, frames, path }, &graph("no_cull", &[]), &graphs);
    stats.into_iter().map(|s| s.last().unwrap().clone()).collect()
}

/// Renderers of `scene` through no culling and every exact graph, kept for a test's duration so
/// that the renderers each `check` makes find their pipelines alive and share them (a device
/// keeps a pipeline while a renderer uses it): on lavapipe, creating pipelines is most of a
/// small check's time.
fn keep_pipelines(gpu: &GpuTest, scene: &Scene) -> Vec<Renderer> {
    let shaders = gpu.shaders();
    let mut kept: Vec<Renderer> = std::iter::once("no_cull")
        .chain(EXACT_GRAPHS)
        .map(|g| Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(8, 8), &graph(g, &[])).unwrap())
        .collect();
    // The verified renderers' oracle pipelines too.
    kept[1].enable_verification(shaders).unwrap();
    kept
}

/// A small scene: a wall in front of boxes, boxes beside it, one box behind the eye.
fn wall_scene() -> Scene {
    let mut scene = Scene { name: "wall".into(), ..Default::default() };
    let cube = scene.add_mesh("cube", &cube_mesh(), "cube").unwrap();
    let grey = scene.add_material(Material::default());
    let red = scene.add_material(Material {
        name: "red".into(),
        albedo: Vec3::new(0.8, 0.1, 0.1),
        roughness: 0.5,
        metallic: 0.0,
        double_sided: false,
        ..Default::default()
    });
    let mut place = |scale: Vec3, at: DVec3, material: u32, flags: u32| {
        scene.instances.push(Instance {
            transform: Transform { linear: Mat3::from_diagonal(scale), translation: at },
            mesh: cube,
            material,
            flags,
        })
    };
    place(Vec3::new(40.0, 0.2, 40.0), DVec3::new(0.0, -0.1, 0.0), grey, 0); // ground
    place(Vec3::new(8.0, 6.0, 0.5), DVec3::new(0.0, 3.0, -4.0), grey, 1); // wall (occluder)
    for i in 0..6 {
        // Hidden behind the wall, well inside its silhouette for perspective and orthographic views.
        place(Vec3::ONE, DVec3::new(-2.5 + i as f64, 2.5, -8.0), red, 0);
    }
    place(Vec3::ONE, DVec3::new(6.0, 0.5, -6.0), red, 0); // beside the wall: visible
    place(Vec3::ONE, DVec3::new(0.0, 0.5, 8.0), red, 0); // behind the eye
    scene
}

fn wall_camera() -> Camera {
    Camera { eye: DVec3::new(0.0, 1.5, 4.0), target: DVec3::new(0.0, 1.5, -10.0), ..Default::default() }
}

#[test]
fn hidden_boxes_are_culled_and_visible_ones_kept() {
    let gpu = GpuTest::new();
    let stats = check(&gpu, &wall_scene(), &wall_camera(), (64, 48), 3, CameraPath::Still);
    let two_phase = &stats[1];
    // 6 boxes hide behind the wall; the one behind the eye is outside the frustum.
    assert!(two_phase.occlusion_culled >= 6, "{two_phase:?}");
    assert!(two_phase.frustum_culled >= 1, "{two_phase:?}");
}

/// The occlusion test's variants, each alone and all together.
const OCCLUSION_VARIANTS: [&[(&str, &str)]; 4] = [
    &[("hiz_test", "finer")],
    &[("bound", "sphere")],
    &[("hiz_method", "per_mip")],
    &[("hiz_test", "finer"), ("bound", "sphere"), ("hiz_method", "per_mip")],
];

#[test]
fn occlusion_test_variants_keep_every_visible_instance_under_motion() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    // The two-phase graph with the finer footprint, sphere bounds and the per-mip pyramid (each
    // alone and together), and the pre-pass with all three.
    let graphs: Vec<GraphSpec> = OCCLUSION_VARIANTS
        .iter()
        .map(|params| graph("two_phase", params))
        .chain([graph("occluder_prepass", OCCLUSION_VARIANTS[3])])
        .collect();
    for path in [CameraPath::Orbit, CameraPath::Shake] {
        let start = Instant::now();
        let (scene, camera) = (wall_scene(), wall_camera());
        let shot = Shot { scene: &scene, camera: &camera, size: (48, 36), frames: 5, path };
        let (_, stats) = check_graphs(&gpu, shaders, shot, &graph("no_cull", &[]), &graphs);
        for (spec, stats) in graphs.iter().zip(&stats) {
            // Each variant did cull by occlusion along the way (the boxes behind the wall), so
            // its test was exercised, not just skipped.
            let occluded: Vec<u32> = stats.iter().map(|s| s.occlusion_culled).collect();
            assert!(occluded.iter().sum::<u32>() >= 6, "{} along {path:?}: occlusion-culled {occluded:?}", label(spec));
            println!("{} along {path:?}: occlusion-culled per frame {occluded:?}", label(spec));
        }
        println!("occlusion variants along {path:?}: {:.2} s", start.elapsed().as_secs_f64());
    }
}

/// The instances the renderer's last frame drew (verification on).
fn drawn_instances(r: &Renderer) -> BTreeSet<u32> {
    let lists = r.drawn().unwrap().expect("verification is on");
    let all = lists.contains(&DrawnInstances::All);
    let instances = r.scene().instances.len() as u32;
    lists
        .into_iter()
        .flat_map(|l| match l {
            DrawnInstances::Some(ids) if !all => ids,
            _ => Vec::new(),
        })
        .chain(if all { 0..instances } else { 0..0 })
        .collect()
}

#[test]
fn one_phase_counts_exactly_the_instances_it_pops_in_late() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, size) = (wall_scene(), (48, 36));
    // The orbit at three steps a frame (36 degrees) brings the boxes out from behind the wall
    // from one frame to the next: hidden in last frame's pyramid, one_phase culls them for a
    // frame. A still camera has nothing new to miss.
    let orbit: Vec<Camera> = (0..5).map(|f| CameraPath::Orbit.camera_at(&wall_camera(), 3 * f)).collect();
    let mut total_missed = 0;
    for (what, cameras) in [("fast orbit", orbit), ("still", vec![wall_camera(); 4])] {
        let start = Instant::now();
        let render = |spec: &GraphSpec| {
            let settings = RenderSettings::new(size.0, size.1);
            let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), settings, spec).unwrap();
            r.enable_verification(shaders).unwrap();
            r
        };
        let mut reference = render(&graph("no_cull", &[]));
        let mut r = render(&graph("one_phase", &[]));
        let mut last_visible = BTreeSet::new();
        let mut missed_per_frame = Vec::new();
        for (f, camera) in cameras.iter().enumerate() {
            let (_, expected) = reference.render_to_image(camera).unwrap();
            let (stats, image) = r.render_to_image(camera).unwrap();
            let v = stats.verify.as_ref().unwrap();
            // The count is exactly the visible instances left undrawn, and `missed` lists them.
            let visible = r.exactly_visible().clone();
            let missed: Vec<u32> = visible.difference(&drawn_instances(&r)).copied().collect();
            assert_eq!(v.false_negatives as usize, missed.len(), "{what}, frame {f}: {v:?}");
            assert_eq!(v.missed, missed.iter().take(16).copied().collect::<Vec<_>>(), "{what}, frame {f}");
            assert_eq!(v.visible as usize, visible.len(), "{what}, frame {f}");
            // What one_phase misses pops in: it was not visible last frame (what was visible
            // then is in front in the pyramid it tests against).
            assert!(missed.iter().all(|i| !last_visible.contains(i)), "{what}, frame {f}: missed {missed:?}");
            // A frame without misses is the unculled frame; one with them lacks what it missed.
            let same = image.as_raw() == expected.as_raw();
            assert_eq!(same, missed.is_empty(), "{what}, frame {f}: missed {missed:?}, same image: {same}");
            if what == "still" && f > 0 {
                assert!(missed.is_empty(), "still camera, frame {f}: missed {missed:?}");
                assert!(stats.occlusion_culled >= 6, "still camera, frame {f}: {stats:?}");
            }
            total_missed += missed.len();
            missed_per_frame.push(missed);
            last_visible = visible;
        }
        gpu.assert_clean();
        println!("one_phase, {what}: missed per frame {missed_per_frame:?}, {:.2} s", start.elapsed().as_secs_f64());
    }
    assert!(total_missed > 0, "the fast orbit must make one_phase miss something");
}

/// `spec` (a two-phase graph) with culling off: its late cull pass reads no Hi-Z and skips the
/// frustum (`frustum: false`, the instance-cull kind's no-cull baseline), so the early and late
/// lists together hold every instance every frame, and the Hi-Z pass is pruned. Everything else
/// (formats, samples, the passes after culling) is the graph's own. The library has no switch
/// for this: `--no-cull` selects `graph/no_cull.ron` instead, which has no MSAA.
fn without_culling(spec: &GraphSpec) -> GraphSpec {
    let name = std::path::Path::new(&spec.file).file_stem().unwrap().to_str().unwrap();
    let text = format!(
        r#"Graph(
    name: "{name} (culling off)",
    extends: "{name}",
    edits: [Set(pass: "cull_late", unbind: ["hiz"], settings: {{"frustum": false}})],
)"#
    );
    GraphSpec { text, file: format!("{} (culling off)", spec.file), ..spec.clone() }
}

#[test]
fn msaa_graphs_cull_over_the_msaa_depth_without_losing_a_sample() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = wall_scene();
    let instances = scene.instances.len() as u32;
    for name in ["msaa_compressed", "msaa_compressed_claim", "msaa_zprepass"] {
        for path in [CameraPath::Orbit, CameraPath::Shake] {
            let start = Instant::now();
            let spec = graph(name, &[("msaa", "4")]);
            let reference = without_culling(&spec);
            let camera = wall_camera();
            let shot = Shot { scene: &scene, camera: &camera, size: (40, 30), frames: 5, path };
            let (unculled, stats) = check_graphs(&gpu, shaders, shot, &reference, std::slice::from_ref(&spec));
            // The reference really culls nothing (its cull pass's counters), and the graph culls
            // by occlusion.
            for (f, s) in unculled.iter().enumerate() {
                assert_eq!((s.drawn, s.frustum_culled, s.occlusion_culled), (instances, 0, 0), "{name}, frame {f}");
            }
            let occluded: Vec<u32> = stats[0].iter().map(|s| s.occlusion_culled).collect();
            assert!(occluded.iter().sum::<u32>() >= 6, "{name} along {path:?}: occlusion-culled {occluded:?}");
            assert!(stats[0].iter().all(|s| s.frustum_culled >= 1), "{name} along {path:?}: the box behind the eye");
            println!("{name} x4 along {path:?}: occlusion-culled {occluded:?}, {:.2} s", start.elapsed().as_secs_f64());
        }
    }
}

#[test]
fn near_plane_inside_bound_and_behind_the_eye() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    let _kept = keep_pipelines(&gpu, &scene);
    // Eye inside the wall's bound, facing along it; the near plane cuts the wall.
    let inside = Camera {
        eye: DVec3::new(0.0, 3.0, -4.0),
        target: DVec3::new(3.0, 3.0, -4.0),
        near: 0.05,
        ..Default::default()
    };
    check(&gpu, &scene, &inside, (40, 30), 2, CameraPath::Still);
    // The wall straddles the near plane: its face is closer than `near` in the middle.
    let straddle = Camera {
        eye: DVec3::new(0.0, 3.0, -3.3),
        target: DVec3::new(0.0, 3.0, -10.0),
        near: 0.5,
        ..Default::default()
    };
    check(&gpu, &scene, &straddle, (40, 30), 2, CameraPath::Still);
    // Looking away: everything is behind the eye.
    let away = Camera { eye: DVec3::new(0.0, 1.5, 4.0), target: DVec3::new(0.0, 1.5, 20.0), ..Default::default() };
    check(&gpu, &scene, &away, (40, 30), 2, CameraPath::Still);
}

#[test]
fn ten_million_units_from_the_origin() {
    let gpu = GpuTest::new();
    let mut scene = wall_scene();
    let offset = DVec3::new(1.0e7, 0.0, -1.0e7);
    scene.translate(offset);
    let mut camera = wall_camera();
    camera.eye += offset;
    camera.target += offset;
    let stats = check(&gpu, &scene, &camera, (64, 48), 2, CameraPath::Still);
    assert!(stats[1].occlusion_culled >= 6, "{:?}", stats[1]);
}

#[test]
fn sub_pixel_and_screen_filling_objects() {
    let gpu = GpuTest::new();
    let mut scene = wall_scene();
    let cube = 0;
    // Tiny boxes far away (well under a pixel) and one huge box around everything.
    for i in 0..20 {
        scene.instances.push(Instance {
            transform: Transform {
                linear: Mat3::from_diagonal(Vec3::splat(0.01)),
                translation: DVec3::new(i as f64 - 10.0, 0.3, -60.0),
            },
            mesh: cube,
            material: 0,
            flags: 0,
        });
    }
    let _kept = keep_pipelines(&gpu, &scene);
    check(&gpu, &scene, &wall_camera(), (48, 36), 2, CameraPath::Still);
    let mut inside_huge = scene.clone();
    inside_huge.instances.push(Instance {
        transform: Transform { linear: Mat3::from_diagonal(Vec3::splat(500.0)), translation: DVec3::ZERO },
        mesh: cube,
        material: 0,
        flags: 0,
    });
    check(&gpu, &inside_huge, &wall_camera(), (48, 36), 2, CameraPath::Still);
    // A ground wider than a cull record's half floats hold (as the city's is from about 5 x 10^7
    // instances): its slot is kept untested, and so is its block of slots.
    let mut huge_ground = scene.clone();
    huge_ground.instances.push(Instance {
        transform: Transform {
            linear: Mat3::from_diagonal(Vec3::new(2.0e5, 0.1, 2.0e5)),
            translation: DVec3::new(0.0, -0.06, 0.0),
        },
        mesh: cube,
        material: 0,
        flags: 0,
    });
    let stats = check(&gpu, &huge_ground, &wall_camera(), (48, 36), 2, CameraPath::Still);
    let instances = huge_ground.instances.len() as u32;
    assert!(stats.iter().all(|s| s.drawn >= 1 && s.drawn < instances), "{stats:?}");
}

#[test]
fn zero_and_negative_scale() {
    let gpu = GpuTest::new();
    let mut scene = wall_scene();
    for (i, scale) in [Vec3::ZERO, Vec3::new(-1.0, 1.0, 1.0), Vec3::new(1.0, -2.0, -1.0), Vec3::new(0.0, 1.0, 1.0)]
        .into_iter()
        .enumerate()
    {
        scene.instances.push(Instance {
            transform: Transform {
                linear: Mat3::from_diagonal(scale),
                translation: DVec3::new(-6.0 + 2.0 * i as f64, 1.0, -2.0),
            },
            mesh: 0,
            material: 1,
            flags: 0,
        });
    }
    check(&gpu, &scene, &wall_camera(), (48, 36), 2, CameraPath::Still);
}

/// Five quads in a row in front of the eye (at the origin, looking down -z): one-sided facing
/// the eye, one-sided turned away, one-sided mirrored in x (glTF keeps its front toward the eye),
/// one-sided mirrored through its own plane (front away), double-sided turned away. With
/// `away_double_sided` the two whose front is away are double-sided too; `shown_only` leaves
/// out what a one-sided rendering must not show.
fn quads_scene(away_double_sided: bool, shown_only: bool) -> Scene {
    let mut scene = Scene { name: "quads".into(), ..Default::default() };
    let mesh = scene.add_mesh("quad", &quad_mesh(), "quad").unwrap();
    let one = scene.add_material(Material { name: "one-sided".into(), ..Default::default() });
    let two = scene.add_material(Material { name: "double-sided".into(), double_sided: true, ..Default::default() });
    let turned = Mat3::from_rotation_y(std::f32::consts::PI);
    let away = if away_double_sided { two } else { one };
    let placements = [
        (Mat3::IDENTITY, one, true),
        (turned, away, away_double_sided),
        (Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0)), one, true),
        (Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0)), away, away_double_sided),
        (turned, two, true),
    ];
    for (i, (linear, material, shown)) in placements.into_iter().enumerate() {
        if shown || !shown_only {
            let translation = DVec3::new(-4.0 + 2.0 * i as f64, 0.0, -8.0);
            scene.instances.push(Instance { transform: Transform { linear, translation }, mesh, material, flags: 0 });
        }
    }
    scene
}

#[test]
fn back_faces_of_one_sided_materials_are_not_drawn() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (w, h) = (64, 48);
    let camera = Camera { eye: DVec3::ZERO, target: DVec3::NEG_Z, ..Default::default() };
    let render = |scene: &Scene| {
        let spec = GraphSpec::builtin("no_cull").unwrap();
        let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
        r.enable_verification(shaders).unwrap();
        let (_, image) = r.render_to_image(&camera).unwrap();
        (image, r.exactly_visible().clone())
    };
    let scene = quads_scene(false, false);
    let (image, visible) = render(&scene);
    // The faces the rasterizer drops leave no pixel: the frame equals one without those quads.
    assert!(image.as_raw() == render(&quads_scene(false, true)).0.as_raw(), "a culled face left pixels");
    assert!(image.as_raw() != render(&quads_scene(true, false)).0.as_raw(), "double-sided quads must show");
    // The instance-id render and the ray cast agree on what is seen.
    assert_eq!(visible, BTreeSet::from([0, 2, 4]));
    let rays = RaycastOracle::new(&scene, camera.eye).cast(&camera, w, h, SamplePattern::Center).unwrap();
    assert_eq!(rays.visible, visible);
    // Culling changes nothing, along the row from in front of the quads and, as the camera
    // orbits past their plane, from behind.
    let side = Camera { eye: DVec3::new(8.0, 1.0, -7.5), target: DVec3::new(0.0, 0.0, -8.0), ..Default::default() };
    check(&gpu, &scene, &side, (w, h), 4, CameraPath::Orbit);
}

#[test]
fn nan_transforms_are_refused_at_upload() {
    let gpu = GpuTest::new();
    let mut scene = wall_scene();
    scene.instances[3].transform.translation.y = f64::NAN;
    let err = Renderer::new(&gpu, gpu.shaders(), scene, RenderSettings::new(8, 8))
        .err()
        .expect("NaN must be refused")
        .to_string();
    assert!(err.contains("instance #3") && err.contains("not finite"), "{err}");
}

#[test]
fn tiny_odd_and_large_outputs() {
    let gpu = GpuTest::new();
    let _kept = keep_pipelines(&gpu, &wall_scene());
    for size in [(1, 1), (3, 3), (7, 2)] {
        check(&gpu, &wall_scene(), &wall_camera(), size, 2, CameraPath::Still);
    }
    // 1023x767: NPOT on both axes at a realistic size; the second frame uses the first's history.
    check(&gpu, &wall_scene(), &wall_camera(), (1023, 767), 2, CameraPath::Shake);
}

#[test]
fn extreme_fields_of_view_and_orthographic() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    let _kept = keep_pipelines(&gpu, &scene);
    // Down to the extremes a user can type: no visible instance is lost, the image is the unculled one.
    for fov in [1.0f32, 170.0, 1e-30, 1e-6, 179.999] {
        let camera = Camera { projection: Projection::Perspective { fov_y_deg: fov }, ..wall_camera() };
        check(&gpu, &scene, &camera, (48, 36), 2, CameraPath::Still);
    }
    // Orthographic: the same guarantees. (At this framing the coarse footprint of every hidden
    // box reaches past the wall's edge, so nothing is provably occluded: conservative, not lost.)
    let ortho = Camera { projection: Projection::Orthographic { height: 12.0, far: 100.0 }, ..wall_camera() };
    check(&gpu, &scene, &ortho, (48, 36), 2, CameraPath::Still);
    let close = Camera {
        projection: Projection::Orthographic { height: 7.0, far: 100.0 },
        eye: DVec3::new(0.0, 3.0, 4.0),
        target: DVec3::new(0.0, 3.0, -10.0),
        ..wall_camera()
    };
    let stats = check(&gpu, &scene, &close, (96, 72), 3, CameraPath::Still);
    assert!(stats[1].occlusion_culled >= 2, "orthographic occlusion: {:?}", stats[1]);
}

#[test]
fn a_thousand_mesh_kinds_under_motion() {
    let gpu = GpuTest::new();
    let scene = SceneSource::Builtin("field".into())
        .load(&LoadOptions { instances: Some(3000), kinds: Some(1000), ..Default::default() })
        .unwrap();
    assert_eq!(scene.meshes.len(), 1000);
    let camera = scene.default_camera(64.0 / 48.0);
    let stats = check(&gpu, &scene, &camera, (64, 48), 4, CameraPath::Orbit);
    assert!(stats[0].draws > 100, "heterogeneous draws: {:?}", stats[0]);
}

#[test]
fn the_city_under_every_camera_path() {
    let gpu = GpuTest::new();
    let scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(3000), ..Default::default() }).unwrap();
    let camera = scene.default_camera(64.0 / 40.0);
    let _kept = keep_pipelines(&gpu, &scene);
    for path in [CameraPath::Orbit, CameraPath::Dolly, CameraPath::Shake] {
        let stats = check(&gpu, &scene, &camera, (64, 40), 4, path);
        assert!(stats[1].occlusion_culled > 500, "{path:?}: street view hides most of the city: {:?}", stats[1]);
    }
}

/// A scene that flags no occluders (as glTF files do) still gets them in the occluder pre-pass:
/// cheap meshes (at most `occluder_triangles` triangles) near and large on screen. With the
/// setting at 0 (flagged ones only) the pre-pass has nothing to draw and occludes nothing.
#[test]
fn the_occluder_prepass_chooses_cheap_meshes_where_the_scene_flags_none() {
    let gpu = GpuTest::new();
    let mut scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(3000), ..Default::default() }).unwrap();
    for instance in &mut scene.instances {
        instance.flags = 0;
    }
    let camera = scene.default_camera(64.0 / 40.0);
    let graphs = [graph("occluder_prepass", &[]), graph("occluder_prepass", &[("occluder_triangles", "0")])];
    let shot = Shot { scene: &scene, camera: &camera, size: (64, 40), frames: 3, path: CameraPath::Orbit };
    let (_, stats) = check_graphs(&gpu, gpu.shaders(), shot, &graph("no_cull", &[]), &graphs);
    let occluders = |s: &FrameStats| CullPassStats::of(s).iter().find(|p| p.pass == "cull_occluders").unwrap().drawn;
    for (cheap, flagged_only) in stats[0].iter().zip(&stats[1]) {
        assert!(occluders(cheap) > 0 && cheap.occlusion_culled > 300, "cheap meshes: {cheap:?}");
        assert!(occluders(flagged_only) == 0 && flagged_only.occlusion_culled == 0, "flagged only: {flagged_only:?}");
    }
}

/// A quad (-0.8..0.8 in x and y), front face toward +z.
fn quad_mesh() -> MeshData {
    MeshData {
        positions: vec![
            Vec3::new(-0.8, -0.8, 0.0),
            Vec3::new(0.8, -0.8, 0.0),
            Vec3::new(0.8, 0.8, 0.0),
            Vec3::new(-0.8, 0.8, 0.0),
        ],
        normals: vec![],
        indices: vec![0, 1, 2, 0, 2, 3],
        ..Default::default()
    }
}

/// A tetrahedron inside the unit cube, its faces counter-clockwise seen from outside.
fn tetrahedron_mesh() -> MeshData {
    let positions = vec![
        Vec3::new(0.5, 0.5, 0.5),
        Vec3::new(0.5, -0.5, -0.5),
        Vec3::new(-0.5, 0.5, -0.5),
        Vec3::new(-0.5, -0.5, 0.5),
    ];
    let mut indices = Vec::new();
    for [a, b, c] in [[0u32, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
        let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
        // The centroid is the origin: a face's outward normal points away from it.
        let outward = (pb - pa).cross(pc - pa).dot(pa + pb + pc) > 0.0;
        indices.extend(if outward { [a, b, c] } else { [a, c, b] });
    }
    MeshData { positions, normals: vec![], indices, ..Default::default() }
}

/// The culling of a random case: bound, Hi-Z footprint, pyramid method, and the exact graph
/// checked besides two_phase.
type TestParams = (&'static str, &'static str, &'static str, &'static str);

/// A random case: scene, camera, output size, camera path and the culling graphs' params.
type Case = (Scene, Camera, (u32, u32), CameraPath, TestParams);

/// A random scene of cubes (some flagged as occluders), one-sided and double-sided quads and
/// tetrahedra, some mirrored, maybe a wall across the view, and a random perspective or
/// orthographic camera, size, path and culling.
fn random_case() -> impl Strategy<Value = Case> {
    let boxes = prop::collection::vec(
        (
            (-20.0f64..20.0, 0.0f64..6.0, -20.0f64..20.0),
            (0.05f32..6.0, 0.05f32..6.0, 0.05f32..6.0),
            -3.2f32..3.2,
            0u32..2,
            // mesh (cube twice as often), double-sided, mirrored
            prop_oneof![Just(0u32), Just(0), Just(1), Just(2)],
            any::<bool>(),
            prop::bool::weighted(0.2),
        ),
        2..40,
    );
    let projection = prop_oneof![
        3 => (10.0f32..150.0).prop_map(|fov_y_deg| Projection::Perspective { fov_y_deg }),
        1 => (1.0f32..40.0, 20.0f32..150.0).prop_map(|(height, far)| Projection::Orthographic { height, far }),
    ];
    let camera = (
        (-25.0f64..25.0, 0.2f64..15.0, -25.0f64..25.0),
        (-10.0f64..10.0, 0.0f64..5.0, -10.0f64..10.0),
        projection,
        0.01f32..1.0,
    );
    let size = prop_oneof![Just((1u32, 1u32)), Just((3, 3)), (2u32..70, 2u32..50)];
    let path =
        prop_oneof![Just(CameraPath::Still), Just(CameraPath::Orbit), Just(CameraPath::Dolly), Just(CameraPath::Shake)];
    // Half the cases get a wall across the view (at a share of the way to the target, width,
    // height), so that the occlusion test has work.
    let wall = prop::option::weighted(0.5, (0.1f64..0.9, 1.0f32..20.0, 1.0f32..12.0));
    let params = (
        prop_oneof![Just("box"), Just("sphere")],
        prop_oneof![Just("coarse"), Just("finer")],
        prop_oneof![Just("single"), Just("per_mip")],
        prop_oneof![Just("frustum"), Just("occluder_prepass")],
    );
    (boxes, wall, camera, size, path, params).prop_filter_map(
        "eye equals target",
        |(boxes, wall, (eye, target, projection, near), size, path, params)| {
            let mut scene = Scene { name: "random".into(), ..Default::default() };
            let meshes = [
                scene.add_mesh("cube", &cube_mesh(), "cube").unwrap(),
                scene.add_mesh("quad", &quad_mesh(), "quad").unwrap(),
                scene.add_mesh("tetrahedron", &tetrahedron_mesh(), "tetrahedron").unwrap(),
            ];
            let one_sided = scene.add_material(Material::default());
            let double_sided =
                scene.add_material(Material { name: "double-sided".into(), double_sided: true, ..Default::default() });
            for ((x, y, z), (sx, sy, sz), angle, occluder, mesh, two_sided, mirrored) in boxes {
                let sx = if mirrored { -sx } else { sx };
                let linear = Mat3::from_rotation_y(angle) * Mat3::from_diagonal(Vec3::new(sx, sy, sz));
                scene.instances.push(Instance {
                    transform: Transform { linear, translation: DVec3::new(x, y, z) },
                    mesh: meshes[mesh as usize],
                    material: if two_sided { double_sided } else { one_sided },
                    flags: occluder,
                });
            }
            let camera = Camera {
                eye: DVec3::new(eye.0, eye.1, eye.2),
                target: DVec3::new(target.0, target.1, target.2),
                projection,
                near,
                ..Default::default()
            };
            camera.validate().ok()?;
            if let Some((at, width, height)) = wall {
                let towards_eye = camera.eye - camera.target;
                let turn = towards_eye.x.atan2(towards_eye.z) as f32;
                scene.instances.push(Instance {
                    transform: Transform {
                        linear: Mat3::from_rotation_y(turn) * Mat3::from_diagonal(Vec3::new(width, height, 0.3)),
                        translation: camera.eye.lerp(camera.target, at),
                    },
                    mesh: meshes[0],
                    material: one_sided,
                    flags: 1,
                });
            }
            Some((scene, camera, size, path, params))
        },
    )
}

/// Random cases (48 in the suite, `PROPTEST_CASES` for more): each renders 2 frames of no
/// culling, of two_phase and of frustum or occluder_prepass (occlusion-test params random too),
/// and checks every culled frame: no false negatives, the unculled image.
#[test]
fn random_scenes_and_cameras_never_lose_a_visible_instance() {
    // One context and one shader cache for all the cases: creating pipelines, not rendering,
    // is what a case costs. A case fails on its own validation messages.
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let start = Instant::now();
    // Every graph a case may take, kept for the test's duration: the cases' renderers share
    // their pipelines.
    let mut specs = vec![graph("no_cull", &[])];
    for bound in ["box", "sphere"] {
        specs.push(graph("frustum", &[("bound", bound)]));
        for hiz_test in ["coarse", "finer"] {
            for hiz_method in ["single", "per_mip"] {
                let occlusion = [("bound", bound), ("hiz_test", hiz_test), ("hiz_method", hiz_method)];
                specs.extend(["two_phase", "occluder_prepass"].map(|g| graph(g, &occlusion)));
            }
        }
    }
    let settings = RenderSettings::new(8, 8);
    let mut kept: Vec<Renderer> = specs
        .iter()
        .map(|spec| Renderer::with_graph(&gpu, shaders, wall_scene(), settings.clone(), spec).unwrap())
        .collect();
    kept[1].enable_verification(shaders).unwrap();
    let (cases, prepass_cases, occluding_cases) = (Cell::new(0), Cell::new(0), Cell::new(0));
    let count = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(48);
    let config = ProptestConfig { cases: count, failure_persistence: None, ..ProptestConfig::default() };
    proptest!(config, |(case in random_case())| {
        let (scene, camera, size, path, (bound, hiz_test, hiz_method, other)) = case;
        let before = gpu.validation_log().count();
        let occlusion = [("bound", bound), ("hiz_test", hiz_test), ("hiz_method", hiz_method)];
        let other = graph(other, if other == "frustum" { &occlusion[..1] } else { &occlusion });
        let graphs = [graph("two_phase", &occlusion), other];
        let shot = Shot { scene: &scene, camera: &camera, size, frames: 2, path };
        let (_, stats) = check_graphs(&gpu, shaders, shot, &graph("no_cull", &[]), &graphs);
        let messages = gpu.validation_log().messages();
        prop_assert!(messages.len() == before, "validation messages:\n{}", messages[before..].join("\n"));
        cases.set(cases.get() + 1);
        prepass_cases.set(prepass_cases.get() + (graphs[1].file.contains("occluder_prepass") as u32));
        occluding_cases.set(occluding_cases.get() + stats[0].iter().any(|s| s.occlusion_culled > 0) as u32);
    });
    println!(
        "{} random cases ({} with occluder_prepass, the others frustum; two_phase culled by occlusion in {}) in {:.1} s",
        cases.get(),
        prepass_cases.get(),
        occluding_cases.get(),
        start.elapsed().as_secs_f64()
    );
}
