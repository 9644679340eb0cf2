//! The sun's shadows: cascades fitted to the camera, each a depth-only view of the renderer's
//! world culled in the camera's dispatches. Casters the camera cannot see (behind it, beyond a
//! side plane, far along the sun) still shadow what it sees; the image with caster culling
//! equals the image without, for still, moving and alpha-masked casters and a moving sun; every
//! lighting method samples the same shadows, and transparent surfaces receive them.

mod common;

use common::GpuTest;
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer, ShadowSettings};
use cullgraph::scene::world::World;
use cullgraph::scene::*;
use glam::{DVec3, Mat3, Vec3};

const SIZE: (u32, u32) = (192, 120);

fn shadows(caster_culling: bool) -> ShadowSettings {
    ShadowSettings { resolution: 512, distance: Some(40.0), caster_culling, ..Default::default() }
}

/// A wide grey ground around the origin, lit by a sun travelling along `sun`.
fn stage(sun: Vec3) -> (Scene, u32) {
    let mut scene = Scene { name: "shadow stage".into(), ..Default::default() };
    scene.sun.direction = sun.normalize();
    let cube = scene.add_mesh("cube", &common::cube_mesh(), "cube").unwrap();
    let grey = scene.add_material(Material { name: "ground".into(), albedo: Vec3::splat(0.6), ..Default::default() });
    scene.instances.push(Instance {
        transform: Transform {
            linear: Mat3::from_diagonal(Vec3::new(200.0, 0.2, 200.0)),
            translation: DVec3::new(0.0, -0.1, 0.0),
        },
        mesh: cube,
        material: grey,
        flags: 0,
    });
    (scene, cube)
}

/// A box of side `side` centred at `at`.
fn add_box(scene: &mut Scene, cube: u32, at: DVec3, side: f32) {
    let red =
        scene.add_material(Material { name: "red".into(), albedo: Vec3::new(0.8, 0.1, 0.1), ..Default::default() });
    scene.instances.push(Instance {
        transform: Transform { linear: Mat3::from_diagonal(Vec3::splat(side)), translation: at },
        mesh: cube,
        material: red,
        flags: 0,
    });
}

fn camera() -> Camera {
    Camera { eye: DVec3::new(0.0, 3.0, 10.0), target: DVec3::ZERO, ..Default::default() }
}

/// The pixel where world point `p` appears to `camera`.
fn pixel_of(camera: &Camera, p: DVec3) -> (u32, u32) {
    let vp = camera.view_projection_rel_eye(SIZE.0 as f32 / SIZE.1 as f32);
    let clip = vp * (p - camera.eye).as_vec3().extend(1.0);
    let ndc = clip.truncate() / clip.w;
    assert!(ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0 && clip.w > 0.0, "{p} is not in view: {ndc}");
    (((ndc.x + 1.0) * 0.5 * SIZE.0 as f32) as u32, ((ndc.y + 1.0) * 0.5 * SIZE.1 as f32) as u32)
}

fn luma(image: &RgbaImage, (x, y): (u32, u32)) -> f32 {
    let [r, g, b] = common::rgb(image, x, y);
    0.2126 * r as f32 + 0.7152 * g as f32 + 0.0722 * b as f32
}

/// Renders two frames of `scene` through `graph` with `settings`' shadows and returns the last
/// image, with the instances the camera view culled by its frustum.
fn render(
    gpu: &GpuTest,
    scene: &Scene,
    camera: &Camera,
    graph: &str,
    settings: Option<ShadowSettings>,
) -> (RgbaImage, u32) {
    let shaders = gpu.shaders();
    let spec = GraphSpec::builtin(graph).unwrap();
    let mut renderer =
        Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    renderer.set_shadows(shaders, settings).unwrap();
    renderer.render_to_image(camera).unwrap();
    let (stats, image) = renderer.render_to_image(camera).unwrap();
    (image, stats.frustum_culled)
}

/// A caster outside the camera's frustum shadows `shadowed` (on the ground, in view): darker
/// with shadows than without, and the same image whether casters are culled or not.
fn assert_shadows_into_view(scene: &Scene, shadowed: DVec3) {
    let gpu = GpuTest::new();
    let camera = camera();
    let at = pixel_of(&camera, shadowed);
    let (lit, culled_without) = render(&gpu, scene, &camera, "default", None);
    let (culled, culled_with) = render(&gpu, scene, &camera, "default", Some(shadows(true)));
    let (unculled, _) = render(&gpu, scene, &camera, "no_cull", Some(shadows(false)));
    assert_eq!(culled_without, 1, "the caster is outside the camera's frustum");
    assert_eq!(culled_with, 1);
    assert!(luma(&culled, at) < 0.8 * luma(&lit, at), "{at:?}: {} shadowed, {} lit", luma(&culled, at), luma(&lit, at));
    assert!(culled.as_raw() == unculled.as_raw(), "caster culling changed the image");
    // Far from the shadow, the sun still reaches the ground.
    let open = pixel_of(&camera, shadowed + DVec3::new(if shadowed.x > 0.0 { -6.0 } else { 6.0 }, 0.0, 0.0));
    assert!((luma(&culled, open) - luma(&lit, open)).abs() < 2.0, "{open:?} is lit in both");
    gpu.assert_clean();
}

#[test]
fn a_caster_behind_the_camera_shadows_what_it_sees() {
    // Light travelling down and away from the camera: the box behind it throws its shadow
    // in front of it.
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, -1.5));
    add_box(&mut scene, cube, DVec3::new(0.0, 9.0, 16.0), 3.0);
    assert_shadows_into_view(&scene, DVec3::new(0.0, 0.0, 16.0 - 1.5 * 9.0));
}

#[test]
fn a_caster_beyond_a_side_plane_shadows_what_the_camera_sees() {
    let (mut scene, cube) = stage(Vec3::new(-2.0, -1.0, 0.0));
    add_box(&mut scene, cube, DVec3::new(17.0, 5.0, 0.0), 2.0);
    assert_shadows_into_view(&scene, DVec3::new(17.0 - 2.0 * 5.0, 0.0, 0.0));
}

#[test]
fn a_caster_far_along_the_sun_shadows_what_the_camera_sees() {
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, 0.0));
    add_box(&mut scene, cube, DVec3::new(0.0, 80.0, 0.0), 4.0);
    assert_shadows_into_view(&scene, DVec3::ZERO);
}

/// A horizontal fence of bars (alpha-masked) above the ground, lit from above and in front.
fn fence_stage() -> Scene {
    let (mut scene, _) = stage(Vec3::new(0.0, -1.0, 1.0));
    let fence = common::bars_material(&mut scene, 8, true);
    let quad = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    // The quad faces +z; turned to face up, 4 units wide, 2 above the ground and 4 behind the
    // origin: its shadow falls 2 units towards the camera.
    let linear = Mat3::from_rotation_x(-std::f32::consts::FRAC_PI_2) * Mat3::from_diagonal(Vec3::splat(4.0));
    scene.instances.push(Instance {
        transform: Transform { linear, translation: DVec3::new(0.0, 2.0, -4.0) },
        mesh: quad,
        material: fence,
        flags: 0,
    });
    scene
}

#[test]
fn alpha_masked_casters_throw_holed_shadows() {
    let gpu = GpuTest::new();
    let scene = fence_stage();
    let camera = camera();
    let (lit, _) = render(&gpu, &scene, &camera, "default", None);
    let (culled, _) = render(&gpu, &scene, &camera, "default", Some(shadows(true)));
    let (unculled, _) = render(&gpu, &scene, &camera, "no_cull", Some(shadows(false)));
    assert!(culled.as_raw() == unculled.as_raw(), "caster culling changed the image");
    // Across the shadow (z = -2), the bars' shadows alternate with the sunlit gaps.
    let (x0, y) = pixel_of(&camera, DVec3::new(-1.8, 0.0, -2.0));
    let (x1, _) = pixel_of(&camera, DVec3::new(1.8, 0.0, -2.0));
    let row: Vec<bool> = (x0..=x1).map(|x| luma(&culled, (x, y)) < 0.8 * luma(&lit, (x, y))).collect();
    let shadowed = row.iter().filter(|&&s| s).count();
    let changes = row.windows(2).filter(|w| w[0] != w[1]).count();
    assert!(shadowed > row.len() / 4 && shadowed < row.len() * 3 / 4, "{row:?}");
    assert!(changes >= 6, "bars and gaps alternate: {row:?}");
    gpu.assert_clean();
}

#[test]
fn every_lighting_method_samples_the_same_shadows() {
    let gpu = GpuTest::new();
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, -1.5));
    add_box(&mut scene, cube, DVec3::new(0.0, 9.0, 16.0), 3.0);
    let camera = camera();
    let shadowed = pixel_of(&camera, DVec3::new(0.0, 0.0, 2.5));
    let (reference, _) = render(&gpu, &scene, &camera, "default", Some(shadows(true)));
    for graph in ["msaa_compressed", "msaa_per_sample", "msaa_zprepass", "visibility_buffer"] {
        let (culled, _) = render(&gpu, &scene, &camera, graph, Some(shadows(true)));
        let (unculled, _) = render(&gpu, &scene, &camera, graph, Some(shadows(false)));
        assert!(culled.as_raw() == unculled.as_raw(), "{graph}: caster culling changed the image");
        let (a, b) = (luma(&culled, shadowed), luma(&reference, shadowed));
        assert!((a - b).abs() < 3.0, "{graph}: {a} in the shadow, the default graph {b}");
    }
    gpu.assert_clean();
}

#[test]
fn transparent_surfaces_receive_shadows() {
    let gpu = GpuTest::new();
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, -1.5));
    add_box(&mut scene, cube, DVec3::new(0.0, 9.0, 16.0), 3.0);
    let glass = scene.add_material(Material {
        name: "glass".into(),
        albedo: Vec3::ONE,
        alpha: 0.95,
        alpha_mode: AlphaMode::Blend,
        ..Default::default()
    });
    // A thin white slab lying in the shadow, half a unit above the ground.
    scene.instances.push(Instance {
        transform: Transform {
            linear: Mat3::from_diagonal(Vec3::new(3.0, 0.05, 3.0)),
            translation: DVec3::new(0.0, 0.5, 2.5),
        },
        mesh: cube,
        material: glass,
        flags: 0,
    });
    let camera = camera();
    let at = pixel_of(&camera, DVec3::new(0.0, 0.525, 2.5));
    let (lit, _) = render(&gpu, &scene, &camera, "default", None);
    let (shadowed, _) = render(&gpu, &scene, &camera, "default", Some(shadows(true)));
    assert!(luma(&shadowed, at) < 0.8 * luma(&lit, at), "{} shadowed, {} lit", luma(&shadowed, at), luma(&lit, at));
    gpu.assert_clean();
}

#[test]
fn moving_casters_and_moving_lights_give_the_image_of_unculled_casters() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, -1.5));
    add_box(&mut scene, cube, DVec3::new(0.0, 9.0, 16.0), 3.0);
    add_box(&mut scene, cube, DVec3::new(-3.0, 1.0, 0.0), 2.0);
    let (mut world, handles) = World::new(scene).unwrap();
    // A point light circling over the boxes, with its shadows.
    let lamp = |t: f64| PointLight::point(DVec3::new(3.0 * t.cos(), 3.0, 3.0 * t.sin()), Vec3::splat(60.0), 15.0);
    let light = world.insert_light(lamp(0.0)).unwrap();
    let size = RenderSettings::new(SIZE.0, SIZE.1);
    let make = |graph: &str, culling: bool| {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r = Renderer::from_world(&gpu, shaders, &world, size.clone(), &spec).unwrap();
        r.set_shadows(shaders, Some(shadows(culling))).unwrap();
        r
    };
    let (mut culled, mut unculled) = (make("default", true), make("no_cull", false));
    let camera = camera();
    for frame in 0..6 {
        let t = frame as f64;
        // The box behind the camera rises and drifts sideways; the one in view slides.
        world
            .set_transform(
                handles[1],
                Transform {
                    linear: Mat3::from_diagonal(Vec3::splat(3.0)),
                    translation: DVec3::new(t * 0.7, 9.0 + t, 16.0),
                },
            )
            .unwrap();
        world
            .set_transform(
                handles[2],
                Transform {
                    linear: Mat3::from_diagonal(Vec3::splat(2.0)),
                    translation: DVec3::new(-3.0 + t, 1.0, 0.0),
                },
            )
            .unwrap();
        world.set_light(light, lamp(t * 0.7)).unwrap();
        if frame >= 3 {
            let turn = Vec3::new(0.3 * (t as f32 - 3.0), -1.0, -1.5).normalize();
            world.set_sun(DirectionalLight { direction: turn, ..world.scene().sun }).unwrap();
        }
        culled.sync(shaders, &world).unwrap();
        unculled.sync(shaders, &world).unwrap();
        let (_, a) = culled.render_to_image(&camera).unwrap();
        let (_, b) = unculled.render_to_image(&camera).unwrap();
        assert!(a.as_raw() == b.as_raw(), "frame {frame}: caster culling changed the image");
    }
    gpu.assert_clean();
}

#[test]
fn bad_shadow_settings_are_refused_and_change_nothing() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, _) = stage(Vec3::new(0.0, -1.0, -1.5));
    let spec = GraphSpec::builtin("default").unwrap();
    let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.set_shadows(shaders, Some(shadows(true))).unwrap();
    for (bad, says) in [
        (ShadowSettings { cascades: 0, ..shadows(true) }, "0 cascades"),
        (ShadowSettings { cascades: 5, ..shadows(true) }, "5 cascades"),
        (ShadowSettings { resolution: 0, ..shadows(true) }, "0 texels"),
        (ShadowSettings { resolution: 1 << 20, ..shadows(true) }, "size 1048576"),
        (ShadowSettings { distance: Some(f32::NAN), ..shadows(true) }, "distance NaN"),
        (ShadowSettings { lambda: 2.0, ..shadows(true) }, "lambda 2"),
        (ShadowSettings { lod_threshold: -1.0, ..shadows(true) }, "level of detail threshold -1"),
        (ShadowSettings { lod_threshold: f64::NAN, ..shadows(true) }, "level of detail threshold NaN"),
    ] {
        let e = r.set_shadows(shaders, Some(bad)).unwrap_err().to_string();
        assert!(e.contains(says), "{e}");
        assert_eq!(r.shadows(), Some(&shadows(true)));
    }
    let memory = r.shadow_map_bytes();
    assert!(memory >= 4 * 512 * 512 * 4, "{memory}");
    r.render(&camera()).unwrap();
    r.set_shadows(shaders, None).unwrap();
    assert_eq!(r.shadow_map_bytes(), 0);
    r.render(&camera()).unwrap();
    gpu.assert_clean();
}

#[test]
fn maps_are_drawn_again_only_when_their_camera_the_sun_or_the_world_changed() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, -1.5));
    add_box(&mut scene, cube, DVec3::new(0.0, 9.0, 16.0), 3.0);
    let (mut world, handles) = World::new(scene).unwrap();
    let spec = GraphSpec::default_graph();
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.set_shadows(shaders, Some(shadows(true))).unwrap();
    let drew = |r: &mut Renderer, camera: &Camera| -> (Vec<u32>, Vec<u8>) {
        let (stats, image) = r.render_to_rgba8(camera).unwrap();
        (stats.shadow_cascades.iter().map(|c| c.index).collect(), image)
    };
    let camera = camera();
    let (first, image) = drew(&mut r, &camera);
    assert_eq!(first, [0, 1, 2, 3]);
    let (second, kept) = drew(&mut r, &camera);
    assert_eq!(second, Vec::<u32>::new(), "nothing changed");
    assert!(image == kept, "the kept maps shade as the drawn ones did");
    // A small step moves the nearest cascades by whole texels; the farthest, whose texels are
    // larger than the step, keep their maps.
    let stepped = Camera {
        eye: camera.eye + DVec3::new(-0.03, 0.0, 0.0),
        target: camera.target + DVec3::new(-0.03, 0.0, 0.0),
        ..camera.clone()
    };
    let (step, _) = drew(&mut r, &stepped);
    assert!(step.contains(&0) && !step.contains(&3), "{step:?}");
    // Any change of the world draws every map again.
    world
        .set_transform(
            handles[1],
            Transform { linear: Mat3::from_diagonal(Vec3::splat(3.0)), translation: DVec3::new(1.0, 9.0, 16.0) },
        )
        .unwrap();
    r.sync(shaders, &world).unwrap();
    assert_eq!(drew(&mut r, &stepped).0, [0, 1, 2, 3]);
    world.set_sun(DirectionalLight { direction: Vec3::new(0.1, -1.0, -1.5).normalize(), ..world.scene().sun }).unwrap();
    r.sync(shaders, &world).unwrap();
    assert_eq!(drew(&mut r, &stepped).0, [0, 1, 2, 3]);
    // Kept off, every map is drawn every frame.
    r.set_shadow_maps_kept(false);
    assert_eq!(drew(&mut r, &stepped).0, [0, 1, 2, 3]);
    gpu.assert_clean();
}

/// The ground lit by `light` alone (the sun is black), with a box of side `side` at `box_at`.
fn local_stage(light: PointLight, box_at: DVec3, side: f32) -> Scene {
    let (mut scene, cube) = stage(Vec3::new(0.0, -1.0, 0.0));
    scene.sun.color = Vec3::ZERO;
    scene.lights.push(light);
    add_box(&mut scene, cube, box_at, side);
    scene
}

/// `light`'s shadow falls on `shadowed` (on the ground, in view): darker with shadows than
/// without, and the same image whether casters are culled or not.
fn assert_light_shadows(scene: &Scene, shadowed: DVec3) {
    let gpu = GpuTest::new();
    let camera = camera();
    let at = pixel_of(&camera, shadowed);
    let (lit, _) = render(&gpu, scene, &camera, "default", None);
    let (culled, _) = render(&gpu, scene, &camera, "default", Some(shadows(true)));
    let (unculled, _) = render(&gpu, scene, &camera, "no_cull", Some(shadows(false)));
    assert!(luma(&culled, at) < 0.8 * luma(&lit, at), "{at:?}: {} shadowed, {} lit", luma(&culled, at), luma(&lit, at));
    assert!(culled.as_raw() == unculled.as_raw(), "caster culling changed the image");
    gpu.assert_clean();
}

#[test]
fn a_spot_light_casts_a_shadow() {
    let mut light = PointLight::point(DVec3::new(0.0, 6.0, 0.0), Vec3::splat(150.0), 20.0);
    light.spot = Some(SpotCone { direction: Vec3::NEG_Y, inner_angle: 0.4, outer_angle: 0.6 });
    assert_light_shadows(&local_stage(light, DVec3::new(0.0, 2.0, 0.0), 1.0), DVec3::ZERO);
}

#[test]
fn a_point_light_casts_a_shadow_through_its_cube() {
    // The light, the box and the shadowed point on one line, along the cube's -x face.
    let (light, ground) = (DVec3::new(3.0, 4.0, 0.0), DVec3::new(-1.5, 0.0, 0.3));
    let box_at = light + (ground - light) * 0.6;
    let scene = local_stage(PointLight::point(light, Vec3::splat(150.0), 20.0), box_at, 0.6);
    assert_light_shadows(&scene, ground);
}

#[test]
fn only_the_budget_of_lights_casts_shadows_and_a_larger_budget_is_refused() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (light, ground) = (DVec3::new(3.0, 4.0, 0.0), DVec3::new(-1.5, 0.0, 0.3));
    let mut scene =
        local_stage(PointLight::point(light, Vec3::splat(150.0), 20.0), light + (ground - light) * 0.6, 0.6);
    // A brighter light elsewhere takes the only shadowed light's place.
    scene.lights.push(PointLight::point(DVec3::new(-6.0, 3.0, 2.0), Vec3::splat(400.0), 20.0));
    let camera = camera();
    let at = pixel_of(&camera, ground);
    let one = ShadowSettings { local_lights: 1, ..shadows(true) };
    let (lit, _) = render(&gpu, &scene, &camera, "default", None);
    let (budget_one, _) = render(&gpu, &scene, &camera, "default", Some(one));
    let (budget_two, _) = render(&gpu, &scene, &camera, "default", Some(shadows(true)));
    assert!((luma(&budget_one, at) - luma(&lit, at)).abs() < 2.0, "past the budget, the light casts no shadow");
    assert!(luma(&budget_two, at) < luma(&lit, at) - 5.0, "within it, it does");
    let spec = GraphSpec::default_graph();
    let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    let e = r.set_shadows(shaders, Some(ShadowSettings { local_lights: 5, ..shadows(true) })).unwrap_err();
    assert!(e.to_string().contains("5 shadowed spot and point lights; at most 4"), "{e}");
    gpu.assert_clean();
}
