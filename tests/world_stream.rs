//! Streaming into a live world: a scene added in pieces over several frames registers each
//! mesh, material and texture once, draws what a renderer of the whole world draws, and a
//! failed piece leaves the world as it was; a glTF file loads into a running world as an API call.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::merge::SceneMerge;
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::world::World;
use cullgraph::scene::{SceneSource, Transform};
use glam::{DVec3, Mat3};

fn city(instances: usize) -> cullgraph::scene::Scene {
    SceneSource::Builtin("city".into())
        .load(&LoadOptions { instances: Some(instances), lights: Some(2), ..Default::default() })
        .unwrap()
}

#[test]
fn a_city_streamed_in_pieces_draws_what_the_whole_world_draws() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let size = RenderSettings::new(64, 48);
    let mut r = Renderer::from_world(&gpu, &shaders, &world, size.clone(), &GraphSpec::default_graph()).unwrap();
    let camera = boxes_camera();
    r.render(&camera).unwrap();

    let placement =
        Transform { linear: Mat3::from_diagonal(glam::Vec3::splat(0.05)), translation: DVec3::new(-1.0, 0.0, -3.0) };
    let source = city(600);
    let used_meshes = {
        let mut m: Vec<u32> = source.instances.iter().map(|i| i.mesh).collect();
        m.sort_unstable();
        m.dedup();
        m.len()
    };
    let mut merge = SceneMerge::new(source, placement).unwrap();
    let pieces = merge.pieces(4);
    assert_eq!(pieces.len(), 4);
    assert_eq!(pieces.iter().map(Vec::len).sum::<usize>(), 600);
    let (mut meshes, mut instances) = (0, 0);
    for (k, piece) in pieces.iter().enumerate() {
        let added = merge.add(&mut world, piece).unwrap();
        assert_eq!(added.lights.len(), if k == 0 { 2 } else { 0 }, "the lights come with the first piece");
        meshes += added.meshes;
        instances += added.instances.len();
        r.sync(&shaders, &world).unwrap();
        r.render(&camera).unwrap();
    }
    assert_eq!(meshes, used_meshes, "each mesh registered once");
    assert_eq!(instances, 600);
    let streamed = r.render_to_rgba8(&camera).unwrap().1;
    let mut whole = Renderer::new(&gpu, &shaders, world.live_scene(), size).unwrap();
    assert!(
        streamed == whole.render_to_rgba8(&camera).unwrap().1,
        "the streamed world draws what the whole world draws"
    );

    // A piece naming an instance the source does not have: an error, and nothing changed.
    let live = (world.live_instances(), world.light_handles().count(), world.scene().meshes.len());
    let mut again = SceneMerge::new(city(600), placement).unwrap();
    let e = again.add(&mut world, &[0, 1, 5000]).unwrap_err().to_string();
    assert!(e.contains("instance 5000 does not exist (600 instances)"), "{e}");
    assert_eq!(live, (world.live_instances(), world.light_handles().count(), world.scene().meshes.len()));
    gpu.assert_clean();
}

#[test]
fn a_gltf_file_loads_into_a_live_world() {
    let dir = tempfile::tempdir().unwrap();
    let uri = common::triangle_data_uri();
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 3.0, "range": 4.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "tri", "mesh": 0, "translation": [1.0, 0.0, 0.0]},
            {"name": "lamp", "translation": [0.0, 2.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": uri}]
    });
    let path = dir.path().join("piece.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let lights = world.light_handles().count();
    let placement = Transform { translation: DVec3::new(10.0, 0.0, 0.0), ..Default::default() };
    let (added, _) = world.load_gltf(&path, placement, &LoadOptions::default()).unwrap();
    assert_eq!((added.instances.len(), added.lights.len(), added.meshes, added.materials), (1, 1, 1, 1));
    let instance = world.instance(added.instances[0]).unwrap();
    assert_eq!(instance.transform.translation, DVec3::new(11.0, 0.0, 0.0));
    assert_eq!(world.light_handles().count(), lights + 1);
    let light = world.live_scene().lights.last().copied().unwrap();
    assert_eq!(light.position, DVec3::new(10.0, 2.0, 0.0));

    let e = world.load_gltf(&dir.path().join("missing.gltf"), placement, &LoadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("missing.gltf"), "{e}");
}
