//! Lights an engine sets at run time and lights a glTF file brings: spot lights light their cone
//! only, the world's sun is what the next frame shades with, and `KHR_lights_punctual` lights
//! are imported (the first directional light as the sun) instead of placed.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::world::{World, WorldError};
use cullgraph::scene::{DirectionalLight, PointLight, Scene, SpotCone};
use glam::{DVec3, Vec3};
use serde_json::json;

const SIZE: (u32, u32) = (64, 48);

fn image(gpu: &GpuTest, scene: Scene) -> Vec<u8> {
    let shaders = gpu.shaders();
    let mut r = Renderer::new(gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1)).unwrap();
    r.render_to_rgba8(&boxes_camera()).unwrap().1
}

/// The boxes in the dark but for `light`.
fn lit_by(light: Option<PointLight>) -> Scene {
    let mut scene = boxes_scene();
    scene.sun.color = Vec3::ZERO;
    scene.lights = light.into_iter().collect();
    scene
}

#[test]
fn a_spot_light_lights_its_cone_only() {
    let gpu = GpuTest::new();
    let above = DVec3::new(0.0, 4.0, 0.5);
    let point = PointLight::point(above, Vec3::splat(60.0), 12.0);
    let cone = SpotCone { direction: Vec3::NEG_Y, inner_angle: 0.15, outer_angle: 0.3 };
    let dark = image(&gpu, lit_by(None));
    let everywhere = image(&gpu, lit_by(Some(point)));
    let spot = image(&gpu, lit_by(Some(PointLight { spot: Some(cone), ..point })));
    let lit = |img: &[u8]| img.chunks(4).zip(dark.chunks(4)).filter(|(a, b)| a != b).count();
    let (by_spot, by_point) = (lit(&spot), lit(&everywhere));
    assert!(by_spot > 20, "the spot lights {by_spot} pixels");
    assert!(by_spot * 3 < by_point, "the spot lights {by_spot} pixels, the point light {by_point}");
    // Whatever the spot lights, the point light at its place lights too; inside the inner cone
    // both give the same pixel.
    let mut same = 0;
    for ((s, p), d) in spot.chunks(4).zip(everywhere.chunks(4)).zip(dark.chunks(4)) {
        if s != d {
            assert!(p != d, "a pixel lit by the spot but not by the point light");
        }
        same += usize::from(s != d && s == p);
    }
    assert!(same > 0, "no pixel inside the inner cone");
    gpu.assert_clean();
}

#[test]
fn the_world_sets_the_sun_and_refuses_a_bad_one() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let mut r =
        Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(SIZE.0, SIZE.1), &GraphSpec::default_graph())
            .unwrap();
    let before = r.render_to_rgba8(&boxes_camera()).unwrap().1;

    let sun = DirectionalLight { direction: Vec3::new(0.6, -0.3, -0.74).normalize(), color: Vec3::new(4.0, 1.0, 0.5) };
    world.set_sun(sun).unwrap();
    assert_eq!(world.sun(), sun);
    r.sync(shaders, &world).unwrap();
    let after = r.render_to_rgba8(&boxes_camera()).unwrap().1;
    assert!(after != before, "the new sun shades the next frame");
    let mut expected = boxes_scene();
    expected.sun = sun;
    assert!(after == image(&gpu, expected), "the image of a scene loaded with that sun");

    for bad in [
        DirectionalLight { direction: Vec3::ZERO, ..sun },
        DirectionalLight { direction: Vec3::new(0.0, -2.0, 0.0), ..sun },
        DirectionalLight { color: Vec3::new(f32::NAN, 1.0, 1.0), ..sun },
        DirectionalLight { color: Vec3::new(-1.0, 1.0, 1.0), ..sun },
    ] {
        let e = world.set_sun(bad).unwrap_err();
        assert!(matches!(e, WorldError::Invalid { .. }) && e.to_string().starts_with("the sun: "), "{e}");
    }
    assert_eq!(world.sun(), sun, "a refused sun changes nothing");

    let bad_cone = SpotCone { direction: Vec3::NEG_Y, inner_angle: 0.5, outer_angle: 0.2 };
    let e = world.insert_light(PointLight { spot: Some(bad_cone), ..PointLight::point(DVec3::Y, Vec3::ONE, 4.0) });
    assert!(e.unwrap_err().to_string().contains("inner 0.5, outer 0.2"));
    gpu.assert_clean();
}

#[test]
fn khr_lights_punctual_lights_are_imported() {
    let dir = tempfile::tempdir().unwrap();
    let uri = common::triangle_data_uri();
    // Rotated -90 degrees about X, a node's -Z points down.
    let down = [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1.0, 0.5, 0.25], "intensity": 2.0},
            {"type": "point", "color": [1.0, 1.0, 1.0], "intensity": 8.0},
            {"type": "spot", "intensity": 5.0, "range": 7.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
            {"type": "directional", "intensity": 1.0}
        ]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
        "nodes": [
            {"name": "tri", "mesh": 0},
            {"name": "sun", "rotation": down, "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "lamp", "translation": [1.0, 2.0, 3.0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "torch", "translation": [0.0, 5.0, 0.0], "rotation": down, "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"name": "moon", "extensions": {"KHR_lights_punctual": {"light": 3}}}
        ],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": uri}]
    });
    let path = dir.path().join("lights.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let (scene, report) =
        cullgraph::scene::gltf_import::load_with_report(&path, &cullgraph::scene::source::LoadOptions::default())
            .unwrap();

    assert!((scene.sun.direction - Vec3::NEG_Y).length() < 1e-5, "{:?}", scene.sun);
    assert_eq!(scene.sun.color, Vec3::new(2.0, 1.0, 0.5));
    assert_eq!(scene.lights.len(), 2, "the file's lights, nothing placed: {:?}", scene.lights);
    let lamp = scene.lights[0];
    assert_eq!((lamp.position, lamp.color, lamp.spot), (DVec3::new(1.0, 2.0, 3.0), Vec3::splat(8.0), None));
    // No range: it ends where its radiance falls below the cutoff.
    let cutoff = cullgraph::scene::gltf_import::LIGHT_RANGE_CUTOFF;
    assert!((lamp.range - (8.0f32 / cutoff).sqrt()).abs() < 1e-3, "{}", lamp.range);
    let torch = scene.lights[1];
    assert_eq!(torch.range, 7.0);
    let cone = torch.spot.expect("a spot light");
    assert!((cone.direction - Vec3::NEG_Y).length() < 1e-5);
    assert_eq!((cone.inner_angle, cone.outer_angle), (0.2, 0.5));
    assert!(report.notes.iter().any(|n| n.contains("1 more directional light(s) ignored")), "{:?}", report.notes);
    assert!(!report.notes.iter().any(|n| n.contains("extensions are ignored")), "{:?}", report.notes);
}
