//! Per-instance user data: a world declares words per instance, sets them like transforms, and
//! the GPU holds them per slot, where a graph's shaders read them (`graph/examples/user_tint.ron`
//! tints each pixel by its instance's word). The words follow their instance through moves to
//! other slots, growth and registrations, and bad input is refused naming the handle.

mod common;

use common::{boxes_camera, boxes_scene, cube_mesh, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer, ViewId};
use cullgraph::scene::world::{World, MAX_USER_WORDS};
use cullgraph::scene::{Instance, Transform};
use glam::{DVec3, Mat3, Vec3};

const SIZE: (u32, u32) = (64, 48);

fn tint_spec() -> GraphSpec {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples/user_tint.ron");
    GraphSpec::from_file(path.as_ref()).unwrap()
}

/// RGBA8 packed as `unpackUnorm4x8` reads it (red in the low byte).
fn pack(rgba: [u8; 4]) -> u32 {
    u32::from_le_bytes(rgba)
}

/// Renders a frame of `world` and checks every pixel of `tinted` against `color` times the
/// tint of the instance `object_id` names there (the background untinted); returns the pixels
/// of each tint seen.
fn check_tints(r: &mut Renderer, world: &World) -> std::collections::BTreeMap<u32, usize> {
    let (_, tinted) = r.render_to_rgba8(&boxes_camera()).unwrap();
    let color = r.read_output_f32("color").unwrap();
    let mut seen = std::collections::BTreeMap::new();
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let tint = match r.pick_handle(ViewId::MAIN, x, y).unwrap() {
                Some(handle) => world.user_data(handle).unwrap()[0],
                None => pack([255; 4]),
            };
            *seen.entry(tint).or_insert(0) += 1;
            let t = tint.to_le_bytes();
            for c in 0..3 {
                let i = ((y * SIZE.0 + x) * 4) as usize + c;
                let want = color.data[i] * t[c] as f32 / 255.0 * 255.0;
                let got = tinted[i] as f32;
                assert!((got - want).abs() <= 1.0, "pixel ({x}, {y}) channel {c}: {got}, want {want} (tint {t:?})");
            }
        }
    }
    seen
}

#[test]
fn shaders_read_each_instances_words_wherever_its_slot_goes() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (mut world, handles) = World::with_user_data(boxes_scene(), 1).unwrap();
    assert_eq!(world.user_data(handles[1]).unwrap(), [0], "words start at zero");
    let (white, red, green, blue) =
        (pack([255; 4]), pack([255, 0, 0, 255]), pack([0, 255, 0, 255]), pack([0, 0, 255, 255]));
    let tints = [white, green, red, blue];
    let changes: Vec<_> = handles.iter().zip(&tints).map(|(h, t)| (*h, std::slice::from_ref(t))).collect();
    world.set_user_data(&changes).unwrap();
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(SIZE.0, SIZE.1), &tint_spec()).unwrap();
    r.render(&boxes_camera()).unwrap();
    let seen = check_tints(&mut r, &world);
    assert!(tints.iter().all(|t| seen.get(t).is_some_and(|&n| n > 10)), "every tint shows: {seen:?}");

    // New words for one instance (the red box turns blue): only they are uploaded.
    world.set_user_data(&[(handles[2], &[blue][..])]).unwrap();
    let stats = r.sync(shaders, &world).unwrap();
    assert_eq!(stats.bytes_uploaded, 8, "one slot and its word");
    let seen = check_tints(&mut r, &world);
    assert!(!seen.contains_key(&red), "the red tint is gone: {seen:?}");

    // An instance of a newly registered mesh (a new group: a new slot range) keeps its words,
    // and an instance that changes mesh takes them to its new slot.
    let cube = world.add_mesh("another cube", &cube_mesh()).unwrap();
    let at = Transform { linear: Mat3::from_diagonal(Vec3::splat(0.7)), translation: DVec3::new(0.2, 0.35, -1.0) };
    let new = world.insert(Instance { transform: at, mesh: cube, material: 1, flags: 0 }).unwrap();
    let yellow = pack([255, 255, 0, 255]);
    world.set_user_data(&[(new, &[yellow][..])]).unwrap();
    let before = r.slot_of(handles[2].index()).unwrap();
    world.set_meshes(&[(handles[2], cube)]).unwrap();
    r.sync(shaders, &world).unwrap();
    assert_ne!(r.slot_of(handles[2].index()), Some(before), "the blue box moved to another slot");
    let seen = check_tints(&mut r, &world);
    assert!(seen.get(&yellow).is_some_and(|&n| n > 10), "the new instance shows its tint: {seen:?}");
    assert!(seen.get(&blue).is_some_and(|&n| n > 10), "the re-meshed box keeps its tint: {seen:?}");
    gpu.assert_clean();
}

#[test]
fn bad_user_data_is_refused_naming_the_handle() {
    let too_many = World::with_user_data(boxes_scene(), MAX_USER_WORDS + 1).unwrap_err().to_string();
    assert!(too_many.contains("17 words an instance; at most 16"), "{too_many}");
    let (mut world, handles) = World::with_user_data(boxes_scene(), 2).unwrap();
    let e = world.set_user_data(&[(handles[0], &[1, 2][..]), (handles[1], &[1][..])]).unwrap_err().to_string();
    assert!(e.contains(&handles[1].to_string()) && e.contains("user data of 1 words; the world declares 2"), "{e}");
    assert_eq!(world.user_data(handles[0]).unwrap(), [0, 0], "nothing applied");
    let (other, other_handles) = World::with_user_data(boxes_scene(), 2).unwrap();
    let e = world.set_user_data(&[(other_handles[0], &[1, 2][..])]).unwrap_err().to_string();
    assert!(e.contains(&format!("world {}", other.id())), "{e}");
    world.remove(handles[3]).unwrap();
    assert!(world.user_data(handles[3]).is_err(), "a removed instance's words are gone");
    let version = world.version();
    assert!(world.set_user_data(&[(handles[3], &[1, 2][..])]).is_err());
    assert_eq!(world.version(), version, "nothing recorded");
}
