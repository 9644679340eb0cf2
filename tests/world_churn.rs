//! Memory that is reused: meshes registered and unregistered over and over keep the vertex and
//! index pools within a fixed bound, and what is drawn afterwards is what a fresh renderer of
//! the same world draws.

mod common;

use common::{boxes_camera, boxes_scene, cube_mesh, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::world::World;
use cullgraph::scene::{Instance, MeshData, Transform};
use glam::{DVec3, Mat3, Vec3};

/// A box made of `copies` cubes side by side (a mesh of 24 * copies vertices).
fn boxes(copies: usize) -> MeshData {
    let cube = cube_mesh();
    let mut m = MeshData::default();
    for c in 0..copies {
        let base = m.positions.len() as u32;
        let shift = Vec3::new(c as f32, 0.0, 0.0);
        m.positions.extend(cube.positions.iter().map(|p| *p + shift));
        m.normals.extend(&cube.normals);
        m.indices.extend(cube.indices.iter().map(|i| i + base));
    }
    m
}

#[test]
fn a_thousand_add_remove_cycles_keep_the_pools_bounded_and_the_image_right() {
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let (vertices0, indices0) = world.pool_sizes();
    // A deterministic churn: up to 8 meshes of 1 to 12 cubes live, each cycle registering one
    // and unregistering the oldest once 8 are live.
    let mut live: Vec<(u32, usize)> = Vec::new();
    let (mut most_vertices, mut most_indices) = (0, 0);
    for cycle in 0..1000usize {
        let copies = 1 + (cycle * 7 + cycle / 3) % 12;
        live.push((world.add_mesh(&format!("churn {cycle}"), &boxes(copies)).unwrap(), copies));
        if live.len() > 8 {
            let (mesh, _) = live.remove((cycle * 5) % live.len());
            world.remove_mesh(mesh).unwrap();
        }
        let (v, i) = world.pool_sizes();
        (most_vertices, most_indices) = (most_vertices.max(v - vertices0), most_indices.max(i - indices0));
    }
    // Live at any time: at most 9 meshes of at most 12 cubes (24 vertices, 36 indices each).
    let (live_vertices, live_indices) = (9 * 12 * 24, 9 * 12 * 36);
    println!("pools beyond the scene's after 1,000 cycles: at most {most_vertices} vertices and {most_indices} indices (live at most {live_vertices} and {live_indices})");
    assert!(most_vertices <= 2 * live_vertices, "{most_vertices} vertices");
    assert!(most_indices <= 2 * live_indices, "{most_indices} indices");
    // Mesh indices are reused too.
    assert!(world.scene().meshes.len() <= 1 + 9, "{} mesh entries", world.scene().meshes.len());

    // The live meshes draw what they are, wherever they were placed.
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    for (k, &(mesh, _)) in live.iter().enumerate() {
        let transform = Transform {
            linear: Mat3::from_diagonal(Vec3::splat(0.3)),
            translation: DVec3::new(-2.0, 1.5, k as f64 * 0.5 - 2.0),
        };
        world.insert(Instance { transform, mesh, material: 1, flags: 0 }).unwrap();
    }
    let size = RenderSettings::new(64, 48);
    let mut churned = Renderer::from_world(&gpu, shaders, &world, size.clone(), &GraphSpec::default_graph()).unwrap();
    let image = churned.render_to_rgba8(&boxes_camera()).unwrap().1;
    let mut fresh_scene = boxes_scene();
    for (k, &(_, copies)) in live.iter().enumerate() {
        let mesh = fresh_scene.add_mesh("fresh", &boxes(copies), "fresh").unwrap();
        let transform = Transform {
            linear: Mat3::from_diagonal(Vec3::splat(0.3)),
            translation: DVec3::new(-2.0, 1.5, k as f64 * 0.5 - 2.0),
        };
        fresh_scene.instances.push(Instance { transform, mesh, material: 1, flags: 0 });
    }
    let mut fresh = Renderer::new(&gpu, shaders, fresh_scene, size).unwrap();
    assert!(image == fresh.render_to_rgba8(&boxes_camera()).unwrap().1, "the reused pool space draws the new meshes");
    gpu.assert_clean();
}

#[test]
fn removed_materials_give_their_index_to_the_next() {
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let materials = world.scene().materials.len();
    for cycle in 0..1000 {
        let m = world
            .add_material(cullgraph::scene::Material { name: format!("churn {cycle}"), ..Default::default() })
            .unwrap();
        assert_eq!(m as usize, materials, "cycle {cycle}: the freed index is reused");
        world.remove_material(m).unwrap();
    }
    assert_eq!(world.scene().materials.len(), materials + 1);
}

#[test]
fn removed_textures_free_their_texels_and_their_index() {
    use cullgraph::scene::{Material, Texture, TextureRef, TextureSlot};
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let big = || Texture { name: "big".into(), width: 64, height: 64, rgba: vec![200; 64 * 64 * 4] };
    let first = world.add_texture(big()).unwrap();
    let mut material = Material { name: "textured".into(), ..Default::default() };
    material.textures[TextureSlot::BaseColor as usize] = Some(TextureRef::new(first));
    let m = world.add_material(material.clone()).unwrap();
    let e = world.remove_texture(first).unwrap_err().to_string();
    assert!(e.contains("is used by 1 material(s), the first"), "{e}");
    world.remove_material(m).unwrap();
    world.remove_texture(first).unwrap();
    assert_eq!(world.scene().textures[first as usize].rgba.len(), 4, "the texels are freed");
    assert!(world.remove_texture(first).unwrap_err().to_string().contains("no such texture"));
    assert!(world.add_material(material).unwrap_err().to_string().contains(&format!("texture {first} was removed")));
    for _ in 0..1000 {
        let t = world.add_texture(big()).unwrap();
        assert_eq!(t, first, "the freed index is reused");
        world.remove_texture(t).unwrap();
    }
    assert_eq!(world.scene().textures.len() as u32, first + 1);
}
