//! Posed instances: a skinned and morphed bar posed through the world API is deformed on the
//! GPU exactly as the CPU reference deforms it, culled with a bound of its pose (no false
//! negative and the culled image equal to the unculled one while it swings in and out of view),
//! and bad poses are refused naming the handle.

mod common;

use common::{boxes_scene, GpuTest};
use cullgraph::oracle::Verify;
use cullgraph::passes::shared::vertex_streams::{SurfaceVertex, VertexStreams};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::deform::MorphTarget;
use cullgraph::scene::world::{InstanceHandle, World};
use cullgraph::scene::{decode_octahedral, Camera, Instance, MeshData, Transform, Vertex};
use glam::{DVec3, Mat4, Vec3, Vec4};

const SIZE: (u32, u32) = (64, 48);

/// A square bar along x from -1 to 1: the left half on joint 0, the right half on joint 1,
/// blended at the middle ring; one morph target lifts the far end.
fn bar() -> MeshData {
    let mut m = MeshData::default();
    let rings = 9;
    for r in 0..rings {
        let x = -1.0 + 2.0 * r as f32 / (rings - 1) as f32;
        let right = ((x + 0.25) / 0.5).clamp(0.0, 1.0);
        for (y, z) in [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)] {
            m.positions.push(Vec3::new(x, y, z));
            m.joints.push([0, 1, 0, 0]);
            m.weights.push(Vec4::new(1.0 - right, right, 0.0, 0.0));
        }
    }
    for r in 0..rings - 1 {
        for k in 0..4u32 {
            let (a, b) = (r * 4 + k, r * 4 + (k + 1) % 4);
            let (c, d) = (a + 4, b + 4);
            m.indices.extend([a, b, d, a, d, c]);
        }
    }
    m.indices.extend([0, 2, 1, 0, 3, 2]);
    let last = (rings - 1) * 4;
    m.indices.extend([last, last + 1, last + 2, last, last + 2, last + 3]);
    let lift = m.positions.iter().map(|p| Vec3::new(0.0, 0.4 * (p.x + 1.0) * 0.5, 0.0)).collect();
    m.morph_targets = vec![MorphTarget { positions: lift, normals: vec![] }];
    m
}

/// The boxes scene with two bars beside it.
fn world() -> (World, Vec<InstanceHandle>, u32) {
    let mut scene = boxes_scene();
    let bar = scene.add_mesh("bar", &bar(), "bar").unwrap();
    for x in [-2.0, 2.0] {
        let transform = Transform { translation: DVec3::new(x, 1.5, -1.0), ..Default::default() };
        scene.instances.push(Instance { transform, mesh: bar, material: 2, flags: 0 });
    }
    let (world, handles) = World::new(scene).unwrap();
    (world, handles, bar)
}

/// Joint 1 turned by `angle` about z around the middle of the bar.
fn bend(angle: f32) -> Vec<Mat4> {
    vec![Mat4::IDENTITY, Mat4::from_rotation_z(angle)]
}

fn renderer(gpu: &GpuTest, world: &World, graph: &str, verify: bool) -> Renderer {
    let shaders = gpu.shaders();
    let spec = GraphSpec::builtin(graph).unwrap();
    let mut r = Renderer::from_world(gpu, shaders, world, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    if verify {
        r.enable_verification(shaders).unwrap();
    }
    r
}

fn camera() -> Camera {
    Camera { eye: DVec3::new(0.0, 2.0, 6.0), target: DVec3::new(0.0, 1.2, 0.0), ..Default::default() }
}

#[test]
fn posed_copies_are_deformed_on_the_gpu_as_the_cpu_reference_deforms_them() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, handles, bar) = world();
    let (left, right) = (handles[handles.len() - 2], handles[handles.len() - 1]);
    let mut r = renderer(&gpu, &world, "default", false);
    r.render(&camera()).unwrap();
    for (angle, lift) in [(0.8f32, 0.5f32), (-1.3, 1.0), (0.0, 0.0)] {
        world.set_pose(right, &bend(angle), &[lift]).unwrap();
        r.sync(shaders, &world).unwrap();
        r.render(&camera()).unwrap();
        let pose = world.pose(right).unwrap().expect("posed").clone();
        assert_eq!((pose.source, world.instance(right).unwrap().mesh), (bar, pose.mesh), "the instance draws its copy");
        let scene = world.scene();
        let source = &scene.meshes[bar as usize];
        let rest = &scene.vertices[source.vertex_offset as usize..][..source.vertex_count as usize];
        let (positions, normals) =
            source.deform.as_ref().unwrap().deform_vertices(rest, &pose.joints, &pose.morph_weights).unwrap();
        let pool = read_pool(&gpu, &r.gpu_scene().vertices, scene.vertices.len());
        let own = &scene.meshes[pose.mesh as usize];
        let gpu_vertices = &pool[own.vertex_offset as usize..][..own.vertex_count as usize];
        for (i, v) in gpu_vertices.iter().enumerate() {
            let p = Vec3::from_array(v.position);
            assert!(p.distance(positions[i]) < 1e-5, "angle {angle}: vertex {i} at {p}, reference {}", positions[i]);
            assert!(decode_octahedral(v.normal).dot(normals[i]) > 0.9999, "angle {angle}: normal {i}");
            let (lo, hi) = (own.bounds.min, own.bounds.max);
            assert!(p.cmpge(lo).all() && p.cmple(hi).all(), "angle {angle}: vertex {i} outside the pose's bounds");
        }
        // The other bar draws the shared rest mesh, untouched.
        assert_eq!(world.instance(left).unwrap().mesh, bar);
        let shared = &pool[source.vertex_offset as usize..][..source.vertex_count as usize];
        assert!(shared.iter().zip(rest).all(|(a, b)| a == b), "the rest mesh is not deformed");
    }
    gpu.assert_clean();
}

/// The first `n` vertices of the GPU's pool, read back from its three streams.
fn read_pool(gpu: &GpuTest, streams: &VertexStreams, n: usize) -> Vec<Vertex> {
    let read = |b: &cullgraph::gpu::Buffer| cullgraph::gpu::transfer::read_buffer(gpu, b).unwrap();
    let (p, nrm, s) = (read(&streams.positions), read(&streams.normals), read(&streams.surface));
    let positions: &[[f32; 3]] = bytemuck::cast_slice(&p[..n * 12]);
    let normals: &[[i16; 2]] = bytemuck::cast_slice(&nrm[..n * 4]);
    let surface: &[SurfaceVertex] = bytemuck::cast_slice(&s[..n * 16]);
    (0..n)
        .map(|i| Vertex { position: positions[i], normal: normals[i], uv: surface[i].uv, tangent: surface[i].tangent })
        .collect()
}

#[test]
fn culling_stays_exact_while_a_posed_bar_swings_in_and_out_of_view() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, handles, _) = world();
    let right = handles[handles.len() - 1];
    let mut culled = renderer(&gpu, &world, "two_phase", true);
    let mut unculled = renderer(&gpu, &world, "no_cull", false);
    // Other graphs read the deformed copies too (the visibility buffer fetches its triangles).
    let mut others: Vec<Renderer> =
        ["visibility_buffer", "msaa_compressed", "one_phase"].iter().map(|g| renderer(&gpu, &world, g, true)).collect();
    // Looking above the right bar: at rest it is out of view, bent up its end comes in.
    let camera = Camera { eye: DVec3::new(2.0, 5.0, 4.0), target: DVec3::new(2.0, 5.0, -1.0), ..Default::default() };
    let mut empty = None;
    let mut seen_in = 0;
    for frame in 0..12 {
        let angle = 1.6 * (frame as f32 * 0.6).sin().abs();
        world.set_pose(right, &bend(angle), &[(frame % 3) as f32 * 0.5]).unwrap();
        culled.sync(shaders, &world).unwrap();
        unculled.sync(shaders, &world).unwrap();
        for (k, other) in others.iter_mut().enumerate() {
            other.sync(shaders, &world).unwrap();
            let verify = other.render(&camera).unwrap().verify.expect("verified");
            assert_eq!(verify.false_negatives, 0, "graph {k}, frame {frame}: missed {:?}", verify.missed);
        }
        let (stats, image) = culled.render_to_image(&camera).unwrap();
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "frame {frame}: missed {:?}", verify.missed);
        let reference = unculled.render_to_image(&camera).unwrap().1;
        let differ = image.pixels().zip(reference.pixels()).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "frame {frame}: the culled image differs from the unculled one");
        let empty = empty.get_or_insert_with(|| image.clone());
        if image.pixels().zip(empty.pixels()).any(|(a, b)| a != b) {
            seen_in += 1;
        }
    }
    // Culled with the bound of its rest pose, it would be missing from these frames.
    assert!(seen_in >= 3, "the bent bar comes into view: {seen_in} frames");
    gpu.assert_clean();
}

#[test]
fn bad_poses_are_refused_naming_the_handle() {
    let (mut world, handles, bar_mesh) = world();
    let (plain, right) = (handles[1], handles[handles.len() - 1]);
    let e = world.set_pose(plain, &bend(0.1), &[]).unwrap_err().to_string();
    assert!(e.contains(&plain.to_string()) && e.contains("has no skin and no morph targets"), "{e}");
    let e = world.set_pose(right, &[Mat4::IDENTITY], &[]).unwrap_err().to_string();
    assert!(e.contains(&right.to_string()) && e.contains("1 joint matrices; mesh"), "{e}");
    let e = world.set_pose(right, &bend(0.1), &[0.1, 0.2]).unwrap_err().to_string();
    assert!(e.contains("2 morph weights") && e.contains("has 1 morph targets"), "{e}");
    let e = world.set_pose(right, &[Mat4::IDENTITY, Mat4::from_scale(Vec3::NAN)], &[]).unwrap_err().to_string();
    assert!(e.contains("finite"), "{e}");
    let (other, _) = World::new(boxes_scene()).unwrap();
    let foreign = other.handles().next().unwrap();
    assert!(world.set_pose(foreign, &bend(0.1), &[]).unwrap_err().to_string().contains("a handle of world"));
    assert!(world.pose(right).unwrap().is_none(), "nothing was posed");

    // A pose gives the instance its own copy; the source mesh cannot go while it is posed, and
    // removing the instance gives the copy's pool space back.
    let pools = world.pool_sizes();
    world.set_pose(right, &bend(0.5), &[]).unwrap();
    let own = world.pose(right).unwrap().unwrap().mesh;
    assert_ne!(own, bar_mesh);
    world.set_meshes(&[(handles[handles.len() - 2], 0)]).unwrap();
    let e = world.remove_mesh(bar_mesh).unwrap_err().to_string();
    assert!(e.contains("bar"), "{e}");
    let removed = world.remove(right).unwrap();
    assert_eq!(removed.mesh, bar_mesh, "the removed instance is given back with the mesh it was given");
    world.remove_mesh(bar_mesh).unwrap();
    let again = world.add_mesh("bar again", &bar()).unwrap();
    let h = world.insert(Instance { mesh: again, ..removed }).unwrap();
    world.set_pose(h, &bend(0.2), &[0.3]).unwrap();
    assert!(
        world.pool_sizes().0 <= pools.0 + 2 * bar().positions.len(),
        "pool space is reused: {:?}",
        world.pool_sizes()
    );
}

/// Motion vectors include the deformation: a pose that changes shows motion on the bar alone,
/// and a pose that stays shows none at the next frame.
#[test]
fn motion_vectors_follow_the_pose() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, handles, _) = world();
    let right = handles[handles.len() - 1];
    let camera = Camera { eye: DVec3::new(2.0, 2.0, 4.0), target: DVec3::new(2.0, 1.5, -1.0), ..Default::default() };
    let mut r = renderer(&gpu, &world, "post", false);
    let frame = |world: &World, r: &mut Renderer| {
        r.sync(shaders, world).unwrap();
        r.render(&camera).unwrap();
        let motion = r.read_output_f32("motion").unwrap();
        motion.data.chunks_exact(2).filter(|m| m[0].abs() + m[1].abs() > 0.25).count()
    };
    world.set_pose(right, &bend(0.0), &[]).unwrap();
    frame(&world, &mut r);
    frame(&world, &mut r);
    assert_eq!(frame(&world, &mut r), 0, "nothing moves");
    world.set_pose(right, &bend(0.6), &[0.5]).unwrap();
    let moving = frame(&world, &mut r);
    assert!(moving > 10, "the bending bar shows motion: {moving} pixels");
    assert_eq!(frame(&world, &mut r), 0, "a pose that stays shows no motion");
    gpu.assert_clean();
}

/// A morphed and animated glTF file (assimp's AnimatedMorphCube) loaded into a live world comes
/// with its animation, placed where its instances went; played through the world API, culling
/// stays exact and the cube changes shape.
#[test]
fn a_loaded_files_animation_plays_in_a_live_world() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let path = "/usr/share/assimp/models/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf";
    let (mut world, _, _) = world();
    let placement =
        Transform { translation: DVec3::new(0.0, 1.0, 1.0), linear: glam::Mat3::from_diagonal(Vec3::splat(10.0)) };
    let (added, _) = world.load_gltf(path.as_ref(), placement, &Default::default()).unwrap();
    let animation = added.animation.clone().expect("the file is animated");
    let mut r = renderer(&gpu, &world, "two_phase", true);
    let mut images = Vec::new();
    for frame in 0..6 {
        let poses = animation.pose(0, frame as f64 * 0.2);
        let moves: Vec<_> = poses.iter().map(|p| (added.instances[p.instance as usize], p.transform)).collect();
        world.set_transforms(&moves).unwrap();
        for p in &poses {
            world.set_pose(added.instances[p.instance as usize], &p.joints, &p.morph_weights).unwrap();
        }
        r.sync(shaders, &world).unwrap();
        let (stats, image) = r.render_to_image(&camera()).unwrap();
        assert_eq!(stats.verify.expect("verified").false_negatives, 0, "frame {frame}");
        images.push(image);
    }
    assert!(images.windows(2).any(|w| w[0] != w[1]), "the cube changes shape");
    gpu.assert_clean();
}
