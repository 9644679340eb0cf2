//! GPU culling on lavapipe with validation on: every culling graph must draw every visible
//! instance (exact visibility from an unculled id render is the oracle) and give the same image,
//! pixel for pixel, as no culling. Named hard cases, then property tests over random scenes,
//! cameras and sizes.

mod common;

use common::{cube_mesh, GpuTest};
use cullgraph::oracle::raycast::{RaycastOracle, SamplePattern};
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, CameraPath, Instance, Material, MeshData, Projection, Scene, SceneSource, Transform};
use cullgraph::stats::FrameStats;
use glam::{DVec3, Mat3, Vec3};
use proptest::prelude::*;
use std::collections::BTreeSet;

/// Graphs that must never miss a visible instance.
const EXACT_GRAPHS: [&str; 3] = ["frustum", "two_phase", "occluder_prepass"];

/// Renders `frames` frames of each graph along `path` and checks them against no culling:
/// identical images and no false negatives. Returns the culled graphs' last-frame stats.
fn check(
    gpu: &GpuTest,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    frames: u32,
    path: CameraPath,
) -> Vec<FrameStats> {
    let shaders = gpu.shaders();
    let settings = RenderSettings::new(size.0, size.1);
    let render = |graph: &str| -> (Vec<RgbaImage>, Vec<FrameStats>) {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r = Renderer::with_graph(gpu, &shaders, scene.clone(), settings.clone(), &spec).unwrap();
        r.enable_verification(&shaders).unwrap();
        (0..frames)
            .map(|f| {
                let (stats, image) = r.render_to_image(&path.camera_at(camera, f)).unwrap();
                (image, stats)
            })
            .unzip()
    };
    let (reference, _) = render("no_cull");
    let mut last = Vec::new();
    for graph in EXACT_GRAPHS {
        let (images, stats) = render(graph);
        for (f, (image, s)) in images.iter().zip(&stats).enumerate() {
            let v = s.verify.as_ref().unwrap();
            assert_eq!(v.false_negatives, 0, "{graph}, frame {f}: visible instances culled: {:?} ({s:?})", v.missed);
            assert!(image.as_raw() == reference[f].as_raw(), "{graph}, frame {f}: the image differs from no culling");
        }
        last.push(stats.last().unwrap().clone());
    }
    last
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

#[test]
fn near_plane_inside_bound_and_behind_the_eye() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
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
    check(&gpu, &scene, &wall_camera(), (48, 36), 2, CameraPath::Still);
    let mut inside_huge = scene.clone();
    inside_huge.instances.push(Instance {
        transform: Transform { linear: Mat3::from_diagonal(Vec3::splat(500.0)), translation: DVec3::ZERO },
        mesh: cube,
        material: 0,
        flags: 0,
    });
    check(&gpu, &inside_huge, &wall_camera(), (48, 36), 2, CameraPath::Still);
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
    let quad = MeshData {
        positions: vec![
            Vec3::new(-0.8, -0.8, 0.0),
            Vec3::new(0.8, -0.8, 0.0),
            Vec3::new(0.8, 0.8, 0.0),
            Vec3::new(-0.8, 0.8, 0.0),
        ],
        normals: vec![],
        indices: vec![0, 1, 2, 0, 2, 3],
    };
    let mesh = scene.add_mesh("quad", &quad, "quad").unwrap();
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
        let mut r = Renderer::with_graph(&gpu, &shaders, scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
        r.enable_verification(&shaders).unwrap();
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
    let err = Renderer::new(&gpu, &gpu.shaders(), scene, RenderSettings::new(8, 8))
        .err()
        .expect("NaN must be refused")
        .to_string();
    assert!(err.contains("instance #3") && err.contains("not finite"), "{err}");
}

#[test]
fn tiny_odd_and_large_outputs() {
    let gpu = GpuTest::new();
    for size in [(1, 1), (3, 3), (7, 2)] {
        check(&gpu, &wall_scene(), &wall_camera(), size, 2, CameraPath::Still);
    }
    // 1023x767: NPOT on both axes at a realistic size (one still frame per graph).
    check(&gpu, &wall_scene(), &wall_camera(), (1023, 767), 1, CameraPath::Still);
}

#[test]
fn extreme_fields_of_view_and_orthographic() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    for fov in [1.0f32, 170.0] {
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
    for path in [CameraPath::Orbit, CameraPath::Dolly, CameraPath::Shake] {
        let stats = check(&gpu, &scene, &camera, (64, 40), 4, path);
        assert!(stats[1].occlusion_culled > 500, "{path:?}: street view hides most of the city: {:?}", stats[1]);
    }
}

/// A random scene of boxes and walls and a random camera, size and path.
fn random_case() -> impl Strategy<Value = (Scene, Camera, (u32, u32), CameraPath)> {
    let boxes = prop::collection::vec(
        (
            (-20.0f64..20.0, 0.0f64..6.0, -20.0f64..20.0),
            (0.05f32..6.0, 0.05f32..6.0, 0.05f32..6.0),
            -3.2f32..3.2,
            0u32..2,
        ),
        2..40,
    );
    let camera = (
        (-25.0f64..25.0, 0.2f64..15.0, -25.0f64..25.0),
        (-10.0f64..10.0, 0.0f64..5.0, -10.0f64..10.0),
        10.0f32..150.0,
        0.01f32..1.0,
    );
    let size = prop_oneof![Just((1u32, 1u32)), Just((3, 3)), (2u32..70, 2u32..50)];
    let path = prop_oneof![Just(CameraPath::Still), Just(CameraPath::Orbit), Just(CameraPath::Shake)];
    (boxes, camera, size, path).prop_filter_map("eye equals target", |(boxes, (eye, target, fov, near), size, path)| {
        let mut scene = Scene { name: "random".into(), ..Default::default() };
        let cube = scene.add_mesh("cube", &cube_mesh(), "cube").unwrap();
        scene.add_material(Material::default());
        for ((x, y, z), (sx, sy, sz), angle, occluder) in boxes {
            let linear = Mat3::from_rotation_y(angle) * Mat3::from_diagonal(Vec3::new(sx, sy, sz));
            scene.instances.push(Instance {
                transform: Transform { linear, translation: DVec3::new(x, y, z) },
                mesh: cube,
                material: 0,
                flags: occluder,
            });
        }
        let camera = Camera {
            eye: DVec3::new(eye.0, eye.1, eye.2),
            target: DVec3::new(target.0, target.1, target.2),
            projection: Projection::Perspective { fov_y_deg: fov },
            near,
            ..Default::default()
        };
        camera.validate().ok()?;
        Some((scene, camera, size, path))
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 40, failure_persistence: None, ..ProptestConfig::default() })]

    /// 40 random scenes x 3 culling graphs x 3 frames = 360 checked GPU frames (plus references).
    #[test]
    fn random_scenes_and_cameras_never_lose_a_visible_instance(case in random_case()) {
        let (scene, camera, size, path) = case;
        let gpu = GpuTest::new();
        check(&gpu, &scene, &camera, size, 3, path);
    }
}
