//! glTF import: the real assets (monastery, 2CylinderEngine), every file of the assimp glTF 2.0
//! test models (broken ones must give errors that name the problem, never panics), and small
//! hand-written files for strips, fans, hierarchies and bad transforms. CPU only.

use cullgraph::scene::gltf_import::{self, ImportReport};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::validate::validate_scene;
use cullgraph::scene::{Scene, SceneError, FLAG_NO_AA, FLAG_OCCLUDER};
use glam::{DVec3, Mat3, Vec3};
use proptest::prelude::*;
use serde_json::json;
use std::f32::consts::FRAC_1_SQRT_2;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

const MONASTERY: &str = "/work/shared/assets/monastery.glb";
const ASSIMP_GLTF2: &str = "/usr/share/assimp/models/glTF2";
/// What the loader's internal panic backstop says; tests require that it never fires.
const BACKSTOP: &str = "the glTF reader failed";

fn assimp_dir() -> PathBuf {
    let dir = PathBuf::from(ASSIMP_GLTF2);
    assert!(
        dir.is_dir(),
        "{ASSIMP_GLTF2} is missing: install the Debian package assimp-testmodels (run scripts/install-deps, \
         or `apt-get install assimp-testmodels`)"
    );
    dir
}

fn monastery() -> PathBuf {
    let path = PathBuf::from(MONASTERY);
    assert!(path.is_file(), "{MONASTERY} is missing: the shared test assets are not available on this machine");
    path
}

fn load(path: &Path) -> Result<(Scene, ImportReport), SceneError> {
    gltf_import::load_with_report(path, &LoadOptions::default())
}

fn load_err(path: &Path) -> String {
    match load(path) {
        Ok((scene, _)) => panic!("{} loaded ({} instances) but should fail", path.display(), scene.instances.len()),
        Err(e) => e.to_string(),
    }
}

fn unique_triangles(scene: &Scene) -> u64 {
    scene.meshes.iter().map(|m| m.index_count as u64 / 3).sum()
}

#[test]
fn monastery_has_the_expected_counts() {
    let (scene, report) = load(&monastery()).unwrap();
    assert_eq!(scene.name, "monastery.glb");
    assert_eq!(scene.meshes.len(), 81);
    assert_eq!(scene.instances.len(), 81);
    assert_eq!(scene.materials.len(), 81);
    assert_eq!(unique_triangles(&scene), 124_789);
    assert_eq!(scene.instanced_triangles(), 124_789);
    assert!(report.skipped_primitives.is_empty(), "{report:?}");
    let (min, max) = scene.world_bounds().unwrap();
    assert!(min.is_finite() && max.is_finite() && (max - min).min_element() > 1.0, "{min} {max}");
    assert_eq!(scene.lights.len(), gltf_import::DEFAULT_FILE_LIGHTS);
    for light in &scene.lights {
        assert!(light.position.y > max.y && light.range as f64 > max.y - min.y);
    }
    validate_scene(&scene).unwrap();
    // `load` (the logging variant) gives the same scene.
    let plain = gltf_import::load(&monastery(), &LoadOptions::default()).unwrap();
    assert_eq!(plain.instances, scene.instances);
}

#[test]
fn monastery_lights_follow_the_option() {
    let options = LoadOptions { lights: Some(9), ..Default::default() };
    let scene = gltf_import::load(&monastery(), &options).unwrap();
    assert_eq!(scene.lights.len(), 9);
    let options = LoadOptions { lights: Some(0), ..Default::default() };
    assert!(gltf_import::load(&monastery(), &options).unwrap().lights.is_empty());
    // An absurd count is an error, not an allocation attempt.
    let options = LoadOptions { lights: Some(usize::MAX), ..Default::default() };
    let e = gltf_import::load(&monastery(), &options).unwrap_err().to_string();
    assert!(e.contains("lights = ") && e.contains("out of range"), "{e}");
}

#[test]
fn engine_has_the_expected_counts() {
    let path = assimp_dir().join("2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    let (scene, report) = load(&path).unwrap();
    // 29 glTF meshes with 34 primitives in all; 82 nodes, 67 of them with a mesh, which gives
    // 115 (node, primitive) instances. 75,730 distinct triangles, 121,496 drawn.
    assert_eq!(scene.meshes.len(), 34);
    let gltf_meshes: std::collections::BTreeSet<&str> =
        scene.meshes.iter().map(|m| m.name.rsplit_once('/').map_or(m.name.as_str(), |(a, _)| a)).collect();
    assert_eq!(gltf_meshes.len(), 29);
    assert_eq!(scene.instances.len(), 115);
    assert_eq!(unique_triangles(&scene), 75_730);
    assert_eq!(scene.instanced_triangles(), 121_496);
    assert!(report.skipped_primitives.is_empty());
    let camera = scene.camera.as_ref().expect("the engine file has a camera node");
    camera.validate().unwrap();
    validate_scene(&scene).unwrap();
    // Shared meshes: every cullgraph mesh is used by at least one instance.
    for (i, _) in scene.meshes.iter().enumerate() {
        assert!(scene.instances.iter().any(|inst| inst.mesh as usize == i), "mesh {i} unused");
    }
}

fn gltf_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            gltf_files(&path, out);
        } else if matches!(path.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
            out.push(path);
        }
    }
}

/// Files of the assimp glTF 2.0 directory that must be refused, with a fragment of the message.
const MUST_FAIL: &[(&str, &str)] = &[
    ("IndexOutOfRange/IndexOutOfRange.gltf", "out of range"),
    ("IndexOutOfRange/AllIndicesOutOfRange.gltf", "out of range"),
    ("MissingBin/BoxTextured.gltf", "BoxTextured0.bin"),
    ("RecursiveNodes/RecursiveNodes.gltf", "cycle"),
    ("BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "non-finite position"),
    ("IncorrectVertexArrays/Cube.gltf", "multiple of 3"),
    ("SchemaFailures/sceneWrongType.gltf", "not a valid glTF"),
    ("TestNoRootNode/NoScene.gltf", "scene: Index out of bounds"),
    ("TestNoRootNode/SceneWithoutNodes.gltf", "missing field `nodes`"),
    ("wrongTypes/badArray.gltf", "invalid type"),
    ("wrongTypes/badNumber.gltf", "invalid type"),
    ("wrongTypes/badObject.gltf", "invalid type"),
    ("wrongTypes/badString.gltf", "invalid type"),
    ("wrongTypes/badUint.gltf", "invalid type"),
    ("draco/2CylinderEngine.gltf", "KHR_draco_mesh_compression"),
    ("BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf", "KHR_technique_webgl"),
];

#[test]
fn every_assimp_gltf2_file_loads_or_fails_cleanly() {
    let dir = assimp_dir();
    let mut files = Vec::new();
    gltf_files(&dir, &mut files);
    files.sort();
    assert!(files.len() >= 40, "only {} glTF files under {}", files.len(), dir.display());
    let (mut loaded, mut refused) = (0, 0);
    for path in &files {
        let rel = path.strip_prefix(&dir).unwrap().to_string_lossy().into_owned();
        let outcome = catch_unwind(AssertUnwindSafe(|| load(path)));
        match outcome {
            Err(_) => panic!("{rel}: the loader panicked"),
            Ok(Ok((scene, _))) => {
                loaded += 1;
                assert!(!MUST_FAIL.iter().any(|(f, _)| *f == rel), "{rel} loaded but is broken");
                validate_scene(&scene).unwrap_or_else(|e| panic!("{rel}: loaded scene fails validation: {e}"));
            }
            Ok(Err(e)) => {
                refused += 1;
                let message = e.to_string();
                assert!(!message.contains(BACKSTOP), "{rel}: the panic backstop fired: {message}");
                assert!(message.contains(path.file_name().unwrap().to_str().unwrap()), "{rel}: {message}");
            }
        }
    }
    assert!(loaded >= 20 && refused >= MUST_FAIL.len(), "loaded {loaded}, refused {refused}");
}

#[test]
fn broken_assimp_files_name_their_problem() {
    let dir = assimp_dir();
    for (file, fragment) in MUST_FAIL {
        let message = load_err(&dir.join(file));
        assert!(message.contains(fragment), "{file}: expected '{fragment}' in: {message}");
    }
    // The places name file, mesh, primitive and accessor.
    let m = load_err(&dir.join("IndexOutOfRange/IndexOutOfRange.gltf"));
    assert!(
        m.starts_with("IndexOutOfRange.gltf: mesh 'Mesh' (#0) primitive 0, indices accessor 0: index 255 at element 0"),
        "{m}"
    );
    let m = load_err(&dir.join("RecursiveNodes/RecursiveNodes.gltf"));
    assert!(m.contains("node #0") && m.contains("#0 -> #1 -> #0"), "{m}");
    let m = load_err(&dir.join("BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb"));
    assert!(m.contains("mesh 'Mesh' (#0) primitive 0, POSITION accessor 2: vertex 0"), "{m}");
    let m = load_err(&dir.join("MissingBin/BoxTextured.gltf"));
    assert!(m.contains("buffer 0: cannot read 'BoxTextured0.bin'"), "{m}");
    let m = load_err(&dir.join("IncorrectVertexArrays/Cube.gltf"));
    assert!(m.contains("mesh 'TruncatedCube' (#1) primitive 0, POSITION accessor 6"), "{m}");
}

#[test]
fn valid_assimp_oddities_load() {
    let dir = assimp_dir();
    // A texture transform (KHR_texture_transform, which the import applies) that is not an
    // object: an error at its line and column.
    let m = load_err(&dir.join("wrongTypes/badExtension.gltf"));
    assert!(m.contains("expected struct TextureTransform at line 130 column 46"), "{m}");
    // Skins, morph targets and animations are imported to be played; poses over the clip are
    // finite and deform every vertex to a finite place.
    for (file, skinned, morphed) in [
        ("simple_skin/simple_skin.gltf", true, false),
        ("glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf", false, true),
    ] {
        let (scene, report) = load(&dir.join(file)).unwrap();
        // Only morphed tangents are left out.
        let ignored = report.notes.iter().filter(|n| n.contains("ignored") && !n.contains("TANGENT offsets"));
        assert_eq!(ignored.count(), 0, "{file}: {report:?}");
        let anim = scene.animation.as_ref().unwrap_or_else(|| panic!("{file} is not animated"));
        assert_eq!(anim.instances().iter().any(|i| i.skin.is_some()), skinned, "{file}");
        assert_eq!(anim.instances().iter().any(|i| i.morph_targets > 0), morphed, "{file}");
        assert_eq!(anim.clips().len(), 1, "{file}");
        for step in 0..10 {
            for pose in anim.pose(0, anim.clips()[0].duration * step as f64 / 10.0) {
                let mesh = &scene.meshes[scene.instances[pose.instance as usize].mesh as usize];
                let rest = &scene.vertices[mesh.vertex_offset as usize..][..mesh.vertex_count as usize];
                let deform = mesh.deform.as_ref().unwrap();
                let (p, n) = deform.deform_vertices(rest, &pose.joints, &pose.morph_weights).unwrap();
                assert!(p.iter().chain(&n).all(|v| v.is_finite()), "{file}");
            }
        }
    }
    // Textures load: BoxTextured's one image, its material's base colour texture, and texture
    // coordinates on the vertices.
    let (scene, report) = load(&dir.join("BoxTextured-glTF-Binary/BoxTextured.glb")).unwrap();
    assert_eq!(scene.textures.len(), 1, "{report:?}");
    assert!(scene.textures[0].width > 1 && !scene.textures[0].name.contains("placeholder"));
    assert!(scene.materials.iter().any(|m| m.texture(cullgraph::scene::TextureSlot::BaseColor).is_some()));
    assert!(scene.vertices.iter().any(|v| v.uv != [0.0, 0.0]));
    // Zero normals are recomputed from the faces (and reported); short ones are normalised.
    let (scene, report) = load(&dir.join("BoxBadNormals-glTF-Binary/BoxBadNormals.glb")).unwrap();
    assert!(report.notes.iter().any(|n| n.contains("NORMAL accessor 1: 4 of 24 normals are zero")), "{report:?}");
    let normal = |i: usize| cullgraph::scene::decode_octahedral(scene.vertices[i].normal);
    assert!(normal(0).dot(Vec3::Z) > 0.999, "{}", normal(0));
    assert!(normal(4).dot(-Vec3::Y) > 0.999, "{}", normal(4));
    // The cameras file has a perspective camera node.
    let (scene, _) = load(&dir.join("cameras/Cameras.gltf")).unwrap();
    assert!(scene.camera.is_some());
}

/// Face normals (not normalised) of every triangle of a scene's single mesh.
fn face_normals(scene: &Scene) -> Vec<Vec3> {
    let m = &scene.meshes[0];
    let idx = &scene.indices[m.first_index as usize..(m.first_index + m.index_count) as usize];
    idx.chunks_exact(3)
        .map(|t| {
            let p = |i: u32| Vec3::from_array(scene.vertices[(m.vertex_offset + i) as usize].position);
            (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]))
        })
        .collect()
}

#[test]
fn asset_generator_primitive_modes() {
    let dir = assimp_dir().join("glTF-Asset-Generator/Mesh_PrimitiveMode");
    let reference = face_normals(&load(&dir.join("Mesh_PrimitiveMode_04.gltf")).unwrap().0);
    assert_eq!(reference.len(), 2);
    // 04-06 and 11-15: triangles, strips and fans, without and with indices: the same quad
    // with the same winding.
    for n in [4, 5, 6, 11, 12, 13, 14, 15] {
        let file = format!("Mesh_PrimitiveMode_{n:02}.gltf");
        let normals = face_normals(&load(&dir.join(&file)).unwrap().0);
        assert_eq!(normals.len(), 2, "{file}");
        for f in &normals {
            assert!(f.normalize().dot(reference[0].normalize()) > 0.999, "{file}: face {f} vs {}", reference[0]);
        }
    }
    // Points and lines: nothing drawable, and the message says why.
    for (n, mode) in [(0, "POINTS"), (1, "LINES"), (2, "LINE_LOOP"), (3, "LINE_STRIP"), (7, "POINTS"), (8, "LINES")] {
        let m = load_err(&dir.join(format!("Mesh_PrimitiveMode_{n:02}.gltf")));
        assert!(m.contains("nothing to draw") && m.contains(mode), "{m}");
    }
}

// ---- hand-written files -----------------------------------------------------------------

/// A scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cullgraph-scene-import-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Little-endian bytes of positions followed by u16 indices (padded to 4).
fn geometry_bytes(positions: &[[f32; 3]], indices: &[u16]) -> Vec<u8> {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    bin
}

/// A primitive for [`document`]: glTF mode, positions, u16 indices (empty for none).
type Prim = (u32, Vec<[f32; 3]>, Vec<u16>);

/// A document with one mesh per entry of `prims` (mode, positions, indices), all sharing one
/// buffer `geo.bin`; `nodes` and `scenes` are given as JSON.
fn document(prims: &[Prim], nodes: serde_json::Value) -> (serde_json::Value, Vec<u8>) {
    let (mut bin, mut views, mut accessors, mut meshes) = (Vec::new(), vec![], vec![], vec![]);
    for (i, (mode, positions, indices)) in prims.iter().enumerate() {
        let start = bin.len();
        bin.extend(geometry_bytes(positions, &[]));
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": positions.len() * 12}));
        let (lo, hi) = positions.iter().fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])], [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])])
        });
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126, "count": positions.len(),
                              "type": "VEC3", "min": lo, "max": hi}));
        let mut prim = json!({"attributes": {"POSITION": accessors.len() - 1}, "mode": mode});
        if !indices.is_empty() {
            let start = bin.len();
            bin.extend(geometry_bytes(&[], indices));
            views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": indices.len() * 2}));
            accessors.push(
                json!({"bufferView": views.len() - 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}),
            );
            prim["indices"] = json!(accessors.len() - 1);
        }
        meshes.push(json!({"name": format!("m{i}"), "primitives": [prim]}));
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": meshes,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": "geo.bin", "byteLength": bin.len()}],
    });
    (doc, bin)
}

fn write(dir: &Path, doc: &serde_json::Value, bin: &[u8]) -> PathBuf {
    std::fs::write(dir.join("geo.bin"), bin).unwrap();
    let path = dir.join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec_pretty(doc).unwrap()).unwrap();
    path
}

fn triangle() -> Prim {
    (4, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![])
}

#[test]
fn non_finite_node_transforms_name_the_node() {
    let dir = scratch("nonfinite");
    // JSON has no NaN; 1e39 does not fit in an f32 and becomes +inf, which is what a broken
    // exporter's NaN/inf looks like after parsing.
    let (doc, bin) = document(
        &[triangle()],
        json!([{"name": "root", "children": [1]}, {"name": "bad", "mesh": 0, "translation": [1e39, 0.0, 0.0]}]),
    );
    let m = load_err(&write(&dir, &doc, &bin));
    assert_eq!(m, "scene.gltf: node 'bad' (#1): transform is not finite");
    let (doc, bin) = document(
        &[triangle()],
        json!([{"name": "m", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1e39, 0, 1]}]),
    );
    assert_eq!(load_err(&write(&dir, &doc, &bin)), "scene.gltf: node 'm' (#0): transform is not finite");
    // Finite locally, infinite once composed.
    let (doc, bin) = document(
        &[triangle()],
        json!([{"name": "big", "scale": [1e30, 1e30, 1e30], "children": [1]}, {"name": "bigger", "mesh": 0, "scale": [1e30, 1e30, 1e30]}]),
    );
    let m = load_err(&write(&dir, &doc, &bin));
    assert!(m.starts_with("scene.gltf: node 'bigger' (#1): world transform is not finite"), "{m}");
    // Finite, but farther than positions stay precise on the GPU: refused at the node.
    let (doc, bin) = document(
        &[triangle()],
        json!([{"name": "far", "children": [1], "translation": [1e12, 0.0, 0.0]}, {"name": "farther", "mesh": 0, "translation": [1e12, 0.0, 0.0]}]),
    );
    let m = load_err(&write(&dir, &doc, &bin));
    assert!(m.starts_with("scene.gltf: node 'farther' (#1): world translation ["), "{m}");
    assert!(m.contains("is beyond ±1099511627776 (2^40) units"), "{m}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn strips_and_fans_become_triangle_lists() {
    let dir = scratch("strip");
    // A strip zig-zagging along +x in the z = 0 plane: 6 vertices, 4 triangles, all facing +z.
    let strip: Vec<[f32; 3]> = (0..6).map(|i| [(i / 2) as f32, 1.0 - (i % 2) as f32, 0.0]).collect();
    // A fan around the origin, counter-clockwise seen from +z: 5 vertices, 3 triangles.
    let fan = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 1.0, 0.0]];
    let (doc, bin) = document(
        &[(5, strip, vec![]), (6, fan.clone(), vec![]), (6, fan, vec![0, 1, 2, 3, 4])],
        json!([{"children": [1, 2, 3]}, {"mesh": 0}, {"mesh": 1}, {"mesh": 2}]),
    );
    let (scene, report) = load(&write(&dir, &doc, &bin)).unwrap();
    assert!(report.skipped_primitives.is_empty());
    assert_eq!(scene.meshes.iter().map(|m| m.index_count / 3).collect::<Vec<_>>(), vec![4, 3, 3]);
    for (k, mesh) in scene.meshes.iter().enumerate() {
        let idx = &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
        for t in idx.chunks_exact(3) {
            let p = |i: u32| Vec3::from_array(scene.vertices[(mesh.vertex_offset + i) as usize].position);
            let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            assert!(n.z > 0.0, "mesh {k}: triangle {t:?} faces {n}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hierarchy_composes_transforms_and_shares_meshes() {
    let dir = scratch("hierarchy");
    let (doc, bin) = document(
        &[triangle()],
        json!([
            {"name": "parent", "translation": [10.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0], "children": [1, 2]},
            // 90 degrees about +y.
            {"name": "child", "mesh": 0, "translation": [1.0, 2.0, 3.0], "rotation": [0.0, FRAC_1_SQRT_2, 0.0, FRAC_1_SQRT_2], "children": [3]},
            {"name": "sibling", "mesh": 0},
            {"name": "grandchild", "mesh": 0, "translation": [0.0, 0.0, 1.0]}
        ]),
    );
    let (scene, _) = load(&write(&dir, &doc, &bin)).unwrap();
    assert_eq!(scene.meshes.len(), 1, "one glTF mesh used three times is one cullgraph mesh");
    assert_eq!(scene.instances.len(), 3);
    let child = &scene.instances[0].transform;
    assert!((child.translation - DVec3::new(12.0, 4.0, 6.0)).length() < 1e-9, "{}", child.translation);
    let expected = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2).mul_scalar(2.0);
    assert!(child.linear.abs_diff_eq(expected, 1e-5), "{:?}", child.linear);
    // The child's local +x lands on world -z, scaled by 2.
    assert!((child.linear * Vec3::X - Vec3::new(0.0, 0.0, -2.0)).length() < 1e-5);
    let grandchild = &scene.instances[1].transform;
    // Grandchild at child-local (0, 0, 1): the child maps +z to +x (times 2).
    assert!((grandchild.translation - DVec3::new(14.0, 4.0, 6.0)).length() < 1e-5, "{}", grandchild.translation);
    let sibling = &scene.instances[2].transform;
    assert!((sibling.translation - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
    assert!(sibling.linear.abs_diff_eq(Mat3::from_diagonal(Vec3::splat(2.0)), 1e-6));
    validate_scene(&scene).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn node_extras_flag_occluders_and_no_aa_down_the_hierarchy() {
    let dir = scratch("extras");
    let (doc, bin) = document(
        &[triangle()],
        json!([
            {"name": "walls", "extras": {"cullgraph": {"occluder": true}, "exporter": "kept out"}, "children": [1, 2]},
            {"name": "wall", "mesh": 0, "extras": {"cullgraph": {"no_aa": true, "occluder": false}}},
            {"name": "door", "mesh": 0, "extras": "not an object: ignored"},
            {"name": "plain", "mesh": 0}
        ]),
    );
    let mut doc = doc;
    doc["scenes"] = json!([{"nodes": [0, 3]}]);
    let (scene, _) = load(&write(&dir, &doc, &bin)).unwrap();
    let flags: Vec<u32> = scene.instances.iter().map(|i| i.flags).collect();
    // A child keeps what an ancestor set (its `false` clears nothing) and adds its own.
    assert_eq!(flags, [FLAG_OCCLUDER | FLAG_NO_AA, FLAG_OCCLUDER, 0]);

    for (extras, message) in [
        (json!({"cullgraph": {"no_AA": true}}), "extras.cullgraph.no_AA is unknown (known: occluder, no_aa)"),
        (json!({"cullgraph": {"occluder": 1}}), "extras.cullgraph.occluder must be true or false, not 1"),
        (json!({"cullgraph": true}), "extras.cullgraph must be an object"),
    ] {
        let (doc, bin) = document(&[triangle()], json!([{"name": "n", "mesh": 0, "extras": extras}]));
        let m = load_err(&write(&dir, &doc, &bin));
        assert!(m.starts_with(&format!("scene.gltf: node 'n' (#0): {message}")), "{m}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn mesh_extras_keep_a_mesh_whole() {
    let dir = scratch("lod-extras");
    // A 24 x 24 grid of quads (1152 triangles): enough for levels of detail.
    let n = 25u16;
    let positions: Vec<[f32; 3]> =
        (0..n * n).map(|i| [(i % n) as f32, (i / n) as f32, ((i % n) as f32 * 0.7).sin() * 0.2]).collect();
    let mut indices = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let a = y * n + x;
            indices.extend([a, a + 1, a + n, a + 1, a + n + 1, a + n]);
        }
    }
    let grid: Prim = (4, positions, indices);
    let (mut doc, bin) = document(&[grid.clone(), grid], json!([{"children": [1, 2]}, {"mesh": 0}, {"mesh": 1}]));
    doc["meshes"][1]["extras"] = json!({"cullgraph": {"lod": false}, "exporter": "kept out"});
    let (scene, _) = load(&write(&dir, &doc, &bin)).unwrap();
    assert!(!scene.meshes[0].lods.is_empty(), "a mesh gets its levels of detail");
    assert!(scene.meshes[1].lods.is_empty(), "\"lod\": false keeps the mesh whole");

    for (extras, message) in [
        (json!({"cullgraph": {"LOD": false}}), "extras.cullgraph.LOD is unknown (known: lod)"),
        (json!({"cullgraph": {"lod": "no"}}), "extras.cullgraph.lod must be true or false, not \"no\""),
    ] {
        doc["meshes"][1]["extras"] = extras;
        let m = load_err(&write(&dir, &doc, &bin));
        assert!(m.starts_with("scene.gltf: mesh 'm1'") && m.contains(message), "{m}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn broken_hierarchies_are_refused_without_recursion() {
    let dir = scratch("tree");
    // A node with two parents.
    let (mut doc, bin) = document(
        &[triangle()],
        json!([{"name": "a", "children": [1, 2]}, {"name": "b", "children": [2]}, {"name": "c", "mesh": 0}]),
    );
    let m = load_err(&write(&dir, &doc, &bin));
    assert!(m.starts_with("scene.gltf: node 'c' (#2): the node is reached twice"), "{m}");
    // A chain deeper than the limit: an error, not a stack overflow.
    let depth = 5000;
    let nodes: Vec<serde_json::Value> =
        (0..depth).map(|i| if i + 1 < depth { json!({"children": [i + 1]}) } else { json!({"mesh": 0}) }).collect();
    doc["nodes"] = json!(nodes);
    let m = load_err(&write(&dir, &doc, &bin));
    assert!(m.contains("deeper than"), "{m}");
    // A self-parented node.
    doc["nodes"] = json!([{"name": "loop", "children": [0], "mesh": 0}]);
    let m = load_err(&write(&dir, &doc, &bin));
    assert!(m.contains("node 'loop' (#0)") && m.contains("cycle"), "{m}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_triangle_primitives_are_reported_not_dropped_silently() {
    let dir = scratch("lines");
    let lines = (1, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], vec![]);
    let (doc, bin) =
        document(&[triangle(), lines], json!([{"children": [1, 2]}, {"mesh": 0}, {"name": "wire", "mesh": 1}]));
    let (scene, report) = load(&write(&dir, &doc, &bin)).unwrap();
    assert_eq!(scene.instances.len(), 1);
    assert_eq!(
        report.skipped_primitives,
        vec!["scene.gltf: mesh 'm1' (#1) primitive 0: mode LINES cannot be drawn as triangles"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_buffers_and_accessors_name_the_accessor() {
    let dir = scratch("buffers");
    let (doc, bin) =
        document(&[(4, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![0, 1, 2])], json!([{"mesh": 0}]));
    // The .bin is shorter than the declared byteLength.
    let m = load_err(&write(&dir, &doc, &bin[..20]));
    assert!(m.contains("buffer 0 has 20 bytes, the file declares byteLength"), "{m}");
    // An accessor that reaches past its view.
    let mut long = doc.clone();
    long["accessors"][0]["count"] = json!(4);
    let m = load_err(&write(&dir, &long, &bin));
    assert!(m.contains("POSITION accessor 0") && m.contains("do not fit in buffer view 0"), "{m}");
    // A view that reaches past its buffer.
    let mut view = doc.clone();
    view["bufferViews"][1]["byteOffset"] = json!(4000);
    let m = load_err(&write(&dir, &view, &bin));
    assert!(m.contains("indices accessor 1") && m.contains("exceeds buffer 0"), "{m}");
    // Wrong component type for positions.
    let mut ty = doc.clone();
    ty["accessors"][0]["componentType"] = json!(5123);
    let m = load_err(&write(&dir, &ty, &bin));
    assert!(m.contains("POSITION accessor 0: must be VEC3 of FLOAT"), "{m}");
    // No POSITION.
    let mut nopos = doc.clone();
    nopos["meshes"][0]["primitives"][0]["attributes"] = json!({"NORMAL": 0});
    let m = load_err(&write(&dir, &nopos, &bin));
    assert!(m.contains("attributes[\"POSITION\"]: Missing data"), "{m}");
    // Zero-area triangles.
    let (flat, flat_bin) =
        document(&[(4, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], vec![])], json!([{"mesh": 0}]));
    let m = load_err(&write(&dir, &flat, &flat_bin));
    assert!(m.contains("mesh 'm0' (#0) primitive 0, POSITION accessor 0") && m.contains("zero area"), "{m}");
    // Malformed URI escapes and unknown schemes are errors, not panics.
    let mut uri = doc.clone();
    uri["buffers"][0]["uri"] = json!("geo%FF.bin");
    assert!(load_err(&write(&dir, &uri, &bin)).contains("malformed URI"));
    uri["buffers"][0]["uri"] = json!("http://example.com/geo.bin");
    assert!(load_err(&write(&dir, &uri, &bin)).contains("unsupported URI scheme"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn truncated_and_garbage_files_fail_cleanly() {
    let dir = scratch("garbage");
    let bytes = std::fs::read(monastery()).unwrap();
    for cut in [0usize, 3, 12, 20, 100, 5000, bytes.len() / 2, bytes.len() - 1] {
        let path = dir.join("cut.glb");
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let m = load_err(&path);
        assert!(!m.contains(BACKSTOP), "cut at {cut}: {m}");
    }
    let path = dir.join("garbage.gltf");
    std::fs::write(&path, b"\x00\xffnot json").unwrap();
    assert!(load_err(&path).contains("not a valid glTF 2.0 document"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A GLB container around a document and its binary chunk.
fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Random byte corruption of a small GLB never panics (nor trips the loader's backstop).
    #[test]
    fn corrupted_glb_never_panics(flips in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6)) {
        let (doc, bin) = fuzz_seed();
        let mut bytes = glb(&doc, &bin);
        for (at, value) in &flips {
            let i = at.index(bytes.len());
            bytes[i] = *value;
        }
        let dir = scratch("fuzz");
        let path = dir.join(format!("f{}.glb", bytes.iter().map(|&b| b as usize).sum::<usize>()));
        std::fs::write(&path, &bytes).unwrap();
        let outcome = catch_unwind(AssertUnwindSafe(|| load(&path)));
        let _ = std::fs::remove_file(&path);
        let _ = std::fs::remove_dir(&dir);
        prop_assert!(outcome.is_ok(), "panicked");
        if let Ok(Err(e)) = outcome {
            prop_assert!(!e.to_string().contains(BACKSTOP), "{}", e);
        }
    }
}

/// Numeric fields of the fuzz seed document that structural fuzzing rewrites.
const FUZZ_FIELDS: &[&str] = &[
    "/accessors/0/count",
    "/accessors/0/byteOffset",
    "/accessors/0/bufferView",
    "/accessors/0/componentType",
    "/accessors/1/count",
    "/accessors/1/byteOffset",
    "/accessors/1/bufferView",
    "/accessors/1/componentType",
    "/bufferViews/0/byteOffset",
    "/bufferViews/0/byteLength",
    "/bufferViews/0/byteStride",
    "/bufferViews/1/byteOffset",
    "/bufferViews/1/byteLength",
    "/bufferViews/1/byteStride",
    "/buffers/0/byteLength",
    "/meshes/0/primitives/0/indices",
    "/meshes/0/primitives/0/mode",
    "/meshes/0/primitives/0/attributes/POSITION",
    "/meshes/0/primitives/0/attributes/NORMAL",
    "/nodes/0/mesh",
    "/nodes/0/children",
    "/scenes/0/nodes/0",
    "/scene",
];

fn fuzz_seed() -> (serde_json::Value, Vec<u8>) {
    let (mut doc, bin) = document(
        &[(4, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], vec![0, 1, 2, 2, 1, 3])],
        json!([{"mesh": 0, "translation": [1.0, 2.0, 3.0]}]),
    );
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    (doc, bin)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Structurally plausible corruption (indices, counts, offsets, strides, modes set to edge
    /// values) never panics and never trips the backstop.
    #[test]
    fn corrupted_fields_never_panic(edits in proptest::collection::vec((0..FUZZ_FIELDS.len(), 0..10usize), 1..5)) {
        const VALUES: [i64; 10] = [0, 1, 2, 3, 5, 7, 255, 5123, 65_536, 4_294_967_295];
        let (mut doc, bin) = fuzz_seed();
        for (field, value) in &edits {
            let pointer = FUZZ_FIELDS[*field];
            let (parent, key) = pointer.rsplit_once('/').unwrap();
            let v = if key == "children" { json!([VALUES[*value]]) } else { json!(VALUES[*value]) };
            match doc.pointer_mut(parent) {
                Some(serde_json::Value::Object(map)) => { map.insert(key.to_string(), v); }
                Some(serde_json::Value::Array(items)) => { if let Some(slot) = items.get_mut(0) { *slot = v; } }
                _ => {}
            }
        }
        let dir = scratch("fieldfuzz");
        let path = dir.join("f.glb");
        std::fs::write(&path, glb(&doc, &bin)).unwrap();
        let outcome = catch_unwind(AssertUnwindSafe(|| load(&path)));
        let _ = std::fs::remove_file(&path);
        let _ = std::fs::remove_dir(&dir);
        prop_assert!(outcome.is_ok(), "panicked on {}", doc);
        match outcome {
            Ok(Err(e)) => prop_assert!(!e.to_string().contains(BACKSTOP), "{} on {}", e, doc),
            Ok(Ok((scene, _))) => prop_assert!(validate_scene(&scene).is_ok()),
            Err(_) => {}
        }
    }
}

#[test]
fn the_fuzz_seed_document_is_valid() {
    let (doc, bin) = fuzz_seed();
    let dir = scratch("seed");
    let path = dir.join("seed.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    let (scene, _) = load(&path).unwrap();
    assert_eq!(scene.instanced_triangles(), 2);
    assert_eq!(scene.instances[0].transform.translation, DVec3::new(1.0, 2.0, 3.0));
    let _ = std::fs::remove_dir_all(&dir);
}
