//! Skinned, morphed and animated glTF: a generated file (a bar of two segments on a chain of
//! three joints, one morph target, a clip that bends the bar, morphs it and moves a rigid node)
//! is imported, posed and deformed on the CPU; broken variants give errors naming their place.

use cullgraph::scene::animation::Property;
use cullgraph::scene::gltf_import::{self, ImportReport};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{InstancePose, Scene, SceneError};
use glam::{DVec3, Mat3, Vec3, Vec4};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// One buffer with one buffer view per accessor, so that a test can change an accessor's bytes.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Adds an accessor of `count` elements of `kind` with `component` type over `data`;
    /// returns its index (also its buffer view's).
    fn add(&mut self, data: Vec<u8>, component: u32, count: usize, kind: &str, extra: Value) -> usize {
        let offset = self.bytes.len();
        self.views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()}));
        self.bytes.extend(&data);
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut accessor =
            json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind});
        if let (Some(a), Some(e)) = (accessor.as_object_mut(), extra.as_object()) {
            a.extend(e.clone());
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn floats(&mut self, values: &[f32], kind: &str, width: usize) -> usize {
        let data = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.add(data, 5126, values.len() / width, kind, json!({}))
    }

    /// The byte offset of accessor `a`'s data.
    fn offset(&self, a: usize) -> usize {
        self.views[a]["byteOffset"].as_u64().unwrap() as usize
    }
}

const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// The test file: its document and its buffer, and the accessors tests change.
struct Doc {
    json: Value,
    bin: Bin,
    times: usize,
}

/// Nodes: 0 'bar' (skinned, morphed, translated by (100, 0, 0), which skinning ignores),
/// 1..3 the joints (1 at the origin under 4, 2 and 3 a step along +x each), 4 'armature' at
/// z = -3, 5 'mover' (a rigid triangle, animated), 6 'still' (a triangle, not animated).
///
/// The bar's vertices: (x, y, 0) for x in 0, 1, 2 and y in 0, 1 (vertex 2x + y). x = 0 is on
/// joint 0, x = 1 half on joint 0 and half on joint 1, (2, 0) on joint 1, and (2, 1) has five
/// influences over JOINTS_0 and JOINTS_1 (1: 0.5, 0: 0.1, 0: 0.1, 0: 0.1 and 1: 0.2). Its morph
/// target lifts each vertex by its x along z; the mesh's default weight is 0.5.
///
/// Clip 'wave' (1 s): joint 1 turns from 0 to 90 degrees about z (LINEAR), the bar's weight
/// goes 0 to 1 (CUBICSPLINE, out-tangent 1 at the start), 'mover' translates (0,0,0) to
/// (2,0,0) (LINEAR) and scales 1 then 2 from 0.5 s (STEP).
fn skinned_doc() -> Doc {
    let mut bin = Bin::default();
    let positions: Vec<f32> = (0..3).flat_map(|x| (0..2).flat_map(move |y| [x as f32, y as f32, 0.0])).collect();
    let position = bin.add(
        positions.iter().flat_map(|v| v.to_le_bytes()).collect(),
        5126,
        6,
        "VEC3",
        json!({"min": [0.0, 0.0, 0.0], "max": [2.0, 1.0, 0.0]}),
    );
    let indices: Vec<u8> = [0u16, 2, 1, 1, 2, 3, 2, 4, 3, 3, 4, 5].iter().flat_map(|i| i.to_le_bytes()).collect();
    let index = bin.add(indices, 5123, 12, "SCALAR", json!({}));
    let joints0: Vec<u8> = vec![0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0];
    let joints0 = bin.add(joints0, 5121, 6, "VEC4", json!({}));
    #[rustfmt::skip]
    let weights0 = [
        1.0, 0.0, 0.0, 0.0,  1.0, 0.0, 0.0, 0.0,
        0.5, 0.5, 0.0, 0.0,  0.5, 0.5, 0.0, 0.0,
        1.0, 0.0, 0.0, 0.0,  0.5, 0.1, 0.1, 0.1,
    ];
    let weights0 = bin.floats(&weights0, "VEC4", 4);
    let joints1: Vec<u8> = [0u16; 20].into_iter().chain([1, 0, 0, 0]).flat_map(|j| j.to_le_bytes()).collect();
    let joints1 = bin.add(joints1, 5123, 6, "VEC4", json!({}));
    let weights1: Vec<u8> = [0u8; 20].into_iter().chain([51, 0, 0, 0]).collect();
    let weights1 = bin.add(weights1, 5121, 6, "VEC4", json!({"normalized": true}));
    let lift: Vec<f32> = (0..3).flat_map(|x| (0..2).flat_map(move |_| [0.0, 0.0, x as f32])).collect();
    let lift = bin.add(
        lift.iter().flat_map(|v| v.to_le_bytes()).collect(),
        5126,
        6,
        "VEC3",
        json!({"min": [0.0, 0.0, 0.0], "max": [0.0, 0.0, 2.0]}),
    );
    let inverse_bind: Vec<f32> =
        (0..3).flat_map(|j| glam::Mat4::from_translation(Vec3::new(-(j as f32), 0.0, 3.0)).to_cols_array()).collect();
    let inverse_bind = bin.floats(&inverse_bind, "MAT4", 16);
    let tri = bin.add(
        [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect(),
        5126,
        3,
        "VEC3",
        json!({"min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}),
    );
    let times = bin.floats(&[0.0, 1.0], "SCALAR", 1);
    let turn = bin.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, SQRT_HALF, SQRT_HALF], "VEC4", 4);
    let weight = bin.floats(&[0.0, 0.0, 1.0, 0.0, 1.0, 0.0], "SCALAR", 1);
    let slide = bin.floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0], "VEC3", 3);
    let step_times = bin.floats(&[0.0, 0.5], "SCALAR", 1);
    let grow = bin.floats(&[1.0, 1.0, 1.0, 2.0, 2.0, 2.0], "VEC3", 3);
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 4, 5, 6]}],
        "nodes": [
            {"name": "bar", "mesh": 0, "skin": 0, "translation": [100.0, 0.0, 0.0]},
            {"name": "j0", "children": [2]},
            {"name": "j1", "translation": [1.0, 0.0, 0.0], "children": [3]},
            {"name": "j2", "translation": [1.0, 0.0, 0.0]},
            {"name": "armature", "translation": [0.0, 0.0, -3.0], "children": [1]},
            {"name": "mover", "mesh": 1, "translation": [5.0, 0.0, 0.0]},
            {"name": "still", "mesh": 1, "translation": [0.0, 5.0, 0.0]}
        ],
        "meshes": [
            {"name": "bar", "weights": [0.5], "primitives": [{
                "attributes": {"POSITION": position, "JOINTS_0": joints0, "WEIGHTS_0": weights0,
                               "JOINTS_1": joints1, "WEIGHTS_1": weights1},
                "indices": index,
                "targets": [{"POSITION": lift}]
            }]},
            {"name": "tri", "primitives": [{"attributes": {"POSITION": tri}}]}
        ],
        "skins": [{"name": "chain", "joints": [1, 2, 3], "inverseBindMatrices": inverse_bind}],
        "animations": [{
            "name": "wave",
            "samplers": [
                {"input": times, "output": turn, "interpolation": "LINEAR"},
                {"input": times, "output": weight, "interpolation": "CUBICSPLINE"},
                {"input": times, "output": slide, "interpolation": "LINEAR"},
                {"input": step_times, "output": grow, "interpolation": "STEP"}
            ],
            "channels": [
                {"sampler": 0, "target": {"node": 2, "path": "rotation"}},
                {"sampler": 1, "target": {"node": 0, "path": "weights"}},
                {"sampler": 2, "target": {"node": 5, "path": "translation"}},
                {"sampler": 3, "target": {"node": 5, "path": "scale"}}
            ]
        }]
    });
    Doc { json, bin, times }
}

impl Doc {
    /// Writes the document with its buffer embedded.
    fn write(&self, dir: &Path, name: &str) -> PathBuf {
        use base64::Engine;
        let mut json = self.json.clone();
        json["accessors"] = json!(self.bin.accessors);
        json["bufferViews"] = json!(self.bin.views);
        let uri = base64::engine::general_purpose::STANDARD.encode(&self.bin.bytes);
        json["buffers"] =
            json!([{"byteLength": self.bin.bytes.len(), "uri": format!("data:application/octet-stream;base64,{uri}")}]);
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        path
    }

    /// Overwrites float `element` of accessor `accessor` with `value`.
    fn set_float(&mut self, accessor: usize, element: usize, value: f32) {
        let at = self.bin.offset(accessor) + 4 * element;
        self.bin.bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
    }
}

fn load(path: &Path) -> Result<(Scene, ImportReport), SceneError> {
    let loaded = gltf_import::load_with_report(path, &LoadOptions::default());
    if let Err(e) = &loaded {
        assert!(!e.to_string().contains("the glTF reader failed"), "{e}");
    }
    loaded
}

fn imported() -> (Scene, ImportReport) {
    let dir = tempfile::tempdir().unwrap();
    load(&skinned_doc().write(dir.path(), "bar.gltf")).unwrap()
}

fn close(a: Vec3, b: Vec3) -> bool {
    a.distance(b) < 1e-5
}

#[test]
fn imports_the_skin_the_morph_target_and_the_clip() {
    let (scene, report) = imported();
    assert_eq!(scene.instances.len(), 3);
    let anim = scene.animation.as_ref().expect("the scene is animated");
    // The bar (skinned and morphed) and the mover (rigid); 'still' is not animated.
    let instances: Vec<(u32, bool, u32)> =
        anim.instances().iter().map(|i| (i.instance, i.skin.is_some(), i.morph_targets)).collect();
    assert_eq!(instances, vec![(0, true, 1), (1, false, 0)]);
    // bar, armature, j0, j1, j2, mover.
    let sources: Vec<u32> = anim.nodes().iter().map(|n| n.source).collect();
    assert_eq!(sources, vec![0, 4, 1, 2, 3, 5]);
    assert_eq!(anim.skins().len(), 1);
    assert_eq!(anim.skins()[0].joints, vec![2, 3, 4]);
    assert_eq!(anim.clips().len(), 1);
    assert_eq!(anim.clips()[0].name, "wave");
    assert_eq!(anim.clips()[0].duration, 1.0);
    assert_eq!(anim.clip_index("wave"), Some(0));
    let properties: Vec<Property> = anim.clips()[0].channels.iter().map(|c| c.property).collect();
    assert_eq!(properties, vec![Property::Rotation, Property::Weights, Property::Translation, Property::Scale]);

    let deform = scene.meshes[scene.instances[0].mesh as usize].deform.as_ref().expect("the bar deforms");
    assert_eq!(deform.joint_count, 2);
    assert_eq!(deform.morph_targets.len(), 1);
    assert_eq!(deform.default_weights, vec![0.5]);
    // Five influences reduced to the four heaviest, renormalised; zero weights name joint 0.
    assert_eq!(deform.joints[5], [1, 1, 0, 0]);
    assert!((deform.weights[5] - Vec4::new(0.5, 0.2, 0.1, 0.1) / 0.9).abs().max_element() < 1e-6);
    assert_eq!(deform.joints[2], [0, 1, 0, 0]);
    assert_eq!(deform.weights[2], Vec4::new(0.5, 0.5, 0.0, 0.0));
    assert!(scene.meshes[scene.instances[1].mesh as usize].deform.is_none());

    let text = report.notes.join("\n");
    assert!(text.contains("mesh 'bar' (#0) primitive 0: 1 of 6 vertices have more than 4 joint influences"), "{text}");
    assert!(!text.contains("ignored"), "{text}");
}

fn poses(scene: &Scene, t: f64) -> Vec<InstancePose> {
    scene.animation.as_ref().unwrap().pose(0, t)
}

#[test]
fn poses_equal_the_keys_at_key_times_and_interpolate_between() {
    let (scene, _) = imported();
    let at = |t: f64| {
        let p = poses(&scene, t);
        (p[0].morph_weights[0], p[1].transform)
    };
    // Key 0 of every channel (and the end of the clip, which wraps to its start).
    for t in [0.0, 1.0, -1.0] {
        let (weight, mover) = at(t);
        assert_eq!(weight, 0.0);
        assert_eq!(mover.translation, DVec3::ZERO);
        assert_eq!(mover.linear, Mat3::IDENTITY);
    }
    // LINEAR translation, STEP scale before its second key.
    let (weight, mover) = at(0.25);
    assert_eq!(mover.translation, DVec3::new(0.5, 0.0, 0.0));
    assert_eq!(mover.linear, Mat3::IDENTITY);
    // CUBICSPLINE: h10 * out-tangent * 1 s + h01 * 1 at s = 1/4.
    let s = 0.25f32;
    assert!((weight - ((s * s * s - 2.0 * s * s + s) + (3.0 * s * s - 2.0 * s * s * s))).abs() < 1e-6);
    // The STEP key at 0.5 s, exactly.
    let (weight, mover) = at(0.5);
    assert_eq!(mover.linear, Mat3::from_diagonal(Vec3::splat(2.0)));
    assert_eq!(mover.translation, DVec3::new(1.0, 0.0, 0.0));
    assert!((weight - 0.625).abs() < 1e-6);
    assert_eq!(at(0.49).1.linear, Mat3::IDENTITY);

    // Without a clip: the rest pose, as the importer placed the instances; mesh default weights.
    let rest = scene.animation.as_ref().unwrap().rest_pose();
    for pose in &rest {
        assert_eq!(pose.transform, scene.instances[pose.instance as usize].transform);
    }
    assert_eq!(rest[0].morph_weights, vec![0.5]);
}

/// The bar's deformed world positions (CPU reference) at `t`.
fn bar_at(scene: &Scene, t: f64) -> (Vec<Vec3>, cullgraph::scene::Aabb) {
    let pose = &poses(scene, t)[0];
    let mesh = &scene.meshes[scene.instances[0].mesh as usize];
    let rest = &scene.vertices[mesh.vertex_offset as usize..][..mesh.vertex_count as usize];
    let deform = mesh.deform.as_ref().unwrap();
    let (local, normals) = deform.deform_vertices(rest, &pose.joints, &pose.morph_weights).unwrap();
    assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    let positions: Vec<Vec3> = rest.iter().map(|v| Vec3::from(v.position)).collect();
    let bounds = deform.bounds(&positions, &pose.joints, &pose.morph_weights).unwrap();
    for p in &local {
        assert!(p.cmpge(bounds.min).all() && p.cmple(bounds.max).all(), "{p} outside {bounds:?}");
    }
    (local.iter().map(|p| pose.transform.apply(*p).as_vec3()).collect(), bounds)
}

#[test]
fn skinned_positions_match_hand_computed_ones() {
    let (scene, _) = imported();
    // At rest (t = 0, weight 0) the bar is where its bind pose put it, whatever the bar
    // node's own translation of 100: glTF ignores the skinned node's transform.
    let (rest, _) = bar_at(&scene, 0.0);
    for (i, p) in rest.iter().enumerate() {
        let expected = Vec3::new((i / 2) as f32, (i % 2) as f32, 0.0);
        assert!(close(*p, expected), "vertex {i}: {p} vs {expected}");
    }
    assert_eq!(poses(&scene, 0.0)[0].transform.translation, DVec3::new(100.0, 0.0, 0.0));
    // At 0.5 s: joint 1 (at (1, 0, 0)) has turned 45 degrees about z (slerp), and the morph
    // weight is 0.625, lifting each vertex by 0.625 x (turns about z keep z).
    let (bent, bounds) = bar_at(&scene, 0.5);
    let (c, s) = (SQRT_HALF, SQRT_HALF);
    let lift = |x: f32| 0.625 * x;
    let expected = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        // Half on joint 0 (still) and half on joint 1 (the pivot itself stays).
        Vec3::new(1.0, 0.0, lift(1.0)),
        (Vec3::new(1.0, 1.0, 0.0) + Vec3::new(1.0 - s, c, 0.0)) * 0.5 + Vec3::Z * lift(1.0),
        Vec3::new(1.0 + c, s, lift(2.0)),
    ];
    for (i, e) in expected.iter().enumerate() {
        assert!(close(bent[i], *e), "vertex {i}: {} vs {e}", bent[i]);
    }
    // Vertex 5 (2, 1): 7/9 on joint 1, which turns its offset (1, 1) from the pivot, 2/9 on joint 0.
    let on_joint1 = Vec3::new(1.0 + c - s, s + c, 0.0);
    let e5 = on_joint1 * (0.7 / 0.9) + Vec3::new(2.0, 1.0, 0.0) * (0.2 / 0.9) + Vec3::Z * lift(2.0);
    assert!(close(bent[5], e5), "vertex 5: {} vs {e5}", bent[5]);
    assert!((bounds.max.z - lift(2.0)).abs() < 1e-6);
}

/// Loads `doc` and returns its error.
fn error_of(doc: &Doc) -> (String, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = doc.write(dir.path(), "bad.gltf");
    match load(&path) {
        Ok(_) => panic!("the broken file loaded"),
        Err(e) => (e.to_string(), "bad.gltf: ".to_string()),
    }
}

#[test]
fn broken_files_name_the_place() {
    let check = |doc: Doc, expected: &str| {
        let (e, file) = error_of(&doc);
        assert_eq!(e.strip_prefix(&file), Some(expected), "{e}");
    };
    // A joint index past the skin's joints.
    let mut doc = skinned_doc();
    doc.json["skins"][0]["joints"] = json!([1]);
    check(
        doc,
        "node 'bar' (#0): its mesh 'bar' (#0) primitive 0, JOINTS_0 accessor 2, JOINTS_1 accessor 4: joint index 1 \
         is out of range: skin 'chain' (#0) has 1 joints",
    );
    // Counts that differ.
    let mut doc = skinned_doc();
    doc.bin.accessors[3]["count"] = json!(5);
    check(doc, "mesh 'bar' (#0) primitive 0, WEIGHTS_0 accessor 3: 5 weight sets for 6 positions");
    let mut doc = skinned_doc();
    doc.bin.accessors[6]["count"] = json!(5);
    check(doc, "mesh 'bar' (#0) primitive 0, morph target 0 POSITION accessor 6: 5 offsets for 6 positions");
    // Non-finite values.
    let mut doc = skinned_doc();
    doc.set_float(3, 9, f32::NAN);
    check(doc, "mesh 'bar' (#0) primitive 0, WEIGHTS_0 accessor 3: vertex 2 has weights [0.5, NaN, 0, 0]: they must be finite and at least 0");
    let mut doc = skinned_doc();
    doc.set_float(7, 20, f32::INFINITY);
    check(doc, "skin 'chain' (#0), inverseBindMatrices accessor 7: matrix 1 is not finite");
    // Key times not increasing.
    let mut doc = skinned_doc();
    let times = doc.times;
    doc.set_float(times, 1, 0.0);
    check(
        doc,
        &format!("animation 'wave' (#0) channel 0, input accessor {times}: key times are not increasing: key 1 at 0 s follows 0 s"),
    );
    // A sampler with the wrong output count.
    let mut doc = skinned_doc();
    doc.bin.accessors[times + 2]["count"] = json!(4);
    check(
        doc,
        &format!(
            "animation 'wave' (#0) channel 1, output accessor {}: it has 4 values; 2 keys of 1 values times 3 (CUBICSPLINE) need 6",
            times + 2
        ),
    );
    // A channel on a node outside the scene.
    let mut doc = skinned_doc();
    doc.json["nodes"].as_array_mut().unwrap().push(json!({"name": "elsewhere"}));
    doc.json["animations"][0]["channels"][2]["target"]["node"] = json!(7);
    check(doc, "animation 'wave' (#0) channel 2: it animates node 'elsewhere' (#7), which is not in the drawn scene");
    // Weights keyed on a node without morph targets.
    let mut doc = skinned_doc();
    doc.json["animations"][0]["channels"][1]["target"]["node"] = json!(5);
    check(
        doc,
        "animation 'wave' (#0) channel 1: it animates the morph weights of node 'mover' (#5), whose mesh has no morph targets",
    );
}

#[test]
fn deformations_are_validated_and_animations_checked_against_the_scene() {
    let (mut scene, _) = imported();
    scene.validate().unwrap();
    let anim = scene.animation.clone().unwrap();
    assert_eq!(anim.problem(&scene), None);
    let mut fewer = scene.clone();
    fewer.instances.truncate(1);
    assert_eq!(anim.problem(&fewer).unwrap(), "animated instance 1 does not exist (1 instances)");
    // A deformation that does not match its mesh's vertices.
    let bar = scene.instances[0].mesh as usize;
    let mut deform = (**scene.meshes[bar].deform.as_ref().unwrap()).clone();
    deform.weights.pop();
    scene.meshes[bar].deform = Some(std::sync::Arc::new(deform));
    let e = scene.validate().unwrap_err().to_string();
    assert_eq!(e, "mesh #0 'bar/0': deformation: 6 joints and 5 weights for 6 vertices");
}
