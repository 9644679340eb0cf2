//! A renderer that mirrors a changing world: moved, inserted and removed instances show where
//! they are at the next frame, culling stays exact (the culled image equals the unculled one and
//! nothing visible is missed, on every frame), a reused slot inherits no visibility, and the same
//! changes give the same images.

mod common;

use common::{boxes_camera, boxes_scene, cube_mesh, GpuTest};
use cullgraph::oracle::Verify;
use cullgraph::passes::instance_cull::CullPassStats;
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::world::{InstanceHandle, World};
use cullgraph::scene::{Camera, Instance, Material, Transform};
use glam::{DVec3, Mat3, Vec3};
use proptest::prelude::*;

const SIZE: (u32, u32) = (64, 48);

fn renderer(gpu: &GpuTest, world: &World, graph: &str, verify: bool) -> Renderer {
    let spec = GraphSpec::builtin(graph).unwrap();
    let shaders = gpu.shaders();
    let mut r = Renderer::from_world(gpu, shaders, world, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    if verify {
        r.enable_verification(shaders).unwrap();
    }
    r
}

fn pixel(image: &RgbaImage, x: u32, y: u32) -> [u8; 4] {
    image.get_pixel(x, y).0
}

/// Where world point `p` lands in the image of `camera` (pixel coordinates).
fn project(camera: &Camera, p: DVec3) -> (u32, u32) {
    let vp = camera.view_projection_rel_eye(SIZE.0 as f32 / SIZE.1 as f32);
    let clip = vp * (p - camera.eye).as_vec3().extend(1.0);
    let ndc = clip.truncate() / clip.w;
    (((ndc.x * 0.5 + 0.5) * SIZE.0 as f32) as u32, ((ndc.y * 0.5 + 0.5) * SIZE.1 as f32) as u32)
}

#[test]
fn a_moved_inserted_and_removed_box_shows_where_it_is_at_the_next_frame() {
    let gpu = GpuTest::new();
    let (mut world, handles) = World::new(boxes_scene()).unwrap();
    let mut r = renderer(&gpu, &world, "default", false);
    let camera = boxes_camera();
    let shaders = gpu.shaders();
    let red_cube = handles[1];
    let before = r.render_to_image(&camera).unwrap().1;
    let old = project(&camera, DVec3::new(-1.5, 0.5, 0.0));
    let red = pixel(&before, old.0, old.1);
    assert!(red[0] > 2 * red[2], "the red cube is at {old:?}: {red:?}");

    // Moved out of the way: its old place shows what is behind it, its new place shows red.
    let moved = Transform { linear: Mat3::IDENTITY, translation: DVec3::new(-1.5, 0.5, -3.0) };
    world.set_transform(red_cube, moved).unwrap();
    let stats = r.sync(shaders, &world).unwrap();
    assert_eq!((stats.instances_changed, stats.relayout, stats.bytes_uploaded), (1, false, 72));
    let (frame_stats, after) = r.render_to_image(&camera).unwrap();
    let update = frame_stats.update.expect("the frame reports the update it applied");
    assert_eq!((update.instances_changed, update.bytes_uploaded, update.cpu_ms), (1, 72, stats.cpu_ms));
    assert_ne!(pixel(&after, old.0, old.1), red, "nothing red left where the cube was");
    let new = project(&camera, DVec3::new(-1.5, 0.5, -3.0));
    let p = pixel(&after, new.0, new.1);
    assert!(p[0] > 2 * p[2], "the cube at its new place {new:?}: {p:?}");

    // Removed: the image is the scene without it; inserted back where it was: the first image.
    world.remove(red_cube).unwrap();
    r.sync(shaders, &world).unwrap();
    let gone = r.render_to_image(&camera).unwrap().1;
    assert_ne!(pixel(&gone, new.0, new.1), p);
    let back = Instance { transform: boxes_scene().instances[1].transform, mesh: 0, material: 1, flags: 0 };
    world.insert(back).unwrap();
    r.sync(shaders, &world).unwrap();
    // Two frames: the first keeps the removed cube's slot empty (its quarantine); either way
    // the image is the first one.
    for _ in 0..2 {
        assert_eq!(r.render_to_image(&camera).unwrap().1, before);
    }
    gpu.assert_clean();
}

/// One change to the world.
#[derive(Clone, Debug)]
enum Op {
    Insert {
        x: f64,
        z: f64,
        tall: bool,
    },
    Remove(usize),
    Move {
        which: usize,
        x: f64,
        z: f64,
    },
    Remesh(usize),
    Recolor(usize),
    /// Registers a material (double-sided or not, so its instances may change face-cull
    /// region) and gives it to an instance.
    NewMaterial {
        which: usize,
        double_sided: bool,
    },
    /// Registers a mesh and gives it to an instance (a draw group the layout lacks).
    NewMesh(usize),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        (-4.0..4.0f64, -4.0..4.0f64, any::<bool>()).prop_map(|(x, z, tall)| Op::Insert { x, z, tall }),
        any::<usize>().prop_map(Op::Remove),
        (any::<usize>(), -4.0..4.0f64, -4.0..4.0f64).prop_map(|(which, x, z)| Op::Move { which, x, z }),
        any::<usize>().prop_map(Op::Remesh),
        any::<usize>().prop_map(Op::Recolor),
        (any::<usize>(), any::<bool>()).prop_map(|(which, double_sided)| Op::NewMaterial { which, double_sided }),
        any::<usize>().prop_map(Op::NewMesh),
    ]
}

/// Applies `op` to `world`; `handles` are the live instances besides the ground.
fn apply(world: &mut World, handles: &mut Vec<InstanceHandle>, op: &Op, meshes: [u32; 2]) {
    let pick = |i: usize, handles: &Vec<InstanceHandle>| handles[i % handles.len()];
    // Heights differ a little with x: two boxes' faces in one plane would z-fight, and where
    // depths tie exactly the order of the draws, which culling changes, decides the pixel.
    let at = |x: f64, z: f64, tall: bool| Transform {
        linear: Mat3::from_diagonal(if tall { Vec3::new(0.6, 2.5, 0.6) } else { Vec3::splat(0.8) }),
        translation: DVec3::new(x, if tall { 1.25 } else { 0.4 } + 0.02 * (x * 97.0).rem_euclid(1.0), z),
    };
    match *op {
        Op::Insert { x, z, tall } => {
            let instance = Instance { transform: at(x, z, tall), mesh: meshes[tall as usize], material: 1, flags: 0 };
            handles.push(world.insert(instance).unwrap());
        }
        Op::Remove(i) if handles.len() > 1 => {
            let h = handles.remove(i % handles.len());
            world.remove(h).unwrap();
        }
        Op::Move { which, x, z } if !handles.is_empty() => {
            let h = pick(which, handles);
            let tall = world.instance(h).unwrap().transform.linear.y_axis.y > 1.0;
            world.set_transform(h, at(x, z, tall)).unwrap();
        }
        Op::Remesh(i) if !handles.is_empty() => {
            let h = pick(i, handles);
            let mesh = world.instance(h).unwrap().mesh;
            world.set_meshes(&[(h, if mesh == meshes[0] { meshes[1] } else { meshes[0] })]).unwrap();
        }
        Op::Recolor(i) if !handles.is_empty() => {
            let h = pick(i, handles);
            let material = world.instance(h).unwrap().material;
            world.set_materials(&[(h, if material == 1 { 2 } else { 1 })]).unwrap();
        }
        Op::NewMaterial { which, double_sided } if !handles.is_empty() => {
            let albedo = Vec3::new(0.2, 0.5 + 0.4 * double_sided as u32 as f32, 0.9);
            let material = Material { name: "new".into(), albedo, double_sided, ..Default::default() };
            let m = world.add_material(material).unwrap();
            world.set_materials(&[(pick(which, handles), m)]).unwrap();
        }
        Op::NewMesh(i) if !handles.is_empty() => {
            let mesh = world.add_mesh("cube 3", &cube_mesh()).unwrap();
            world.set_meshes(&[(pick(i, handles), mesh)]).unwrap();
        }
        _ => {}
    }
}

/// The boxes world with a second cube mesh (so instances can change mesh), its handles besides
/// the ground, and the two meshes.
fn living_boxes() -> (World, Vec<InstanceHandle>, [u32; 2]) {
    let (mut world, handles) = World::new(boxes_scene()).unwrap();
    let other = world.add_mesh("cube 2", &cube_mesh()).unwrap();
    (world, handles[1..].to_vec(), [0, other])
}

/// Pixels the culled and unculled images of random boxes may differ in: where two boxes
/// interpenetrate, their surfaces' depths can tie exactly at a pixel on the intersection, and
/// the draw order, which culling changes, then decides the pixel. A culling error (a box missed
/// or drawn with stale data) differs in dozens of pixels at the least.
const DEPTH_TIE_PIXELS: usize = 2;

fn differing_pixels(a: &RgbaImage, b: &RgbaImage) -> usize {
    a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
}

/// Runs `ops`, two per frame, with the camera circling, through two-phase culling with
/// verification and through no culling; every frame's images must be equal with no false
/// negative. Returns the culled images.
fn run(gpu: &GpuTest, ops: &[Op]) -> Vec<RgbaImage> {
    let (mut world, mut handles, meshes) = living_boxes();
    let mut culled = renderer(gpu, &world, "two_phase", true);
    let mut unculled = renderer(gpu, &world, "no_cull", false);
    let shaders = gpu.shaders();
    let mut images = Vec::new();
    for (frame, pair) in ops.chunks(2).enumerate() {
        for op in pair {
            apply(&mut world, &mut handles, op, meshes);
        }
        culled.sync(shaders, &world).unwrap();
        unculled.sync(shaders, &world).unwrap();
        let angle = frame as f64 * 0.7;
        let camera = Camera {
            eye: DVec3::new(7.0 * angle.cos(), 3.0, 7.0 * angle.sin()),
            target: DVec3::new(0.0, 0.5, 0.0),
            ..Default::default()
        };
        let (stats, image) = culled.render_to_image(&camera).unwrap();
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "frame {frame}: missed {:?}", verify.missed);
        let reference = unculled.render_to_image(&camera).unwrap().1;
        let differ = differing_pixels(&image, &reference);
        assert!(
            differ <= DEPTH_TIE_PIXELS,
            "frame {frame}: the culled image differs from the unculled one in {differ} pixels"
        );
        images.push(image);
    }
    gpu.assert_clean();
    images
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    /// Random inserts, removes, moves, re-meshes and re-colorings with a moving camera:
    /// culling never changes the image and never misses a visible instance, on every frame.
    #[test]
    fn culling_stays_exact_under_random_changes(ops in proptest::collection::vec(op(), 4..24)) {
        let gpu = GpuTest::new();
        run(&gpu, &ops);
    }
}

/// Two syncs before a frame, in which slots change twice or more, in either order: a move
/// before and after another material, before and after another mesh (a slot in another group),
/// an insert then moved, a move then removed, and the second sync changing the first's slots
/// again. Every slot ends as its last change left it: the renderer shows what one made afresh
/// from the world shows, and misses nothing.
#[test]
fn a_slots_last_change_wins_within_a_frame() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, mut handles, meshes) = living_boxes();
    for i in 0..6 {
        let op = Op::Insert { x: -3.5 + 1.3 * i as f64, z: 2.5, tall: i % 2 == 0 };
        apply(&mut world, &mut handles, &op, meshes);
    }
    let camera = Camera { eye: DVec3::new(0.0, 6.0, 9.0), target: DVec3::new(0.0, 0.5, 0.0), ..Default::default() };
    let mut live = renderer(&gpu, &world, "two_phase", true);
    let before = live.render_to_image(&camera).unwrap().1;

    let moved = |which: usize, x: f64, z: f64| Op::Move { which, x, z };
    let mut ops = vec![
        moved(0, 1.5, -1.0),
        Op::Recolor(0),
        Op::Recolor(1),
        moved(1, -2.5, -2.0),
        moved(2, 3.0, 0.5),
        Op::Remesh(2),
        Op::Remesh(3),
        moved(3, -1.0, 1.0),
        Op::Insert { x: 0.5, z: -3.0, tall: true },
    ];
    // The inserted box moved, then a box moved and removed.
    let inserted = handles.len();
    ops.extend([moved(inserted, 2.0, -2.5), moved(4, -3.0, 0.0), Op::Remove(4)]);
    for op in &ops {
        apply(&mut world, &mut handles, op, meshes);
    }
    live.sync(shaders, &world).unwrap();
    let again = [moved(0, -0.5, -3.0), Op::Recolor(0), moved(1, 3.5, -0.5), Op::Recolor(2), moved(3, -3.5, -1.5)];
    for op in &again {
        apply(&mut world, &mut handles, op, meshes);
    }
    live.sync(shaders, &world).unwrap();
    let (stats, image) = live.render_to_image(&camera).unwrap();
    assert_eq!(stats.verify.expect("verified").false_negatives, 0);
    let mut fresh = renderer(&gpu, &world, "two_phase", false);
    let want = fresh.render_to_image(&camera).unwrap().1;
    let differ = differing_pixels(&image, &want);
    assert!(differ <= DEPTH_TIE_PIXELS, "{differ} pixels differ from a renderer made afresh");
    assert!(differing_pixels(&image, &before) > 100, "the changes show");
    gpu.assert_clean();
}

#[test]
fn a_shared_scene_is_held_once_and_a_world_renderers_copy_is_its_own() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let camera = boxes_camera();
    let settings = || RenderSettings::new(SIZE.0, SIZE.1);
    // A scene rendered as it is: the renderer keeps the caller's, and draws it as its own copy.
    let scene = std::sync::Arc::new(boxes_scene());
    let mut shared = Renderer::new(&gpu, shaders, scene.clone(), settings()).unwrap();
    assert!(std::sync::Arc::ptr_eq(&shared.shared_scene(), &scene), "the renderer holds the caller's scene");
    let mut owned = Renderer::new(&gpu, shaders, boxes_scene(), settings()).unwrap();
    assert_eq!(shared.render_to_image(&camera).unwrap().1, owned.render_to_image(&camera).unwrap().1);

    // A world renderer's slots: a caller's share keeps the slots as they were when shared.
    let (mut world, mut handles, meshes) = living_boxes();
    let mut live = renderer(&gpu, &world, "two_phase", false);
    let held = live.shared_scene();
    let slots_then = held.instances.clone();
    for op in [Op::Recolor(0), Op::Insert { x: 1.0, z: 1.0, tall: true }] {
        apply(&mut world, &mut handles, &op, meshes);
    }
    live.sync(shaders, &world).unwrap();
    assert_eq!(held.instances, slots_then, "a shared copy does not change");
    assert_ne!(live.scene().instances, slots_then, "the renderer's own slots took the changes");
    let image = live.render_to_image(&camera).unwrap().1;
    let want = renderer(&gpu, &world, "two_phase", false).render_to_image(&camera).unwrap().1;
    assert!(differing_pixels(&image, &want) <= DEPTH_TIE_PIXELS);
    gpu.assert_clean();
}

#[test]
fn the_same_changes_give_the_same_images_bit_for_bit() {
    let gpu = GpuTest::new();
    let ops: Vec<Op> = (0..16)
        .map(|i| match i % 5 {
            0 => Op::Insert { x: i as f64 * 0.4 - 3.0, z: 1.0, tall: i % 2 == 0 },
            1 => Op::Move { which: i, x: -2.0, z: i as f64 * 0.3 - 2.0 },
            2 => Op::Remesh(i),
            3 => Op::Recolor(i),
            _ => Op::Remove(i),
        })
        .collect();
    assert_eq!(run(&gpu, &ops), run(&gpu, &ops));
}

/// Inserting more instances than a group has room for grows the layout at its end: every slot
/// keeps its instance and the culling history stays, so the late phase draws only the boxes
/// new this round (a cleared history would make it draw everything visible), and the images
/// stay exact. The graph is recompiled only once the slots outgrow it.
#[test]
fn growing_past_the_room_keeps_every_slot_and_the_culling_history() {
    let gpu = GpuTest::new();
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let mut culled = renderer(&gpu, &world, "two_phase", true);
    let mut unculled = renderer(&gpu, &world, "no_cull", false);
    let shaders = gpu.shaders();
    let camera = boxes_camera();
    culled.render_to_image(&camera).unwrap();
    let slots_before = culled.scene().instances.len();
    for round in 0..6 {
        let mut inserted = Vec::new();
        for k in 0..8 {
            let x = -3.0 + k as f64 * 0.8;
            let z = -2.0 - round as f64 * 0.9;
            let t = Transform { linear: Mat3::from_diagonal(Vec3::splat(0.5)), translation: DVec3::new(x, 0.25, z) };
            inserted.push(world.insert(Instance { transform: t, mesh: 0, material: 2, flags: 0 }).unwrap());
        }
        let kept: Vec<_> = (0..world.instance_slots() as u32)
            .filter(|i| !inserted.iter().any(|h| h.index() == *i))
            .map(|i| culled.slot_of(i))
            .collect();
        let stats = culled.sync(shaders, &world).unwrap();
        assert!(!stats.relayout, "round {round}: growth is not a new layout");
        let after: Vec<_> = (0..world.instance_slots() as u32)
            .filter(|i| !inserted.iter().any(|h| h.index() == *i))
            .map(|i| culled.slot_of(i))
            .collect();
        assert_eq!(kept, after, "round {round}: every instance keeps its slot");
        unculled.sync(shaders, &world).unwrap();
        let (s, image) = culled.render_to_image(&camera).unwrap();
        assert_eq!(s.verify.as_ref().unwrap().false_negatives, 0, "round {round}");
        assert!(image == unculled.render_to_image(&camera).unwrap().1, "round {round}");
        let passes = CullPassStats::of(&s);
        let late = passes.iter().find(|c| c.pass == "cull_late").unwrap();
        assert!(late.drawn <= 8, "round {round}: the late phase drew {} (history lost?)", late.drawn);
    }
    assert!(culled.scene().instances.len() > slots_before + 16, "48 inserts into a group of 4 grow the slots");
    gpu.assert_clean();
}

/// Groups that grow in several regions, a lower region after a higher one, take slots after
/// every other group's while their commands stay in their regions: the culled lists must still
/// draw each instance with its own group's mesh (the tall boxes of the double-sided and masked
/// regions against the cubes of the one-sided region), with no relayout, no false negative
/// and the unculled image, through the early (last frame's list) and the late phase.
#[test]
fn groups_grown_in_several_regions_draw_their_own_instances() {
    let gpu = GpuTest::new();
    let (mut world, _) = World::new(boxes_scene()).unwrap();
    let mut tall = cube_mesh();
    for p in &mut tall.positions {
        p.y *= 3.0;
    }
    let tall = world.add_mesh("tall box", &tall).unwrap();
    let double_sided =
        world.add_material(Material { albedo: Vec3::new(0.2, 0.9, 0.3), double_sided: true, ..Default::default() });
    let masked = world.add_material(Material {
        albedo: Vec3::new(0.9, 0.3, 0.8),
        alpha_mode: cullgraph::scene::AlphaMode::Mask { cutoff: 0.5 },
        ..Default::default()
    });
    let (double_sided, masked) = (double_sided.unwrap(), masked.unwrap());
    let mut culled = renderer(&gpu, &world, "two_phase", true);
    let mut unculled = renderer(&gpu, &world, "no_cull", false);
    let shaders = gpu.shaders();
    let camera = boxes_camera();
    culled.render_to_image(&camera).unwrap();
    // Rounds of each region in turn, each more than its groups' spare slots.
    let kinds = [(tall, double_sided), (0, 2), (tall, masked), (0, 2), (tall, double_sided)];
    for (round, &(mesh, material)) in kinds.iter().enumerate() {
        for k in 0..8 {
            let x = -3.0 + k as f64 * 0.8;
            let z = -1.5 - round as f64 * 0.9;
            let t = Transform { linear: Mat3::from_diagonal(Vec3::splat(0.3)), translation: DVec3::new(x, 0.15, z) };
            world.insert(Instance { transform: t, mesh, material, flags: 0 }).unwrap();
        }
        let stats = culled.sync(shaders, &world).unwrap();
        assert!(!stats.relayout, "round {round}: growth is not a new layout");
        unculled.sync(shaders, &world).unwrap();
        let want = unculled.render_to_image(&camera).unwrap().1;
        // Twice: the second frame's early phase draws the first frame's list.
        for frame in 0..2 {
            let (s, image) = culled.render_to_image(&camera).unwrap();
            assert_eq!(s.verify.as_ref().unwrap().false_negatives, 0, "round {round}, frame {frame}");
            let differ = differing_pixels(&image, &want);
            assert_eq!(differ, 0, "round {round}, frame {frame}: the culled image differs in {differ} pixels");
        }
    }
    gpu.assert_clean();
}

/// An instance inserted right after another was removed does not take over its slot's
/// visibility: the removed instance was visible, the new one is hidden behind a wall, and the
/// early phase (last frame's visible slots) must not draw it.
#[test]
fn a_reused_slot_inherits_no_visibility() {
    let gpu = GpuTest::new();
    let mut scene = boxes_scene();
    // A wall across the view, between the boxes and where the new box goes.
    let wall = Instance {
        transform: Transform {
            linear: Mat3::from_diagonal(Vec3::new(12.0, 6.0, 0.3)),
            translation: DVec3::new(0.0, 3.0, -1.5),
        },
        mesh: 0,
        material: 0,
        flags: 0,
    };
    scene.instances.push(wall);
    let (mut world, handles) = World::new(scene).unwrap();
    let mut r = renderer(&gpu, &world, "two_phase", true);
    let shaders = gpu.shaders();
    let camera = boxes_camera();
    // Two frames: the second's early phase draws what the first saw.
    for _ in 0..2 {
        let s = r.render(&camera).unwrap().verify.unwrap();
        assert_eq!((s.false_negatives, s.false_positives), (0, 0));
    }
    let red_cube = handles[1];
    let old_slot = r.slot_of(red_cube.index()).unwrap();
    world.remove(red_cube).unwrap();
    let hidden = Instance {
        transform: Transform { linear: Mat3::IDENTITY, translation: DVec3::new(0.0, 0.5, -5.0) },
        mesh: 0,
        material: 1,
        flags: 0,
    };
    let new = world.insert(hidden).unwrap();
    r.sync(shaders, &world).unwrap();
    assert_ne!(r.slot_of(new.index()), Some(old_slot), "the freed slot waits a frame");
    let s = r.render(&camera).unwrap().verify.unwrap();
    assert_eq!((s.false_negatives, s.false_positives), (0, 0), "nothing hidden is drawn: {s:?}");
    gpu.assert_clean();
}

/// The cull bound the GPU derives for a moved instance (from its record and its mesh's local
/// bounds, so that a move uploads 64 bytes) contains every vertex of the moved instance, and is
/// not much larger than the one the CPU packs: rotated, scaled and far from the origin.
#[test]
fn moved_instances_get_bounds_that_contain_them() {
    use cullgraph::passes::shared::cull_data::GpuCullRecord;
    let gpu = GpuTest::new();
    let (mut world, handles) = World::new(boxes_scene()).unwrap();
    let mut r = renderer(&gpu, &world, "two_phase", false);
    let shaders = gpu.shaders();
    r.render(&boxes_camera()).unwrap();
    let moves = [
        (
            handles[1],
            Mat3::from_rotation_y(0.7) * Mat3::from_diagonal(Vec3::new(2.0, 0.5, 1.0)),
            DVec3::new(3.0, 1.0, -2.0),
        ),
        (
            handles[2],
            Mat3::from_rotation_x(-1.1) * Mat3::from_diagonal(Vec3::new(1.0, 3.0, 0.2)),
            DVec3::new(1.0e6 + 0.3, 7.0, 2.0e5),
        ),
        (handles[3], Mat3::from_diagonal(Vec3::splat(40.0)), DVec3::new(-3.0e4, 0.0, 12.5)),
    ];
    let changes: Vec<_> = moves.iter().map(|(h, l, t)| (*h, Transform { linear: *l, translation: *t })).collect();
    world.set_transforms(&changes).unwrap();
    let update = r.sync(shaders, &world).unwrap();
    assert_eq!(update.bytes_uploaded, 3 * 72, "moves upload 72 bytes each");
    r.render(&boxes_camera()).unwrap();
    let bytes = cullgraph::gpu::transfer::read_buffer(&gpu, &r.gpu_scene().cull_records).unwrap();
    // The buffer has room to grow past the records.
    let records: &[GpuCullRecord] = bytemuck::cast_slice(&bytes[..bytes.len() / 32 * 32]);
    let scene = world.scene();
    for (h, _, _) in &moves {
        let slot = r.slot_of(h.index()).unwrap() as usize;
        let instance = world.instance(*h).unwrap();
        let (hi, lo, radius, half) = records[slot].unpack();
        assert_eq!(records[slot].group_flags & cullgraph::passes::shared::cull_data::CULL_HUGE, 0, "{h}");
        let center = hi.as_dvec3() + lo.as_dvec3();
        let mesh = &scene.meshes[instance.mesh as usize];
        let vertices = &scene.vertices[mesh.vertex_offset as usize..(mesh.vertex_offset + mesh.vertex_count) as usize];
        for v in vertices {
            let p = instance.transform.apply(Vec3::from_array(v.position));
            assert!(((p - center).abs()).cmple(half.as_dvec3()).all(), "{h}: {p} outside the box {center} ± {half}");
            assert!((p - center).length() <= radius as f64, "{h}: {p} outside the sphere");
        }
        // As tight as the CPU's bound, up to half-float rounding.
        let group = records[slot].group_flags & 0xFF_FFFF;
        let cpu = cullgraph::passes::shared::cull_data::cull_record(scene, instance, group).unpack();
        assert!((half - cpu.3).abs().max_element() <= 1e-2 * cpu.3.max_element().max(1.0), "{h}: {half} vs {}", cpu.3);
    }
    gpu.assert_clean();
}

/// The city's graphs leave out the emissive/occlusion target for a scene without emission or
/// occlusion: a material that brings emission to a live world brings the target back (the
/// graph is compiled again), and the box glows as in a renderer made afresh.
#[test]
fn an_emissive_material_on_a_live_world_brings_its_target_and_glows() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, handles, _) = living_boxes();
    let camera = boxes_camera();
    let mut live = renderer(&gpu, &world, "two_phase", false);
    let before = live.render_to_image(&camera).unwrap().1;
    let glow = Material {
        name: "glow".into(),
        albedo: Vec3::splat(0.05),
        emissive: Vec3::new(0.0, 3.0, 0.0),
        ..Default::default()
    };
    let m = world.add_material(glow).unwrap();
    world.set_materials(&handles.iter().map(|&h| (h, m)).collect::<Vec<_>>()).unwrap();
    live.sync(shaders, &world).unwrap();
    let after = live.render_to_image(&camera).unwrap().1;
    let fresh = renderer(&gpu, &world, "two_phase", false).render_to_image(&camera).unwrap().1;
    assert!(differing_pixels(&after, &fresh) <= DEPTH_TIE_PIXELS);
    // Nothing in the scene was green before; the boxes glow green (their albedo is near black).
    let green = |image: &RgbaImage| image.pixels().filter(|p| p.0[1] as i32 > p.0[0] as i32 + 100).count();
    assert_eq!(green(&before), 0);
    assert!(green(&after) > 100, "{} green pixels", green(&after));
    gpu.assert_clean();
}

/// A long bulk move (checked on several threads) reaches every moved slot's record on the GPU,
/// with the world's last transform of each, and the culling stays exact.
/// The cull decides blocks of 256 slots by bounds made at upload; a world's update marks its
/// slot's block to be tested slot by slot, so a box moved out of a block that lies wholly
/// outside the view is drawn at its new place.
#[test]
fn a_box_moved_out_of_a_block_outside_the_view_is_drawn() {
    let gpu = GpuTest::new();
    let mut scene = boxes_scene();
    let cube = scene.instances[1].mesh;
    let green =
        scene.add_material(Material { name: "green".into(), albedo: Vec3::new(0.1, 0.8, 0.1), ..Default::default() });
    // 2000 small boxes far behind the eye, in a draw group of their own: whole blocks of slots
    // outside the frustum.
    let small = Mat3::from_diagonal(Vec3::splat(0.3));
    let far = |i: usize| Transform {
        linear: small,
        translation: DVec3::new(40.0 + (i % 50) as f64, 0.5, 60.0 + (i / 50) as f64),
    };
    scene.instances.extend((0..2000).map(|i| Instance { transform: far(i), mesh: cube, material: green, flags: 0 }));
    let (mut world, handles) = World::new(scene).unwrap();
    let mut live = renderer(&gpu, &world, "two_phase", true);
    let camera = boxes_camera();
    let (stats, _) = live.render_to_image(&camera).unwrap();
    let late = CullPassStats::of(&stats).into_iter().find(|c| c.pass == "cull_late").unwrap();
    assert!(late.frustum_culled >= 2000, "{late:?}");
    // Five of them, from all over the group's slots, moved in front of the eye.
    let boxes = &handles[handles.len() - 2000..];
    let near = |k: usize| Transform { linear: small, translation: DVec3::new(0.5 + 0.6 * k as f64, 0.3, 2.5) };
    for k in 0..5 {
        world.set_transform(boxes[100 + 400 * k], near(k)).unwrap();
    }
    live.sync(gpu.shaders(), &world).unwrap();
    for frame in 0..2 {
        let (stats, image) = live.render_to_image(&camera).unwrap();
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "frame {frame}: {verify:?}");
        let fresh = renderer(&gpu, &world, "two_phase", false).render_to_image(&camera).unwrap().1;
        assert!(differing_pixels(&image, &fresh) <= DEPTH_TIE_PIXELS, "frame {frame}");
        for k in 0..5 {
            let at = project(&camera, near(k).translation);
            let p = pixel(&image, at.0, at.1);
            assert!(p[1] > 2 * p[0] && p[1] > 2 * p[2], "frame {frame}: moved box {k} at {at:?}: {p:?}");
        }
    }
    gpu.assert_clean();
}

#[test]
fn a_long_bulk_move_reaches_every_slot() {
    use cullgraph::passes::shared::gpu_types::GpuInstance;
    // The scatter's workgroups laid out in rows of 7 (as where maxComputeWorkGroupCount[0] is
    // short of a long list's): every slot is still reached. Results do not depend on the layout,
    // so the other tests of this file may run under it too.
    cullgraph::gpu::line_dispatch::set_width_for_tests(7);
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = boxes_scene();
    let first = scene.instances[1];
    let n = 80_000;
    scene.instances.extend((0..n).map(|i| Instance { transform: small_box(i), ..first }));
    let (mut world, handles) = World::new(scene).unwrap();
    let mut live = renderer(&gpu, &world, "two_phase", true);
    let camera = boxes_camera();
    live.render(&camera).unwrap();
    // Every small box moves twice before one sync: the second move counts.
    let boxes = &handles[handles.len() - n..];
    let shifted = |i: usize, by: DVec3| Transform { translation: small_box(i).translation + by, ..small_box(i) };
    world.set_transforms_by(boxes, |i| shifted(i, DVec3::Y)).unwrap();
    world.set_transforms_by(boxes, |i| shifted(i, DVec3::new(0.5, 0.2, 0.0))).unwrap();
    live.sync(shaders, &world).unwrap();
    let (stats, image) = live.render_to_image(&camera).unwrap();
    assert_eq!(stats.verify.expect("verified").false_negatives, 0);
    let bytes = cullgraph::gpu::transfer::read_buffer(&gpu, &live.gpu_scene().instances).unwrap();
    let records: &[GpuInstance] = bytemuck::cast_slice(&bytes[..live.scene().instances.len() * 64]);
    for (i, &h) in boxes.iter().enumerate() {
        let slot = live.slot_of(h.index()).expect("placed");
        let expected = GpuInstance::new(world.instance(h).unwrap());
        assert_eq!(records[slot as usize], expected, "box {i} in slot {slot}");
    }
    let fresh = renderer(&gpu, &world, "two_phase", false).render_to_image(&camera).unwrap().1;
    assert!(differing_pixels(&image, &fresh) <= DEPTH_TIE_PIXELS);

    // Three syncs before one frame, on the threads that own the slots' queue entries: the
    // first queues whole records (other materials), the second moves every box (those
    // records take the moves) and some twice in one list, the third moves a range again
    // (superseding queued moves) and one it then removes. Every slot ends with its last state.
    // The journal is trimmed to what the renderer applied, as an engine does: one that
    // outgrew its limit would lay the world out anew.
    let sync = |live: &mut Renderer, world: &mut World| {
        let update = live.sync(shaders, world).unwrap();
        assert!(!update.relayout);
        world.trim_journal(live.synced_version().unwrap());
        update.bytes_uploaded
    };
    world.trim_journal(live.synced_version().unwrap());
    let by = |k: f64| DVec3::new(0.0, 0.1 * k, 0.05 * k);
    let red = world.instance(handles[2]).unwrap().material;
    let repainted: Vec<_> = boxes[100..110].iter().map(|&h| (h, red)).collect();
    world.set_materials(&repainted).unwrap();
    let _ = sync(&mut live, &mut world);
    let twice: Vec<InstanceHandle> = boxes.iter().chain(&boxes[..5000]).copied().collect();
    world.set_transforms_by(&twice, |i| if i < n { shifted(i, by(2.0)) } else { shifted(i - n, by(3.0)) }).unwrap();
    let _ = sync(&mut live, &mut world);
    world.set_transforms_by(&boxes[20_000..60_000], |i| shifted(i + 20_000, by(4.0))).unwrap();
    world.remove(boxes[30_000]).unwrap();
    // The moves are written where the GPU reads them, 72 bytes each (those they supersede stay
    // there, dropped); the removed box's slot takes a whole record.
    let bytes = sync(&mut live, &mut world);
    assert!((40_000 * 72..40_000 * 72 + 100).contains(&bytes), "{bytes} bytes");
    let (stats, image) = live.render_to_image(&camera).unwrap();
    assert_eq!(stats.verify.expect("verified").false_negatives, 0);
    let bytes = cullgraph::gpu::transfer::read_buffer(&gpu, &live.gpu_scene().instances).unwrap();
    let records: &[GpuInstance] = bytemuck::cast_slice(&bytes[..live.scene().instances.len() * 64]);
    assert_eq!(live.slot_of(boxes[30_000].index()), None);
    for (i, &h) in boxes.iter().enumerate().filter(|&(i, _)| i != 30_000) {
        let slot = live.slot_of(h.index()).expect("placed");
        let expected = GpuInstance::new(world.instance(h).unwrap());
        assert_eq!(records[slot as usize], expected, "box {i} in slot {slot}, second round");
    }
    let fresh = renderer(&gpu, &world, "two_phase", false).render_to_image(&camera).unwrap().1;
    assert!(differing_pixels(&image, &fresh) <= DEPTH_TIE_PIXELS);
    gpu.assert_clean();
    cullgraph::gpu::line_dispatch::set_width_for_tests(0);
}

/// Small box `i` of a grid behind the boxes scene.
fn small_box(i: usize) -> Transform {
    Transform {
        linear: Mat3::from_diagonal(Vec3::splat(0.05)),
        translation: DVec3::new(-4.0 + 0.03 * (i % 256) as f64, 0.1, -4.0 - 0.03 * (i / 256) as f64),
    }
}
