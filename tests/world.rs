//! The living world on the CPU: persistent handles, stale handles refused, bad values refused
//! with the handle named and nothing changed, bulk changes all or nothing, and a journal that
//! replays to the same world.

use cullgraph::scene::world::{Change, InstanceHandle, World, WorldError};
use cullgraph::scene::{Instance, Material, MeshData, PointLight, Scene, Transform};
use glam::{DVec3, Mat3, Vec3};
use proptest::prelude::*;
use std::collections::BTreeMap;

fn cube() -> MeshData {
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    MeshData {
        positions: p.iter().map(|v| Vec3::from_array(*v)).collect(),
        normals: vec![],
        indices: vec![
            0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5,
        ],
        ..Default::default()
    }
}

fn at(x: f64) -> Transform {
    Transform { linear: Mat3::IDENTITY, translation: DVec3::new(x, 0.0, 0.0) }
}

/// A world of `n` cubes in a row, one material.
fn world(n: usize) -> (World, Vec<InstanceHandle>) {
    let mut scene = Scene::default();
    let mesh = scene.add_mesh("cube", &cube(), "cube").unwrap();
    let material = scene.add_material(Material::default());
    for i in 0..n {
        scene.instances.push(Instance { transform: at(i as f64 * 2.0), mesh, material, flags: 0 });
    }
    World::new(scene).unwrap()
}

#[test]
fn removed_handles_are_stale_and_their_index_is_reused_with_a_new_generation() {
    let (mut w, h) = world(3);
    let removed = w.remove(h[1]).unwrap();
    assert_eq!(removed.transform, at(2.0));
    let stale = w.set_transform(h[1], at(5.0)).unwrap_err();
    assert_eq!(stale, WorldError::Stale { handle: "instance #1 (generation 0)".into() });
    assert_eq!(stale.to_string(), "instance #1 (generation 0): stale handle (removed)");
    assert!(w.remove(h[1]).is_err(), "removed twice");
    let again = w.insert(Instance { transform: at(9.0), mesh: 0, material: 0, flags: 0 }).unwrap();
    assert_eq!((again.index(), again.generation()), (1, 1), "the freed index, one generation on");
    assert!(w.instance(h[1]).is_err(), "the old handle does not reach the new instance");
    assert_eq!(w.instance(again).unwrap().transform, at(9.0));
    assert_eq!(w.live_instances(), 3);
    assert_eq!(w.instance_slots(), 3);
}

/// Bulk moves read the engine's own layout (here positions apart from rotations), are checked on
/// several threads when the list is long, name the first bad handle in list order whichever
/// thread finds it, and move nothing then.
#[test]
fn bulk_moves_read_any_layout_and_refuse_the_first_bad_handle_in_order() {
    let n = 200_000;
    let (mut w, h) = world(n);
    let xs: Vec<f64> = (0..n).map(|i| i as f64 * 3.0).collect();
    let turn = Mat3::from_rotation_y(0.5);
    let version = w.version();
    let removed = h[n - 10];
    w.remove(removed).unwrap();
    let version_removed = w.version();
    // A stale handle late in the list and a NaN earlier, in another thread's share: the NaN is
    // reported.
    let mut handles = h.clone();
    handles.swap(n - 10, n - 1);
    let bad_at = 150_000;
    let transform_of = |i: usize| Transform {
        linear: turn,
        translation: DVec3::new(if i == bad_at { f64::NAN } else { xs[i] }, 1.0, 0.0),
    };
    let e = w.set_transforms_by(&handles, transform_of).unwrap_err();
    assert!(e.to_string().starts_with(&format!("{}: translation", handles[bad_at])), "{e}");
    assert_eq!(w.version(), version_removed, "nothing was recorded");
    assert_eq!(w.instance(h[bad_at - 1]).unwrap().transform, at((bad_at - 1) as f64 * 2.0), "nothing moved");
    // Without the NaN the stale handle is refused, by name.
    let e = w.set_transforms_by(&handles, |i| Transform { linear: turn, translation: DVec3::new(xs[i], 1.0, 0.0) });
    assert_eq!(e.unwrap_err(), WorldError::Stale { handle: removed.to_string() });
    // Without it, everything moves, each listed once in the journal.
    let live: Vec<InstanceHandle> = h.iter().copied().filter(|&x| x != removed).collect();
    w.set_transforms_by(&live, |i| Transform {
        linear: turn,
        translation: DVec3::new(live[i].index() as f64 * 3.0, 1.0, 0.0),
    })
    .unwrap();
    for &handle in [live[0], live[n / 2], live[n - 2]].iter() {
        let t = w.instance(handle).unwrap().transform;
        assert_eq!((t.linear, t.translation), (turn, DVec3::new(handle.index() as f64 * 3.0, 1.0, 0.0)));
    }
    assert_eq!(w.version(), version_removed + live.len() as u64);
    assert!(version < version_removed);
    // A handle listed twice takes its last transform, in a short list and in a long one (whose
    // moves are applied on several threads).
    w.set_transforms_by(&[live[3], live[3]], |i| at(100.0 + i as f64)).unwrap();
    assert_eq!(w.instance(live[3]).unwrap().transform, at(101.0));
    let twice: Vec<InstanceHandle> = live.iter().chain(&live[..5000]).copied().collect();
    let before = w.version();
    w.set_transforms_by(&twice, |i| at(i as f64)).unwrap();
    assert_eq!(w.version(), before + twice.len() as u64, "every listed move is in the journal");
    assert_eq!(w.instance(live[10]).unwrap().transform, at((live.len() + 10) as f64), "the later move");
    assert_eq!(w.instance(live[7000]).unwrap().transform, at(7000.0), "listed once");
}

#[test]
fn bad_values_name_the_handle_and_change_nothing() {
    let (mut w, h) = world(2);
    let version = w.version();
    let nan = Transform { linear: Mat3::IDENTITY, translation: DVec3::new(f64::NAN, 0.0, 0.0) };
    let far = at(1e16);
    let e = w.set_transforms(&[(h[0], at(7.0)), (h[1], nan)]).unwrap_err();
    assert!(e.to_string().starts_with("instance #1 (generation 0): translation"), "{e}");
    assert_eq!(w.instance(h[0]).unwrap().transform, at(0.0), "bulk changes are all or nothing");
    assert!(w.set_transform(h[0], far).unwrap_err().to_string().contains("beyond"));
    let e = w.set_meshes(&[(h[0], 7)]).unwrap_err();
    assert_eq!(e, WorldError::UnknownMesh { handle: "instance #0 (generation 0)".into(), mesh: 7, meshes: 1 });
    assert!(matches!(w.set_materials(&[(h[1], 3)]), Err(WorldError::UnknownMaterial { material: 3, .. })));
    assert!(w.set_flags(&[(h[1], 1 << 6)]).unwrap_err().to_string().contains("more than 6 bits"));
    let mut bad_light = PointLight::point(DVec3::ZERO, Vec3::ONE, 0.0);
    assert!(w.insert_light(bad_light).unwrap_err().to_string().contains("range 0"));
    bad_light.range = 1.0;
    bad_light.color = Vec3::NAN;
    assert!(w.insert_light(bad_light).is_err());
    assert_eq!(w.version(), version, "nothing was recorded");
}

#[test]
fn meshes_and_materials_in_use_are_not_unregistered() {
    let (mut w, h) = world(2);
    let e = w.remove_mesh(0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "mesh 0 'cube' is used by 2 instance(s), the first instance #0 (generation 0); remove or re-mesh them first"
    );
    let other = w.add_mesh("other", &cube()).unwrap();
    w.set_meshes(&[(h[0], other), (h[1], other)]).unwrap();
    w.remove_mesh(0).unwrap();
    assert!(matches!(w.set_meshes(&[(h[0], 0)]), Err(WorldError::UnknownMesh { mesh: 0, .. })));
    let red = w.add_material(Material { name: "red".into(), albedo: Vec3::X, ..Default::default() }).unwrap();
    assert!(w.remove_material(0).is_err());
    w.set_materials(&[(h[0], red), (h[1], red)]).unwrap();
    w.remove_material(0).unwrap();
    assert!(w.add_material(Material { albedo: Vec3::NEG_ONE, ..Default::default() }).is_err());
}

#[test]
fn the_journal_lists_each_change_and_is_trimmed_to_what_consumers_need() {
    let (mut w, h) = world(2);
    assert_eq!(w.version(), 0);
    w.set_transform(h[1], at(3.0)).unwrap();
    let light = w.insert_light(PointLight::point(DVec3::Y, Vec3::ONE, 5.0)).unwrap();
    w.remove(h[0]).unwrap();
    assert_eq!(w.changes_since(0).unwrap(), [Change::Transform(1), Change::Light(light.index()), Change::Instance(0)]);
    assert_eq!(w.changes_since(2).unwrap(), [Change::Instance(0)]);
    w.trim_journal(2);
    assert_eq!(w.changes_since(2).unwrap(), [Change::Instance(0)]);
    assert!(w.changes_since(1).is_none(), "trimmed: the consumer reloads everything");
    assert_eq!(w.changes_since(3).unwrap(), []);
}

/// One operation of a random sequence.
#[derive(Clone, Debug)]
enum Op {
    Insert(f64),
    Remove(usize),
    Move(usize, f64),
    /// Uses a handle that was removed (if any).
    Stale(usize),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        (-100.0..100.0f64).prop_map(Op::Insert),
        any::<usize>().prop_map(Op::Remove),
        (any::<usize>(), -100.0..100.0f64).prop_map(|(i, x)| Op::Move(i, x)),
        any::<usize>().prop_map(Op::Stale),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Against a model (a map from live handles to positions): live handles reach their own
    /// instance, removed ones are stale forever, and replaying the journal's changes onto a
    /// snapshot gives the same instances as the world.
    #[test]
    fn random_edits_match_a_model(ops in proptest::collection::vec(op(), 1..60)) {
        let (mut w, handles) = world(4);
        let mut model: BTreeMap<InstanceHandle, f64> = handles.iter().enumerate().map(|(i, h)| (*h, i as f64 * 2.0)).collect();
        let mut removed: Vec<InstanceHandle> = Vec::new();
        let snapshot = w.scene().instances.clone();
        for op in ops {
            match op {
                Op::Insert(x) => {
                    let h = w.insert(Instance { transform: at(x), mesh: 0, material: 0, flags: 0 }).unwrap();
                    prop_assert!(!model.contains_key(&h) && !removed.contains(&h), "a handle is never given twice");
                    model.insert(h, x);
                }
                Op::Remove(i) if !model.is_empty() => {
                    let h = *model.keys().nth(i % model.len()).unwrap();
                    w.remove(h).unwrap();
                    model.remove(&h);
                    removed.push(h);
                }
                Op::Move(i, x) if !model.is_empty() => {
                    let h = *model.keys().nth(i % model.len()).unwrap();
                    w.set_transform(h, at(x)).unwrap();
                    model.insert(h, x);
                }
                Op::Stale(i) if !removed.is_empty() => {
                    let h = removed[i % removed.len()];
                    prop_assert!(w.set_transform(h, at(0.0)).is_err());
                    prop_assert!(w.remove(h).is_err());
                }
                _ => {}
            }
        }
        prop_assert_eq!(w.live_instances(), model.len());
        for (h, x) in &model {
            prop_assert_eq!(w.instance(*h).unwrap().transform, at(*x));
        }
        let live: Vec<InstanceHandle> = w.handles().collect();
        prop_assert_eq!(live, model.keys().copied().collect::<Vec<_>>());
        // Replaying: every changed index takes the world's current entry.
        let mut replayed = snapshot;
        for change in w.changes_since(0).unwrap() {
            if let Change::Instance(i) | Change::Transform(i) = change {
                let i = *i as usize;
                if i >= replayed.len() { replayed.resize(i + 1, w.scene().instances[i]); }
                replayed[i] = w.scene().instances[i];
            }
        }
        prop_assert_eq!(&replayed, &w.scene().instances);
    }
}

/// City traffic: the same seed gives the same traffic; vehicles stay on the streets' lanes,
/// leave at the edge and are replaced, so their number holds, and the churn really inserts and
/// removes.
#[test]
fn city_traffic_drives_on_the_streets_deterministically() {
    use cullgraph::scene::procedural::city::{grid, BLOCK, PITCH, STREET};
    use cullgraph::scene::procedural::traffic::Traffic;
    use cullgraph::scene::source::LoadOptions;
    use cullgraph::scene::SceneSource;
    let n = 4000;
    let city =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(n), ..Default::default() }).unwrap();
    let run = || {
        let (mut world, _) = World::new(city.clone()).unwrap();
        let mut traffic = Traffic::new(&mut world, n, 60, 10.0, 7).unwrap();
        for _ in 0..200 {
            traffic.step(&mut world, 0.1).unwrap();
        }
        assert_eq!(traffic.len(), 60);
        world
    };
    let (a, b) = (run(), run());
    assert_eq!(a.scene().instances, b.scene().instances, "same seed, same traffic");
    // Replaced vehicles reuse the indices of those that left, one generation on.
    assert_eq!(a.instance_slots(), n + 60);
    assert!(a.handles().filter(|h| h.generation() > 0).count() > 30, "vehicles left and were replaced");
    let (origin, _) = grid(n);
    // In a street: the coordinate across the street lies past a block, within the street.
    let in_street = |v: f64, o: f64| {
        let r = (v - o).rem_euclid(PITCH);
        r > BLOCK && r < BLOCK + STREET
    };
    for h in a.handles().filter(|h| h.index() as usize >= n) {
        let t = a.instance(h).unwrap().transform.translation;
        assert!(in_street(t.x, origin.x) || in_street(t.z, origin.z), "{h} at {t} is off the streets");
    }
}

/// A journal nobody trims stays bounded; a consumer left behind is told to reload everything.
#[test]
fn an_untrimmed_journal_stays_bounded() {
    let (mut w, h) = world(2);
    let limit = w.journal_limit();
    for k in 0..(3 * limit) {
        w.set_transform(h[k % 2], at(k as f64 * 1e-3)).unwrap();
    }
    assert_eq!(w.version(), 3 * limit as u64);
    assert!(w.changes_since(w.version() - (limit / 2) as u64).is_some(), "recent changes are kept");
    assert!(w.changes_since(0).is_none(), "a consumer at version 0 reloads everything");
    assert!(w.changes_since(w.version() - limit as u64 - 1).is_none());
}
