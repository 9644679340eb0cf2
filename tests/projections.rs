//! The culling hard cases under every projection an engine can hand a view: infinite and
//! finite-far perspective, orthographic, off-centre (a VR eye's), an engine's own matrices, each
//! with and without a per-frame sub-pixel jitter. Every culling graph must draw every instance
//! the exact-visibility oracle sees (rendered with the same, jittered, projection) and give the
//! image of no culling, pixel for pixel, with the validation layer clean.

mod common;

use common::{cube_mesh, GpuTest};
use cullgraph::oracle::Verify;
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::projection::halton_jitter;
use cullgraph::scene::{Camera, CameraPath, Instance, Material, Projection, Scene, Transform};
use cullgraph::stats::FrameStats;
use glam::{DMat4, DVec3, Mat3, Vec2, Vec3};

/// Graphs that must never miss a visible instance.
const EXACT_GRAPHS: [&str; 3] = ["frustum", "two_phase", "occluder_prepass"];

/// A projection under test, and whether each frame gets the next Halton jitter.
#[derive(Clone, Copy, Debug)]
struct Lens {
    name: &'static str,
    projection: Projection,
    jitter: bool,
}

/// Every projection type, and some with a jitter.
fn lenses() -> Vec<Lens> {
    let lens = |name, projection, jitter| Lens { name, projection, jitter };
    vec![
        lens("infinite", Projection::Perspective { fov_y_deg: 60.0 }, false),
        lens("far", Projection::PerspectiveFar { fov_y_deg: 60.0, far: 40.0 }, false),
        lens("ortho", Projection::Orthographic { height: 9.0, far: 60.0 }, false),
        lens(
            "offcenter",
            Projection::OffCenter {
                left_deg: -38.0,
                right_deg: 24.0,
                up_deg: 32.0,
                down_deg: -22.0,
                far: f32::INFINITY,
            },
            false,
        ),
        lens("infinite+jitter", Projection::Perspective { fov_y_deg: 60.0 }, true),
        lens("far+jitter", Projection::PerspectiveFar { fov_y_deg: 50.0, far: 25.0 }, true),
        lens("ortho+jitter", Projection::Orthographic { height: 9.0, far: 60.0 }, true),
        lens(
            "offcenter+far+jitter",
            Projection::OffCenter { left_deg: -20.0, right_deg: 35.0, up_deg: 25.0, down_deg: -30.0, far: 30.0 },
            true,
        ),
    ]
}

/// A wall in front of boxes, boxes beside it, one box behind the eye (as in tests/culling.rs).
fn wall_scene() -> Scene {
    let mut scene = Scene { name: "wall".into(), ..Default::default() };
    let cube = scene.add_mesh("cube", &cube_mesh(), "cube").unwrap();
    let grey = scene.add_material(Material::default());
    let red = scene.add_material(Material {
        name: "red".into(),
        albedo: Vec3::new(0.8, 0.1, 0.1),
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
        place(Vec3::ONE, DVec3::new(-2.5 + i as f64, 2.5, -8.0), red, 0); // hidden behind the wall
    }
    place(Vec3::ONE, DVec3::new(6.0, 0.5, -6.0), red, 0); // beside the wall
    place(Vec3::ONE, DVec3::new(0.0, 0.5, 8.0), red, 0); // behind the eye
    place(Vec3::ONE, DVec3::new(1.0, 1.0, -60.0), red, 0); // beyond every finite far plane
    scene
}

fn wall_camera() -> Camera {
    Camera { eye: DVec3::new(0.0, 3.0, 4.0), target: DVec3::new(0.0, 3.0, -10.0), ..Default::default() }
}

/// `base` along `path` for `frames` frames, jittered by the Halton sequence when the lens says
/// so, each labelled for messages.
fn shots(base: &Camera, lens: &Lens, path: CameraPath, frames: u32) -> Vec<(String, Camera)> {
    (0..frames)
        .map(|frame| {
            let mut camera = path.camera_at(base, frame);
            if lens.jitter {
                camera.jitter = halton_jitter(frame as u64);
            }
            (format!("{} frame {frame}", lens.name), camera)
        })
        .collect()
}

/// The shots of every lens from `base` (whose projection each lens replaces), one after another.
fn every_lens(base: &Camera, path: CameraPath, frames: u32) -> Vec<(String, Camera)> {
    lenses()
        .iter()
        .flat_map(|lens| shots(&Camera { projection: lens.projection, ..base.clone() }, lens, path, frames))
        .collect()
}

fn render(
    gpu: &GpuTest,
    scene: &Scene,
    cameras: &[(String, Camera)],
    size: (u32, u32),
    graph: &str,
    verify: bool,
) -> Vec<(RgbaImage, FrameStats)> {
    let shaders = gpu.shaders();
    let spec = GraphSpec::builtin(graph).unwrap();
    let mut r = Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(size.0, size.1), &spec).unwrap();
    if verify {
        r.enable_verification(shaders).unwrap();
    }
    cameras
        .iter()
        .map(|(_, c)| {
            let (stats, image) = r.render_to_image(c).unwrap();
            (image, stats)
        })
        .collect()
}

/// Renders the shots in order through no culling and through each exact graph (one renderer
/// each, so each shot's culling also tests against the history the previous shot left, whatever
/// its projection): no false negatives, identical images. Returns each graph's stats per shot.
fn check(gpu: &GpuTest, scene: &Scene, cameras: &[(String, Camera)], size: (u32, u32)) -> Vec<Vec<FrameStats>> {
    let reference = render(gpu, scene, cameras, size, "no_cull", false);
    let stats = EXACT_GRAPHS
        .iter()
        .map(|graph| {
            let frames = render(gpu, scene, cameras, size, graph, true);
            for (((image, s), (want, _)), (label, _)) in frames.iter().zip(&reference).zip(cameras) {
                let v = s.verify.as_ref().unwrap();
                assert_eq!(v.false_negatives, 0, "{label} {graph} at {size:?}: culled visible {:?}", v.missed);
                assert!(image.as_raw() == want.as_raw(), "{label} {graph} at {size:?}: the image differs from no_cull");
            }
            frames.into_iter().map(|(_, s)| s).collect()
        })
        .collect();
    gpu.assert_clean();
    stats
}

#[test]
fn hidden_boxes_are_culled_and_visible_ones_kept_under_every_projection() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    let frames = 3;
    let cameras = every_lens(&wall_camera(), CameraPath::Still, frames);
    let stats = check(&gpu, &scene, &cameras, (64, 48));
    for (i, lens) in lenses().iter().enumerate() {
        // two_phase, the lens's last frame.
        let two_phase = &stats[1][(i as u32 * frames + frames - 1) as usize];
        assert!(two_phase.frustum_culled >= 1, "{}: the box behind the eye: {two_phase:?}", lens.name);
        // Perspective views see the hidden boxes well inside the wall's silhouette.
        if !matches!(lens.projection, Projection::Orthographic { .. }) {
            assert!(two_phase.occlusion_culled >= 4, "{}: {two_phase:?}", lens.name);
        }
        // A finite far plane culls the box beyond it.
        let finite = match lens.projection {
            Projection::PerspectiveFar { .. } | Projection::Orthographic { .. } => true,
            Projection::OffCenter { far, .. } => far.is_finite(),
            _ => false,
        };
        if finite {
            assert!(two_phase.frustum_culled >= 2, "{}: beyond the far plane: {two_phase:?}", lens.name);
        }
    }
}

#[test]
fn near_plane_and_eye_inside_a_bound_under_every_projection() {
    let gpu = GpuTest::new();
    // Eye inside the wall's bound, facing along it; then the wall straddling the near plane.
    let inside =
        Camera { eye: DVec3::new(0.0, 3.0, -4.0), target: DVec3::new(3.0, 3.0, -4.0), near: 0.05, ..wall_camera() };
    let straddle = Camera { eye: DVec3::new(0.0, 3.0, -3.3), near: 0.5, ..wall_camera() };
    let mut cameras = every_lens(&inside, CameraPath::Still, 2);
    cameras.extend(every_lens(&straddle, CameraPath::Still, 2));
    check(&gpu, &wall_scene(), &cameras, (40, 30));
}

#[test]
fn ten_million_units_from_the_origin_under_every_projection() {
    let gpu = GpuTest::new();
    let offset = DVec3::new(1.0e7, 0.0, -1.0e7);
    let mut scene = wall_scene();
    scene.translate(offset);
    let mut camera = wall_camera();
    camera.eye += offset;
    camera.target += offset;
    check(&gpu, &scene, &every_lens(&camera, CameraPath::Shake, 2), (48, 36));
}

#[test]
fn sub_pixel_huge_zero_and_negative_scale_under_every_projection() {
    let gpu = GpuTest::new();
    let mut scene = wall_scene();
    let mut add = |linear: Mat3, at: DVec3| {
        scene.instances.push(Instance {
            transform: Transform { linear, translation: at },
            mesh: 0,
            material: 1,
            flags: 0,
        })
    };
    for i in 0..10 {
        add(Mat3::from_diagonal(Vec3::splat(0.01)), DVec3::new(i as f64 - 5.0, 0.3, -20.0));
    }
    for (i, s) in [Vec3::ZERO, Vec3::new(-1.0, 1.0, 1.0), Vec3::new(1.0, -2.0, -1.0), Vec3::new(0.0, 1.0, 1.0)]
        .into_iter()
        .enumerate()
    {
        add(Mat3::from_diagonal(s), DVec3::new(-6.0 + 2.0 * i as f64, 1.0, -2.0));
    }
    check(&gpu, &scene, &every_lens(&wall_camera(), CameraPath::Still, 2), (48, 36));
    scene.instances.push(Instance {
        transform: Transform { linear: Mat3::from_diagonal(Vec3::splat(500.0)), translation: DVec3::ZERO },
        mesh: 0,
        material: 0,
        flags: 0,
    });
    check(&gpu, &scene, &every_lens(&wall_camera(), CameraPath::Still, 1), (32, 24));
}

#[test]
fn one_pixel_and_odd_sizes_under_every_projection() {
    let gpu = GpuTest::new();
    for size in [(1, 1), (7, 3)] {
        check(&gpu, &wall_scene(), &every_lens(&wall_camera(), CameraPath::Orbit, 2), size);
    }
}

#[test]
fn extreme_off_centre_and_far_planes() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    let extreme = [
        // Nearly 180° wide and tall, and a sliver entirely off to one side of the view axis.
        Projection::OffCenter { left_deg: -89.5, right_deg: 89.0, up_deg: 89.5, down_deg: -89.0, far: f32::INFINITY },
        Projection::OffCenter { left_deg: 10.0, right_deg: 12.0, up_deg: -5.0, down_deg: -9.0, far: f32::INFINITY },
        Projection::OffCenter { left_deg: -0.5, right_deg: 0.5, up_deg: 0.4, down_deg: -0.4, far: 1e6 },
        // A far plane cutting through the hidden boxes, and one just past the near plane.
        Projection::PerspectiveFar { fov_y_deg: 60.0, far: 12.2 },
        Projection::PerspectiveFar { fov_y_deg: 170.0, far: 0.2 },
        Projection::OrthographicOffCenter { left: -1.0, right: 7.0, bottom: -2.0, top: 1.0, far: 13.0 },
    ];
    let cameras: Vec<(String, Camera)> = extreme
        .into_iter()
        .flat_map(|projection| {
            [false, true].map(|jitter| {
                let lens = Lens { name: "extreme", projection, jitter };
                shots(&Camera { projection, ..wall_camera() }, &lens, CameraPath::Still, 2)
            })
        })
        .flatten()
        .collect();
    check(&gpu, &scene, &cameras, (48, 36));
}

/// An engine's own matrices (a VR eye: off-centre, finite far) render the same image as the
/// projection they were made from, culled without losses.
#[test]
fn engine_matrices_render_as_the_projection_they_describe() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    let lens = Lens {
        name: "engine",
        projection: Projection::OffCenter {
            left_deg: -40.0,
            right_deg: 30.0,
            up_deg: 35.0,
            down_deg: -30.0,
            far: 50.0,
        },
        jitter: true,
    };
    let camera = Camera { projection: lens.projection, ..wall_camera() };
    let view = DMat4::from_mat3(camera.view_rotation().as_dmat3()) * DMat4::from_translation(-camera.eye);
    let engine = Camera::from_matrices(view, camera.projection_matrix(1.0)).unwrap();
    let cameras = shots(&engine, &lens, CameraPath::Orbit, 3);
    check(&gpu, &scene, &cameras, (64, 48));
    // Made from its matrices or from its angles, the same view renders the same image (up to
    // the last bits of the decomposition).
    let pair = [("angles".to_string(), camera), ("matrices".to_string(), engine)];
    let images = render(&gpu, &scene, &pair, (64, 48), "no_cull", false);
    let differing = images[0].0.as_raw().iter().zip(images[1].0.as_raw()).filter(|(a, b)| a != b).count();
    assert!(differing <= 8, "{differing} bytes differ between the projection and its matrix");
}

/// The jitter moves the image by the sub-pixel amount: a jittered frame differs from the
/// unjittered one, and last frame's jitter never leaks into this frame's culling.
#[test]
fn jitter_moves_the_image_and_culling_follows() {
    let gpu = GpuTest::new();
    let scene = wall_scene();
    let still = wall_camera();
    let moved = Camera { jitter: Vec2::new(0.5, 0.5), ..still.clone() };
    let images = render(&gpu, &scene, &[("still".into(), still), ("moved".into(), moved)], (64, 48), "no_cull", false);
    assert!(images[0].0.as_raw() != images[1].0.as_raw(), "a half-pixel jitter left the image unchanged");
    // Alternating jitters, the largest and none, frame after frame: last frame's jitter never
    // leaks into this frame's culling.
    let jitters = [Vec2::new(0.9, -0.9), Vec2::new(-0.9, 0.9), Vec2::ZERO, Vec2::new(1.0, 1.0), Vec2::new(-1.0, -1.0)];
    let cameras: Vec<(String, Camera)> =
        jitters.iter().map(|&jitter| (format!("jitter {jitter}"), Camera { jitter, ..wall_camera() })).collect();
    check(&gpu, &scene, &cameras, (40, 30));
}
