//! An engine's own Rust pass kind, registered and used from RON like a built-in one: the
//! `instance_bounds` graphics pass of `examples/custom_pass.rs` draws each instance's box as
//! lines over the lit image, green where this frame's late cull found it visible and red where
//! it culled it. The scene is a wall with one box hidden behind it and one box beside it.

mod common;
#[path = "../examples/custom_pass.rs"]
mod custom_pass;

use common::{cube_mesh, GpuTest};
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::{Camera, Instance, Material, Scene, Transform};
use glam::{DVec3, Mat3, Vec3, Vec4};

const SIZE: (u32, u32) = (160, 96);
const GREEN: [u8; 4] = [0, 255, 0, 255];
const RED: [u8; 4] = [255, 0, 0, 255];

/// Wall (slot order follows the mesh, so each instance is its own box), the hidden box behind
/// it, and a visible box beside it.
fn scene() -> (Scene, [(DVec3, Vec3); 2]) {
    let mut scene = Scene { name: "bounds test".into(), ..Default::default() };
    let cube = scene.add_mesh("cube", &cube_mesh(), "cube").unwrap();
    let grey = scene.add_material(Material {
        name: "grey".into(),
        albedo: Vec3::splat(0.5),
        roughness: 0.9,
        metallic: 0.0,
        double_sided: false,
        ..Default::default()
    });
    let mut place = |scale: Vec3, at: DVec3| {
        scene.instances.push(Instance {
            transform: Transform { linear: Mat3::from_diagonal(scale), translation: at },
            mesh: cube,
            material: grey,
            flags: 0,
        })
    };
    let hidden = (DVec3::new(0.0, 2.0, -4.0), Vec3::ONE);
    let beside = (DVec3::new(5.0, 1.0, 2.0), Vec3::ONE);
    place(Vec3::new(8.0, 6.0, 0.4), DVec3::new(0.0, 2.0, 0.0));
    place(hidden.1, hidden.0);
    place(beside.1, beside.0);
    (scene, [hidden, beside])
}

fn camera() -> Camera {
    Camera { eye: DVec3::new(0.0, 2.0, 10.0), target: DVec3::new(0.0, 2.0, 0.0), ..Default::default() }
}

/// The pixel where the world point `p` lands.
fn pixel_of(camera: &Camera, p: DVec3) -> (i64, i64) {
    let clip = camera.view_projection_rel_eye(SIZE.0 as f32 / SIZE.1 as f32) * (p - camera.eye).as_vec3().extend(1.0);
    let ndc = Vec4::new(clip.x / clip.w, clip.y / clip.w, 0.0, 0.0);
    (((ndc.x + 1.0) * 0.5 * SIZE.0 as f32) as i64, ((ndc.y + 1.0) * 0.5 * SIZE.1 as f32) as i64)
}

/// The screen rectangle of a box's corners, grown by a pixel.
fn rect_of(camera: &Camera, (center, half): (DVec3, Vec3)) -> (i64, i64, i64, i64) {
    let mut r = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
    for i in 0..8 {
        let side =
            DVec3::new((i & 1) as f64 * 2.0 - 1.0, (i >> 1 & 1) as f64 * 2.0 - 1.0, (i >> 2 & 1) as f64 * 2.0 - 1.0);
        let (x, y) = pixel_of(camera, center + side * half.as_dvec3() * 0.5);
        r = (r.0.min(x - 1), r.1.min(y - 1), r.2.max(x + 1), r.3.max(y + 1));
    }
    r
}

/// The second frame (the first has no visibility history) through `spec`.
fn render(gpu: &GpuTest, spec: &GraphSpec) -> RgbaImage {
    let (scene, _) = scene();
    let mut renderer =
        Renderer::with_graph(gpu, gpu.shaders(), scene, RenderSettings::new(SIZE.0, SIZE.1), spec).unwrap();
    renderer.render(&camera()).unwrap();
    renderer.render_to_image(&camera()).unwrap().1
}

fn bounds_spec(show: &str) -> GraphSpec {
    let mut kinds = cullgraph::passes::builtin_kinds();
    kinds.register(custom_pass::InstanceBoundsKind).unwrap();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples/instance_bounds.ron");
    GraphSpec::from_file(path.as_ref()).unwrap().with_kinds(kinds).with_overrides([("show".into(), show.into())])
}

/// Pixels (x, y, rgba) where `a` and `b` differ.
fn changed(a: &RgbaImage, b: &RgbaImage) -> Vec<(i64, i64, [u8; 4])> {
    a.enumerate_pixels()
        .zip(b.pixels())
        .filter(|((_, _, pa), pb)| pa.0 != pb.0)
        .map(|((x, y, pa), _)| (x as i64, y as i64, pa.0))
        .collect()
}

#[test]
fn an_engine_pass_draws_visible_boxes_green_and_culled_boxes_red() {
    let gpu = GpuTest::new();
    let plain = render(&gpu, &GraphSpec::builtin("two_phase").unwrap());
    let all = render(&gpu, &bounds_spec("all"));
    let (_, [hidden, beside]) = scene();
    let (hidden_rect, beside_rect) = (rect_of(&camera(), hidden), rect_of(&camera(), beside));
    let inside = |(x0, y0, x1, y1): (i64, i64, i64, i64), x: i64, y: i64| x >= x0 && x <= x1 && y >= y0 && y <= y1;

    // The pass changes only the pixels its lines cover, to exactly their colors.
    let lines = changed(&all, &plain);
    assert!(
        lines.iter().all(|(_, _, c)| *c == GREEN || *c == RED),
        "only line colors: {:?}",
        &lines[..8.min(lines.len())]
    );
    // The box hidden behind the wall was culled: red lines, and only within its projection.
    let red: Vec<_> = lines.iter().filter(|(_, _, c)| *c == RED).collect();
    assert!(red.len() >= 20, "the hidden box's edges are drawn: {} red pixels", red.len());
    assert!(red.iter().all(|(x, y, _)| inside(hidden_rect, *x, *y)), "red pixels outside {hidden_rect:?}");
    // The box beside the wall is visible: green lines around it (the wall's are green too).
    let green_beside = lines.iter().filter(|(x, y, c)| *c == GREEN && inside(beside_rect, *x, *y)).count();
    assert!(green_beside >= 20, "the visible box's edges are drawn: {green_beside} green pixels");

    // `show` picks the culled or the visible boxes alone.
    let culled = changed(&render(&gpu, &bounds_spec("culled")), &plain);
    assert_eq!(culled.iter().filter(|(_, _, c)| *c == RED).count(), red.len());
    assert!(culled.iter().all(|(_, _, c)| *c == RED));
    let visible = changed(&render(&gpu, &bounds_spec("visible")), &plain);
    assert!(!visible.is_empty() && visible.iter().all(|(_, _, c)| *c == GREEN));
}

#[test]
fn a_graph_using_an_unregistered_kind_is_refused_at_its_position() {
    let gpu = GpuTest::new();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples/instance_bounds.ron");
    let spec = GraphSpec::from_file(path.as_ref()).unwrap();
    let (scene, _) = scene();
    let err = Renderer::with_graph(&gpu, gpu.shaders(), scene, RenderSettings::new(SIZE.0, SIZE.1), &spec)
        .err()
        .expect("instance_bounds is not a built-in kind")
        .to_string();
    assert!(err.contains("instance_bounds.ron:") && err.contains("unknown pass kind 'instance_bounds'"), "{err}");
}

#[test]
fn a_kind_name_is_registered_once() {
    let mut kinds = cullgraph::passes::builtin_kinds();
    kinds.register(custom_pass::InstanceBoundsKind).unwrap();
    let err = kinds.register(custom_pass::InstanceBoundsKind).unwrap_err().to_string();
    assert!(err.contains("'instance_bounds' is already registered"), "{err}");
}
