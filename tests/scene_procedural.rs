//! Procedural generators: determinism, exact instance counts, mesh kinds, occluders, bounds,
//! lights, parameter checks and speed. CPU only.

use cullgraph::scene::procedural::{self, city, field};
use cullgraph::scene::source::{LoadOptions, SceneSource};
use cullgraph::scene::validate::validate_scene;
use cullgraph::scene::{Scene, SceneError, FLAG_OCCLUDER};
use glam::DVec3;
use std::collections::{HashMap, HashSet};
use std::time::Instant;

fn options(instances: Option<usize>, kinds: Option<usize>, seed: u64) -> LoadOptions {
    LoadOptions { instances, kinds, lights: None, seed }
}

fn gen(name: &str, options: &LoadOptions) -> Scene {
    let scene = procedural::generate(name, options).unwrap_or_else(|e| panic!("{name}: {e}"));
    validate_scene(&scene).unwrap_or_else(|e| panic!("{name}: {e}"));
    scene
}

/// Everything that defines a scene, for equality checks.
fn fingerprint(s: &Scene) -> (usize, Vec<u8>, Vec<u32>, String) {
    let instances = format!("{:?}{:?}{:?}{:?}", s.instances, s.meshes, s.materials, s.lights);
    (s.instances.len(), bytemuck::cast_slice(&s.vertices).to_vec(), s.indices.clone(), instances)
}

#[test]
fn generators_are_deterministic() {
    for name in ["builtin:city", "builtin:field"] {
        let a = gen(name, &options(Some(3000), None, 7));
        let b = gen(name, &options(Some(3000), None, 7));
        assert!(fingerprint(&a) == fingerprint(&b), "{name}: same seed, different scenes");
        assert_eq!(a.camera, b.camera);
        let c = gen(name, &options(Some(3000), None, 8));
        assert!(a.instances != c.instances, "{name}: different seeds, same instances");
    }
}

#[test]
fn city_instance_counts_are_exact() {
    for n in [1, 2, 3, 41, 1000, 10_000, 12_345] {
        let scene = gen("builtin:city", &options(Some(n), None, 1));
        assert_eq!(scene.instances.len(), n, "instances = {n}");
    }
    assert_eq!(gen("city", &LoadOptions::default()).instances.len(), city::DEFAULT_INSTANCES);
}

#[test]
fn city_uses_many_mesh_kinds_and_shares_them() {
    let scene = gen("builtin:city", &options(Some(10_000), None, 1));
    let used: HashSet<u32> = scene.instances.iter().map(|i| i.mesh).collect();
    assert!(used.len() >= 16, "only {} mesh kinds used", used.len());
    assert_eq!(used.len(), scene.meshes.len(), "every city mesh is used at 10k instances");
    // Prop kinds (not ground, sidewalk/box or buildings) alone number at least 16.
    let props =
        scene.meshes.iter().filter(|m| !m.name.contains("building") && m.name != "city/ground" && m.name != "city/box");
    assert!(props.count() >= 16);
    // Meshes stay few: instances share them.
    assert!(scene.meshes.len() < 64);
    let materials: HashSet<u32> =
        scene.instances.iter().filter(|i| i.flags & FLAG_OCCLUDER != 0).map(|i| i.material).collect();
    assert!(materials.len() >= 4, "buildings use {} colors", materials.len());
}

#[test]
fn city_buildings_are_occluders() {
    let scene = gen("builtin:city", &options(Some(10_000), None, 3));
    let occluders: Vec<_> = scene.instances.iter().filter(|i| i.flags & FLAG_OCCLUDER != 0).collect();
    let blocks =
        scene.instances.iter().filter(|i| scene.meshes[i.mesh as usize].name == "city/box" && i.flags == 0).count();
    assert!(occluders.len() >= blocks, "{} occluders for {blocks} blocks", occluders.len());
    for inst in &occluders {
        assert!(
            scene.meshes[inst.mesh as usize].name.starts_with("city/b"),
            "{}",
            scene.meshes[inst.mesh as usize].name
        );
        let (min, max) = scene.instance_bounds(inst);
        let size = max - min;
        assert!(size.y >= 8.0 && size.x >= 10.0 && size.z >= 10.0, "building {size}");
    }
    // Nothing that is not a building is flagged.
    assert!(scene
        .instances
        .iter()
        .filter(|i| !scene.meshes[i.mesh as usize].name.contains("building")
            && scene.meshes[i.mesh as usize].name != "city/box")
        .all(|i| i.flags & FLAG_OCCLUDER == 0));
}

/// Whether the segment `a..b` passes through the box `min..max` (slab test).
fn segment_hits_box(a: DVec3, b: DVec3, min: DVec3, max: DVec3) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if a[k] < min[k] || a[k] > max[k] {
                return false;
            }
        } else {
            let (mut u, mut v) = ((min[k] - a[k]) / d[k], (max[k] - a[k]) / d[k]);
            if u > v {
                std::mem::swap(&mut u, &mut v);
            }
            t0 = t0.max(u);
            t1 = t1.min(v);
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

#[test]
fn street_camera_sees_a_street_and_buildings_hide_most_of_the_city() {
    let scene = gen("builtin:city", &options(Some(10_000), None, 1));
    let camera = scene.camera.clone().expect("the city suggests a camera");
    camera.validate().unwrap();
    assert!(camera.eye.y > 1.0 && camera.eye.y < 3.0, "eye at {}", camera.eye);
    let occluders: Vec<(DVec3, DVec3)> =
        scene.instances.iter().filter(|i| i.flags & FLAG_OCCLUDER != 0).map(|i| scene.instance_bounds(i)).collect();
    // The eye stands in the open, not inside a building.
    assert!(!occluders.iter().any(|(min, max)| camera.eye.cmpge(*min).all() && camera.eye.cmple(*max).all()));
    // Most instances' centres are behind some building as seen from the eye.
    let mut hidden = 0;
    let mut total = 0;
    for inst in scene.instances.iter().skip(1).step_by(7) {
        if inst.flags & FLAG_OCCLUDER != 0 {
            continue;
        }
        let (min, max) = scene.instance_bounds(inst);
        let center = (min + max) * 0.5;
        total += 1;
        if occluders.iter().any(|(lo, hi)| segment_hits_box(camera.eye, center, *lo, *hi)) {
            hidden += 1;
        }
    }
    assert!(hidden * 10 >= total * 7, "only {hidden} of {total} sampled instances are hidden from the street camera");
}

#[test]
fn city_bounds_scale_with_the_instance_count() {
    // Bounds of everything but the ground plane (instance 0, which has a margin).
    let city_bounds = |n: usize| {
        let scene = gen("builtin:city", &options(Some(n), None, 1));
        assert_eq!(scene.meshes[scene.instances[0].mesh as usize].name, "city/ground");
        let all = scene.world_bounds().unwrap();
        assert!(all.0.is_finite() && all.1.is_finite());
        scene.instances[1..]
            .iter()
            .map(|i| scene.instance_bounds(i))
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
            .unwrap()
    };
    let small = city_bounds(1000);
    let large = city_bounds(100_000);
    for (min, max) in [small, large] {
        assert!(min.y >= -1.0 && max.y <= 260.0, "{min} {max}");
    }
    let width = |b: (DVec3, DVec3)| (b.1 - b.0).x;
    // A hundred times the instances over a hundred times the area: ten times the width.
    let ratio = width(large) / width(small);
    assert!((9.0..=11.5).contains(&ratio), "width ratio {ratio}");
    // Density: about 40 instances per block of BLOCK + STREET meters.
    let per_block = 100_000.0 / (width(large) / (city::BLOCK + city::STREET)).powi(2);
    assert!(per_block > 30.0 && per_block < 50.0, "{per_block} per block");
}

#[test]
fn city_lights_sit_at_street_lamps() {
    let scene = gen("builtin:city", &options(Some(10_000), None, 1));
    assert_eq!(scene.lights.len(), city::DEFAULT_LIGHTS);
    let lamps: Vec<DVec3> = scene
        .instances
        .iter()
        .filter(|i| scene.meshes[i.mesh as usize].name == "city/lamp_post")
        .map(|i| i.transform.translation)
        .collect();
    assert!(lamps.len() > 100);
    for light in &scene.lights {
        assert!(light.position.y > 4.0 && light.position.y < 7.0, "{}", light.position);
        let nearest =
            lamps.iter().map(|p| (p.x - light.position.x).hypot(p.z - light.position.z)).fold(f64::MAX, f64::min);
        assert!(nearest < 1.5, "light {} is {nearest} m from the nearest lamp", light.position);
        assert!(light.color.x > light.color.z, "lamp light should be warm: {}", light.color);
    }
    let none = gen("builtin:city", &LoadOptions { lights: Some(0), ..options(Some(1000), None, 1) });
    assert!(none.lights.is_empty());
    // More lights than lamps: topped up over the city.
    let many = gen("builtin:city", &LoadOptions { lights: Some(500), ..options(Some(1000), None, 1) });
    assert_eq!(many.lights.len(), 500);
    // The sun is kept.
    assert_eq!(scene.sun, Default::default());
}

#[test]
fn city_of_a_million_instances_is_fast() {
    let start = Instant::now();
    let scene = procedural::generate("builtin:city", &options(Some(1_000_000), None, 1)).unwrap();
    let elapsed = start.elapsed();
    assert_eq!(scene.instances.len(), 1_000_000);
    validate_scene(&scene).unwrap();
    eprintln!("builtin:city with 10^6 instances: {elapsed:?} ({} meshes)", scene.meshes.len());
    // Debug build of this crate; a release build is several times faster.
    assert!(elapsed.as_secs_f64() < 10.0, "took {elapsed:?}");
}

#[test]
fn field_counts_and_kinds() {
    let scene = gen("builtin:field", &LoadOptions::default());
    assert_eq!(scene.instances.len(), field::DEFAULT_INSTANCES);
    assert_eq!(scene.meshes.len(), field::DEFAULT_KINDS);
    let scene = gen("builtin:field", &options(Some(4321), Some(1000), 5));
    assert_eq!(scene.instances.len(), 4321);
    assert_eq!(scene.meshes.len(), 1000);
    // Every kind is used and every kind is a different mesh.
    let used: HashSet<u32> = scene.instances.iter().map(|i| i.mesh).collect();
    assert_eq!(used.len(), 1000);
    let mut seen = HashMap::new();
    for (k, m) in scene.meshes.iter().enumerate() {
        let vertices = &scene.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize];
        let key: Vec<u8> = bytemuck::cast_slice(vertices).to_vec();
        if let Some(other) = seen.insert(key, k) {
            panic!("kinds {other} and {k} are the same mesh");
        }
    }
    // Mirrored instances (negative determinant) are among them, and some are tilted.
    let mirrored = scene.instances.iter().filter(|i| i.transform.linear.determinant() < 0.0).count();
    assert!((4321 / 60..=4321 / 40).contains(&mirrored), "{mirrored} mirrored");
    let tilted = scene.instances.iter().filter(|i| (i.transform.linear.y_axis.normalize().y) < 0.99).count();
    assert!(tilted > 4321 / 10);
    let (min, max) = scene.world_bounds().unwrap();
    assert!(min.is_finite() && max.is_finite() && (max - min).x > 100.0 && (max - min).x < 1000.0);
    assert_eq!(scene.lights.len(), field::DEFAULT_LIGHTS);
}

#[test]
fn field_supports_many_kinds() {
    let start = Instant::now();
    let scene = gen("builtin:field", &options(Some(20_000), Some(10_000), 2));
    assert_eq!(scene.meshes.len(), 10_000);
    let families: HashSet<&str> = scene.meshes.iter().map(|m| m.name.split('#').next().unwrap()).collect();
    assert_eq!(families.len(), field::FAMILIES);
    eprintln!("builtin:field with 10^4 kinds: {:?}, {} triangles", start.elapsed(), scene.indices.len() / 3);
}

#[test]
fn absurd_parameters_are_refused_by_name() {
    let cases: [(&str, LoadOptions, &str); 10] = [
        ("city", options(Some(0), None, 1), "instances = 0"),
        ("city", options(Some(procedural::MAX_INSTANCES + 1), None, 1), "instances = 2147483648"),
        ("field", options(Some(0), None, 1), "instances = 0"),
        ("field", options(None, Some(0), 1), "kinds = 0"),
        ("field", options(None, Some(100_001), 1), "kinds = 100001"),
        ("field", options(Some(usize::MAX), None, 1), "instances"),
        ("city", LoadOptions { lights: Some(usize::MAX), ..Default::default() }, "lights"),
        ("crowd", options(Some(0), None, 1), "instances = 0"),
        ("crowd", options(Some(100_001), None, 1), "instances = 100001"),
        ("crowd", LoadOptions { lights: Some(usize::MAX), ..Default::default() }, "lights"),
    ];
    for (name, opts, fragment) in cases {
        match procedural::generate(name, &opts) {
            Err(SceneError::Builtin(m)) => {
                assert!(m.contains(fragment) && m.contains(&format!("builtin:{name}")), "{m}")
            }
            other => panic!("{name} {opts:?}: expected a Builtin error, got {other:?}"),
        }
    }
    let e = procedural::generate("x", &LoadOptions::default()).unwrap_err().to_string();
    assert_eq!(
        e,
        "unknown built-in scene 'builtin:x'; available: builtin:city, builtin:field, builtin:crowd, builtin:dense"
    );
}

#[test]
fn scene_source_loads_builtins_end_to_end() {
    let source: SceneSource = "builtin:city".parse().unwrap();
    let scene = source.load(&options(Some(2000), None, 9)).unwrap();
    assert_eq!(scene.instances.len(), 2000);
    let source: SceneSource = "builtin:field".parse().unwrap();
    assert_eq!(source.load(&options(Some(300), Some(30), 9)).unwrap().meshes.len(), 30);
    let source: SceneSource = "builtin:nothing".parse().unwrap();
    assert!(source.load(&LoadOptions::default()).is_err());
}
