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
    let mut r = Renderer::from_world(&gpu, shaders, &world, size.clone(), &GraphSpec::default_graph()).unwrap();
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
        r.sync(shaders, &world).unwrap();
        r.render(&camera).unwrap();
    }
    assert_eq!(meshes, used_meshes, "each mesh registered once");
    assert_eq!(instances, 600);
    let streamed = r.render_to_rgba8(&camera).unwrap().1;
    let mut whole = Renderer::new(&gpu, shaders, world.live_scene(), size).unwrap();
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

/// The boxes scene with `n` more red cubes out of its camera's view, in rows of 50.
fn boxes_and_far_cubes(n: usize) -> cullgraph::scene::Scene {
    let mut scene = boxes_scene();
    let base = scene.instances[1];
    for i in 0..n {
        let at = DVec3::new(-30.0 - (i % 50) as f64, 0.5, -30.0 - (i / 50) as f64);
        scene
            .instances
            .push(cullgraph::scene::Instance { transform: Transform { translation: at, ..base.transform }, ..base });
    }
    scene
}

/// A cube whose faces each span the whole texture.
fn textured_cube() -> cullgraph::scene::MeshData {
    let mut m = common::cube_mesh();
    m.uvs = (0..m.positions.len()).map(|i| [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]][i % 4].into()).collect();
    m
}

/// A `side` x `side` checker of `rgb` and black whose alpha ramps across (what a masked
/// material's coverage-preserving mips change).
fn checker(name: &str, side: u32, rgb: [u8; 3]) -> cullgraph::scene::Texture {
    let rgba = (0..side * side)
        .flat_map(|i| {
            let (x, y) = (i % side, i / side);
            let c = if (x / 4 + y / 4) % 2 == 0 { rgb } else { [0, 0, 0] };
            [c[0], c[1], c[2], (x * 255 / side.max(1)) as u8]
        })
        .collect();
    cullgraph::scene::Texture { name: name.into(), width: side, height: side, rgba }
}

/// Registering meshes, textures and materials into a live world writes only what they add,
/// with the layout kept: a texture size class outgrows its array (carried over on the GPU), a
/// removed texture's index comes back in another class, and a material that masks a texture
/// makes its mips again. After each step the renderer draws exactly what a renderer made
/// afresh from the same world draws.
#[test]
fn registrations_upload_only_what_they_add() {
    use cullgraph::scene::{AlphaMode, Instance, Material, TextureRef};
    use glam::Vec3;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    // Enough instances that a whole upload would show in the figures.
    let (mut world, _) = World::new(boxes_and_far_cubes(3000)).unwrap();
    let size = RenderSettings::new(96, 72);
    let spec = GraphSpec::default_graph();
    let mut r = Renderer::from_world(&gpu, shaders, &world, size.clone(), &spec).unwrap();
    let camera = boxes_camera();
    let mut last = r.render_to_rgba8(&camera).unwrap().1;
    let mut compare = |world: &World, r: &mut Renderer, what: &str| {
        let stats = r.sync(shaders, world).unwrap();
        assert!(!stats.relayout, "{what}: the layout is kept");
        let got = r.render_to_rgba8(&camera).unwrap().1;
        let mut fresh = Renderer::from_world(&gpu, shaders, world, size.clone(), &spec).unwrap();
        let want = fresh.render_to_rgba8(&camera).unwrap().1;
        let differ = got.chunks_exact(4).zip(want.chunks_exact(4)).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{what}: pixels differ from a renderer made afresh");
        let changed = got.chunks_exact(4).zip(last.chunks_exact(4)).filter(|(a, b)| a != b).count();
        assert!(changed > 10, "{what}: the change shows ({changed} pixels changed)");
        last = got;
        stats.bytes_uploaded
    };

    // One mesh, texture and material, and an instance of them.
    let cube = world.add_mesh("textured cube", &textured_cube()).unwrap();
    let first = world.add_texture(checker("first", 64, [250, 200, 20])).unwrap();
    let mut material = Material { name: "textured".into(), albedo: Vec3::ONE, ..Default::default() };
    material.textures[0] = Some(TextureRef::new(first));
    let textured = world.add_material(material.clone()).unwrap();
    let place = |x: f64, z: f64, material| Instance {
        transform: Transform { linear: Mat3::from_diagonal(Vec3::splat(0.6)), translation: DVec3::new(x, 0.3, z) },
        mesh: cube,
        material,
        flags: 0,
    };
    world.insert(place(-0.4, -1.2, textured)).unwrap();
    let bytes = compare(&world, &mut r, "one registration");
    let texels = 64 * 64 * 4 * 4 / 3 + 64;
    let mesh = 24 * 32 + 36 * 4;
    assert!(bytes >= texels && bytes <= texels + mesh + 4096, "one registration uploaded {bytes} bytes");

    // More textures of that class than its array holds: the array grows on the GPU.
    let mut materials = Vec::new();
    for k in 0..9u8 {
        let t = world.add_texture(checker(&format!("t{k}"), 64, [40 + 20 * k, 255 - 20 * k, 90])).unwrap();
        let mut m = material.clone();
        m.textures[0] = Some(TextureRef::new(t));
        materials.push((t, world.add_material(m).unwrap()));
    }
    let handles: Vec<_> = materials
        .iter()
        .enumerate()
        .map(|(k, &(_, m))| world.insert(place(-2.4 + 0.6 * k as f64, 2.2, m)).unwrap())
        .collect();
    compare(&world, &mut r, "a grown texture class");

    // A texture removed, its index taken by one of another class.
    world.remove(handles[3]).unwrap();
    let (gone, gone_material) = materials[3];
    world.remove_material(gone_material).unwrap();
    world.remove_texture(gone).unwrap();
    let again = world.add_texture(checker("bigger", 128, [20, 90, 250])).unwrap();
    assert_eq!(again, gone, "the removed texture's index is reused");
    let mut m = material.clone();
    m.textures[0] = Some(TextureRef::new(again));
    let m = world.add_material(m).unwrap();
    world.insert(place(-0.6, 2.2, m)).unwrap();
    compare(&world, &mut r, "a texture index in another class");

    // The first texture now masked: its mips are made again to keep its coverage.
    material.textures[0] = Some(TextureRef::new(first));
    material.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    world.set_material(textured, material.clone()).unwrap();
    let bytes = compare(&world, &mut r, "a texture masked");
    assert!(bytes >= texels && bytes <= texels + 4096, "masking a texture uploaded {bytes} bytes");

    // Materials that become double-sided, then blended: their instances change draw groups.
    let (_, other) = materials[0];
    let mut sides = world.scene().materials[other as usize].clone();
    sides.double_sided = true;
    sides.albedo = Vec3::new(0.3, 1.0, 0.3);
    world.set_material(other, sides.clone()).unwrap();
    compare(&world, &mut r, "a material made double-sided");
    sides.alpha_mode = AlphaMode::Blend;
    sides.alpha = 0.5;
    world.set_material(other, sides).unwrap();
    compare(&world, &mut r, "a material made blended");
    gpu.assert_clean();
}

/// A world that grows in place between frames submitted without waiting, as an engine submits
/// them: no validation message, and the last frame draws what a renderer made afresh draws.
/// (`streaming_a_level_while_frames_are_in_flight_is_clean` in `tests/cli_render.rs` is the
/// case that catches memory destroyed under a frame still executing.)
#[test]
fn growing_while_frames_are_in_flight_keeps_what_they_use() {
    use cullgraph::render::FramePipeline;
    use cullgraph::scene::Instance;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    // Large enough that the growth below stays within the room the graph was compiled with:
    // the passes resize their own memory rather than the graph being made anew.
    let (mut world, _) = World::new(boxes_and_far_cubes(2000)).unwrap();
    let spec = GraphSpec::default_graph();
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(64, 48), &spec).unwrap();
    let camera = boxes_camera();
    let mut pipeline = FramePipeline::new(&gpu).unwrap();
    let cube = world.add_mesh("small cube", &common::cube_mesh()).unwrap();
    for round in 0..8 {
        for k in 0..(4 << round.min(3)) {
            let at = DVec3::new(-3.0 + 0.05 * k as f64, 0.1 + 0.2 * round as f64, -2.0);
            let transform = Transform { linear: Mat3::from_diagonal(glam::Vec3::splat(0.05)), translation: at };
            world.insert(Instance { transform, mesh: cube, material: 1, flags: 0 }).unwrap();
        }
        let stats = r.sync(shaders, &world).unwrap();
        assert!(!stats.relayout, "round {round}: grown in place");
        pipeline.submit(&mut r, &camera).unwrap();
    }
    pipeline.finish(&r).unwrap();
    let streamed = r.render_to_rgba8(&camera).unwrap().1;
    let mut fresh = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(64, 48), &spec).unwrap();
    assert!(streamed == fresh.render_to_rgba8(&camera).unwrap().1, "the grown world draws what a fresh one draws");
    gpu.assert_clean();
}
