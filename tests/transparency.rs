//! Transparent (alphaMode BLEND) materials: drawn after the lighting, sorted back to front,
//! culled like everything else but never occluding (lavapipe, validation on).

mod common;

use common::GpuTest;
use cullgraph::oracle::Verify;
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::{AlphaMode, Instance, Material, Scene, Transform};
use cullgraph::stats::FrameStats;
use glam::{DVec3, Mat3, Vec3};

const SIZE: (u32, u32) = (96, 72);

/// Every built-in method that lights a frame.
const METHODS: [&str; 11] = [
    "default",
    "one_phase",
    "frustum",
    "occluder_prepass",
    "fxaa",
    "msaa_per_sample",
    "msaa_zprepass",
    "msaa_compressed",
    "msaa_compressed_claim",
    "msaa_compressed_edges",
    "visibility_buffer",
];

fn glass(name: &str, albedo: Vec3, alpha: f32) -> Material {
    Material { name: name.into(), albedo, alpha, alpha_mode: AlphaMode::Blend, ..Default::default() }
}

/// Renders two frames of `scene` through `graph` (the second has the first's culling history),
/// with exact visibility checked.
fn render(gpu: &GpuTest, scene: &Scene, graph: &str) -> (FrameStats, RgbaImage) {
    let shaders = gpu.shaders();
    let spec = GraphSpec::builtin(graph).unwrap();
    let mut r = Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.enable_verification(shaders).unwrap();
    r.render_to_image(&common::camera_on_z()).unwrap();
    r.render_to_image(&common::camera_on_z()).unwrap()
}

/// A red box behind a half-transparent blue pane that covers the left half of the view.
fn pane_over_box() -> Scene {
    let mut scene = common::sunlit_scene("transparency");
    let red =
        scene.add_material(Material { name: "red".into(), albedo: Vec3::new(0.9, 0.05, 0.05), ..Default::default() });
    let blue = scene.add_material(glass("blue glass", Vec3::new(0.05, 0.05, 0.9), 0.5));
    let cube = scene.add_mesh("cube", &common::cube_mesh(), "cube").unwrap();
    let pane = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, 0.0, -1.0), 2.5),
        mesh: cube,
        material: red,
        flags: 0,
    });
    scene.instances.push(Instance {
        transform: Transform {
            linear: Mat3::from_diagonal(Vec3::new(2.0, 4.0, 1.0)),
            translation: DVec3::new(-1.0, 0.0, 1.0),
        },
        mesh: pane,
        material: blue,
        flags: 0,
    });
    scene
}

/// In every method, the box shows through the pane mixed with its blue and plain red beside it;
/// the pane hides nothing from the culling (0 false negatives, the box stays visible), and the
/// culled image equals the unculled one.
#[test]
fn a_transparent_pane_blends_over_the_box_behind_it_in_every_method() {
    let gpu = GpuTest::new();
    let scene = pane_over_box();
    let (_, unculled) = render(&gpu, &scene, "no_cull");
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    let (through, beside) = (common::rgb(&unculled, cx - 8, cy), common::rgb(&unculled, cx + 8, cy));
    assert!(beside[0] > beside[2] + 100, "plain red beside the pane: {beside:?}");
    assert!(
        through[2] > beside[2] + 60 && through[0] > 60,
        "red and blue mix through the pane: {through:?} (beside: {beside:?})"
    );
    for graph in METHODS {
        let (stats, image) = render(&gpu, &scene, graph);
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "{graph}: missed {:?}", verify.missed);
        assert_eq!(verify.visible, 2, "{graph}: the box and the pane are both seen");
        let (t, b) = (common::rgb(&image, cx - 8, cy), common::rgb(&image, cx + 8, cy));
        for (got, want, what) in [(t, through, "through the pane"), (b, beside, "beside it")] {
            let off = (0..3).map(|c| got[c].abs_diff(want[c])).max().unwrap();
            assert!(off <= 4, "{graph}: {what} {got:?}, unculled {want:?}");
        }
        if !graph.starts_with("msaa") && graph != "fxaa" && graph != "visibility_buffer" {
            assert!(image == unculled, "{graph}: culling changed the image");
        }
    }
    gpu.assert_clean();
}

/// Two overlapping panes, red in front of green, are drawn back to front whatever their order
/// in the scene: the nearer pane's colour dominates where they overlap. Swapping their depths
/// swaps the result.
#[test]
fn transparent_panes_are_sorted_back_to_front() {
    let gpu = GpuTest::new();
    let pane_scene = |red_z: f64, green_z: f64| {
        let mut scene = common::sunlit_scene("transparency");
        let red = scene.add_material(glass("red glass", Vec3::new(0.9, 0.02, 0.02), 0.7));
        let green = scene.add_material(glass("green glass", Vec3::new(0.02, 0.9, 0.02), 0.7));
        let pane = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
        // The red pane first in the scene, whatever its depth.
        for (material, z) in [(red, red_z), (green, green_z)] {
            scene.instances.push(Instance {
                transform: common::scaled_at(DVec3::new(0.0, 0.0, z), 1.5),
                mesh: pane,
                material,
                flags: 0,
            });
        }
        scene
    };
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    for graph in ["default", "msaa_compressed"] {
        let (_, red_front) = render(&gpu, &pane_scene(0.5, -0.5), graph);
        let p = common::rgb(&red_front, cx, cy);
        assert!(p[0] > p[1] + 40, "{graph}: red in front dominates: {p:?}");
        let (_, green_front) = render(&gpu, &pane_scene(-0.5, 0.5), graph);
        let p = common::rgb(&green_front, cx, cy);
        assert!(p[1] > p[0] + 40, "{graph}: green in front dominates: {p:?}");
    }
    gpu.assert_clean();
}

/// A transparent pane behind an opaque wall is culled by the Hi-Z like any hidden instance (it
/// is not drawn), and a box behind a transparent pane is never culled (the pane writes no depth).
#[test]
fn transparent_instances_are_occlusion_culled_but_never_occlude() {
    let gpu = GpuTest::new();
    let mut scene = pane_over_box();
    let grey = scene.add_material(Material { name: "wall".into(), albedo: Vec3::splat(0.5), ..Default::default() });
    let blue = scene.instances[1].material;
    let pane = scene.instances[1].mesh;
    // A wall in the middle, in front of the box and partly of the pane, hiding a second, small
    // blue pane behind it.
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, 0.0, 1.5), 1.0),
        mesh: pane,
        material: grey,
        flags: 0,
    });
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, 0.0, 0.0), 0.2),
        mesh: pane,
        material: blue,
        flags: 0,
    });
    let (stats, _) = render(&gpu, &scene, "default");
    let verify = stats.verify.expect("verified");
    assert_eq!(verify.false_negatives, 0, "missed {:?}", verify.missed);
    assert_eq!(verify.visible, 3, "box, front pane and wall; the pane behind the wall is hidden");
    assert_eq!(verify.false_positives, 0, "the hidden pane is culled, not drawn");
    gpu.assert_clean();
}

/// A live world turns the pane over the box transparent at run time (a material registered
/// then given to the instance): the next frame blends it with the box behind, culling still
/// exact. A new emissive material given to it next makes it glow.
#[test]
fn a_live_world_makes_an_instance_transparent_and_emissive() {
    use cullgraph::scene::world::World;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = pane_over_box();
    let opaque_blue =
        scene.add_material(Material { name: "blue".into(), albedo: Vec3::new(0.05, 0.05, 0.9), ..Default::default() });
    scene.instances[1].material = opaque_blue;
    let (mut world, handles) = World::new(scene).unwrap();
    let spec = GraphSpec::builtin("default").unwrap();
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.enable_verification(shaders).unwrap();
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    let frame = |r: &mut Renderer| {
        r.render_to_image(&common::camera_on_z()).unwrap();
        let (stats, image) = r.render_to_image(&common::camera_on_z()).unwrap();
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "missed {:?}", verify.missed);
        (verify.visible, common::rgb(&image, cx - 8, cy))
    };
    // The pane covers the left half of the view; the box shows on the right whatever the pane is.
    let (visible, opaque) = frame(&mut r);
    assert_eq!(visible, 2);
    assert!(opaque[2] > opaque[0] + 100, "blue pane: {opaque:?}");

    let glass = world.add_material(glass("blue glass", Vec3::new(0.05, 0.05, 0.9), 0.5)).unwrap();
    world.set_materials(&[(handles[1], glass)]).unwrap();
    r.sync(shaders, &world).unwrap();
    let (visible, through) = frame(&mut r);
    assert_eq!(visible, 2);
    assert!(through[0] > opaque[0] + 40, "red comes through: {through:?} (opaque {opaque:?})");

    let lamp = Material {
        name: "lamp".into(),
        albedo: Vec3::splat(0.1),
        emissive: Vec3::new(1.0, 1.0, 0.0),
        ..Default::default()
    };
    let lamp = world.add_material(lamp).unwrap();
    world.set_materials(&[(handles[1], lamp)]).unwrap();
    r.sync(shaders, &world).unwrap();
    let (visible, glow) = frame(&mut r);
    assert_eq!(visible, 2);
    assert!(glow[0] > 200 && glow[1] > 200 && glow[2] < 120, "the lamp glows yellow: {glow:?}");
    gpu.assert_clean();
}
