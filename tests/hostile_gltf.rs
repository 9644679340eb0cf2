//! glTF files made to hurt the importer (issue 38), generated small at run time: external
//! buffers and images on special or huge files, one accessor shared by thousands of primitives,
//! totals past the scene limits from a file of a few hundred kilobytes, images and cameras the
//! `gltf` crate would panic on, and geometry at the edge of the coordinate range. Each gives an
//! error naming what the user gave (buffer, node, accessor, image), or loads with a note naming
//! it; never a panic, an abort or unbounded memory. `cullgraph render` exits 1 with the error.

mod common;

use cullgraph::scene::gltf_import::{self, ImportReport};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::validate::{validate_scene, MAX_INSTANCES, MAX_TEXTURES, MAX_VERTICES};
use cullgraph::scene::{Scene, SceneError, MAX_COORDINATE};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// What the loader's internal panic backstop says; it must never fire.
const BACKSTOP: &str = "the glTF reader failed";

fn load(path: &Path) -> Result<(Scene, ImportReport), SceneError> {
    let loaded = gltf_import::load_with_report(path, &LoadOptions::default());
    if let Err(e) = &loaded {
        assert!(!e.to_string().contains(BACKSTOP), "{e}");
    }
    loaded
}

fn load_err(path: &Path) -> String {
    match load(path) {
        Ok((scene, _)) => panic!("{} loaded ({} instances) but should fail", path.display(), scene.instances.len()),
        Err(e) => e.to_string(),
    }
}

fn f32s(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The 36 bytes of a triangle's positions, from height `y0` to `y0 + 1`.
fn triangle_bytes(y0: f32) -> Vec<u8> {
    f32s(&[0.0, y0, 0.0, 1.0, y0, 0.0, 0.0, y0 + 1.0, 0.0])
}

fn data_uri(bytes: &[u8]) -> String {
    use base64::Engine;
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A document with one node 'n' drawing one triangle (mesh 'tri', POSITION accessor 0 on
/// buffer view 0) whose buffer is `buffer`.
fn triangle_doc(buffer: Value) -> Value {
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "n", "mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [buffer]
    })
}

/// The triangle document with its buffer embedded.
fn embedded_triangle() -> Value {
    let bin = triangle_bytes(0.0);
    triangle_doc(json!({"byteLength": bin.len(), "uri": data_uri(&bin)}))
}

fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
    path
}

/// A hostile file and the error it must give, in full.
struct Hostile {
    path: PathBuf,
    error: String,
}

/// The external buffer of the triangle on `/proc/self/pagemap` (endless; reports 0 bytes).
fn pagemap_buffer(dir: &Path) -> Hostile {
    let path = write(dir, "pagemap.gltf", &triangle_doc(json!({"byteLength": 36, "uri": "/proc/self/pagemap"})));
    let error = format!(
        "{}: buffer 0: cannot read '/proc/self/pagemap' (/proc/self/pagemap): the buffer file is not a regular file \
         (a file the kernel generates, on proc)",
        path.display()
    );
    Hostile { path, error }
}

/// The external buffer of the triangle in a sparse 100 GiB file, declared 100 GiB long.
fn sparse_buffer(dir: &Path) -> Hostile {
    let huge: u64 = 100 << 30;
    let file = std::fs::File::create(dir.join("huge.bin")).unwrap();
    file.set_len(huge).unwrap();
    let path = write(dir, "huge.gltf", &triangle_doc(json!({"byteLength": huge, "uri": "huge.bin"})));
    let error = format!(
        "{}: buffer 0: its byteLength {huge} takes the scene's buffers to {huge} bytes; a scene's buffers may hold at \
         most 2147483648 together",
        path.display()
    );
    Hostile { path, error }
}

/// The external buffer of the triangle on a FIFO (opening it would block) or a directory.
fn special_buffer(dir: &Path, name: &str, fifo: bool) -> Option<Hostile> {
    let special = dir.join(name);
    if fifo {
        let made = std::process::Command::new("mkfifo").arg(&special).status();
        if !made.is_ok_and(|s| s.success()) {
            return None; // no mkfifo here: the directory covers the rule
        }
    } else {
        std::fs::create_dir(&special).unwrap();
    }
    let path = write(dir, &format!("{name}.gltf"), &triangle_doc(json!({"byteLength": 36, "uri": name})));
    let error = format!(
        "{}: buffer 0: cannot read '{name}' ({}): the buffer file is not a regular file (a device, FIFO or directory)",
        path.display(),
        special.display()
    );
    Some(Hostile { path, error })
}

/// 22,000 nodes placing a mesh of 100,000 primitives: 2.2x10^9 instances from a 4 MB file.
fn many_instances(dir: &Path) -> Hostile {
    let mut doc = embedded_triangle();
    doc["meshes"][0] = json!({"name": "many", "primitives": vec![json!({"attributes": {"POSITION": 0}}); 100_000]});
    doc["nodes"] = json!(vec![json!({"mesh": 0}); 22_000]);
    doc["scenes"][0]["nodes"] = json!((0..22_000).collect::<Vec<u32>>());
    let path = write(dir, "instances.gltf", &doc);
    let last = MAX_INSTANCES / 100_000; // the node that takes the scene past the limit
    let error = format!(
        "instances.gltf: node #{last}: the 100000 primitives of its mesh 'many' (#0) take the scene past \
         {MAX_INSTANCES} instances, the most a scene may hold ({} placed before it)",
        last * 100_000
    );
    Hostile { path, error }
}

/// 65 primitives that share one POSITION accessor of 2^20 vertices, each with indices of its
/// own: 65 copies of its vertices would pass the scene's vertex limit. The buffer is declared
/// and never read: the totals come from the document alone.
fn shared_positions(dir: &Path) -> Hostile {
    let vertices = 1usize << 20;
    let mut doc = embedded_triangle();
    doc["buffers"][0] = json!({"byteLength": vertices * 12 + 8, "uri": "never-read.bin"});
    doc["bufferViews"] = json!([{"buffer": 0, "byteLength": vertices * 12}, {"buffer": 0, "byteOffset": vertices * 12, "byteLength": 6}]);
    doc["accessors"][0]["count"] = json!(vertices);
    let index = json!({"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"});
    let accessors = doc["accessors"].as_array_mut().unwrap();
    accessors.extend(vec![index; 65]);
    let prims: Vec<Value> = (1..=65).map(|i| json!({"attributes": {"POSITION": 0}, "indices": i})).collect();
    doc["meshes"][0] = json!({"name": "shared", "primitives": prims});
    let path = write(dir, "vertices.gltf", &doc);
    let error = format!(
        "vertices.gltf: mesh 'shared' (#0) primitive 64, POSITION accessor 0: its {vertices} vertices take the scene \
         past {MAX_VERTICES} vertices, the most a scene may hold ({MAX_VERTICES} before it)"
    );
    Hostile { path, error }
}

/// More images than a scene may hold textures (none of them is read).
fn many_images(dir: &Path) -> Hostile {
    let mut doc = embedded_triangle();
    doc["images"] = json!(vec![json!({"uri": "i.png"}); MAX_TEXTURES + 1]);
    let path = write(dir, "images.gltf", &doc);
    let error = format!(
        "images.gltf: image {MAX_TEXTURES}: the file has {} images; a scene may hold at most {MAX_TEXTURES} textures",
        MAX_TEXTURES + 1
    );
    Hostile { path, error }
}

/// A node at the top of the coordinate range whose triangle reaches one unit past it.
fn beyond_range(dir: &Path) -> Hostile {
    let mut doc = embedded_triangle();
    doc["nodes"][0] = json!({"name": "top", "mesh": 0, "translation": [0.0, MAX_COORDINATE, 0.0]});
    let path = write(dir, "beyond.gltf", &doc);
    let error =
        "beyond.gltf: node 'top' (#0): its mesh 'tri' (#0) reaches [0, 1099511627776, 0]..[1, 1099511627777, 0], \
                 beyond ±1099511627776 (2^40) units, where positions stop keeping 1/256 unit of precision on the GPU"
            .to_string();
    Hostile { path, error }
}

fn hostile_files(dir: &Path) -> Vec<Hostile> {
    let mut files = vec![pagemap_buffer(dir), sparse_buffer(dir)];
    files.extend(special_buffer(dir, "pipe", true));
    files.extend(special_buffer(dir, "folder", false));
    files.extend([many_instances(dir), shared_positions(dir), many_images(dir), beyond_range(dir)]);
    files
}

#[test]
fn hostile_files_are_refused_naming_what_the_user_gave() {
    let dir = tempfile::tempdir().unwrap();
    for hostile in hostile_files(dir.path()) {
        let start = std::time::Instant::now();
        assert_eq!(load_err(&hostile.path), hostile.error);
        assert!(start.elapsed().as_secs() < 20, "{}: {:?}", hostile.path.display(), start.elapsed());
    }
}

/// A buffer is read up to its byteLength, whatever the file's size: the first 36 bytes of a
/// sparse 100 GiB file are the triangle.
#[test]
fn a_buffer_in_a_huge_sparse_file_reads_only_its_byte_length() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("sparse.bin");
    std::fs::write(&bin, triangle_bytes(0.0)).unwrap();
    std::fs::OpenOptions::new().write(true).open(&bin).unwrap().set_len(100 << 30).unwrap();
    let path = write(dir.path(), "sparse.gltf", &triangle_doc(json!({"byteLength": 36, "uri": "sparse.bin"})));
    let (scene, _) = load(&path).unwrap();
    assert_eq!((scene.instances.len(), scene.vertices.len()), (1, 3));
}

/// An external image on a special file becomes the placeholder with a note naming the image.
#[test]
fn an_image_on_a_special_file_is_the_placeholder() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = embedded_triangle();
    doc["images"] = json!([{"uri": "/proc/self/pagemap", "name": "pagemap"}, {"uri": "/dev/zero"}]);
    let (scene, report) = load(&write(dir.path(), "image.gltf", &doc)).unwrap();
    assert!(scene.textures.iter().all(|t| t.name.ends_with("(placeholder)")));
    let notes = report.notes.join("\n");
    for image in ["image 0 'pagemap': cannot read '/proc/self/pagemap'", "image 1 '/dev/zero': cannot read"] {
        assert!(notes.contains(image), "{notes}");
    }
    assert!(notes.contains("a file the kernel generates") && notes.contains("a device, FIFO or directory"), "{notes}");
}

/// 20,000 primitives with the same accessors are one mesh, read once, drawn 20,000 times; the
/// same primitive in another glTF mesh shares it too, and every skipped primitive is reported.
#[test]
fn primitives_that_share_their_accessors_share_one_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = embedded_triangle();
    let triangle = json!({"attributes": {"POSITION": 0}});
    let lines = json!({"attributes": {"POSITION": 0}, "mode": 1});
    doc["meshes"] = json!([
        {"name": "many", "primitives": vec![triangle.clone(); 20_000]},
        {"name": "again", "primitives": [triangle, lines.clone(), lines]}
    ]);
    doc["nodes"] = json!([{"mesh": 0}, {"mesh": 1}]);
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    let (scene, report) = load(&write(dir.path(), "shared.gltf", &doc)).unwrap();
    assert_eq!((scene.meshes.len(), scene.vertices.len(), scene.indices.len()), (1, 3, 3));
    assert_eq!(scene.instances.len(), 20_001);
    assert!(scene.instances.iter().all(|i| i.mesh == 0));
    assert_eq!(
        report.skipped_primitives,
        [1, 2]
            .map(|p| format!("shared.gltf: mesh 'again' (#1) primitive {p}: mode LINES cannot be drawn as triangles"))
    );
    validate_scene(&scene).unwrap();
}

/// Images without a source, or with a buffer view and no MIME type, and a camera without the
/// projection its type names: the `gltf` crate panics on each; they become the placeholder or an
/// ignored camera, with notes naming them.
#[test]
fn inputs_the_gltf_crate_would_panic_on_are_refused_first() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = embedded_triangle();
    doc["images"] =
        json!([{"name": "nothing"}, {"bufferView": 0, "name": "no-mime"}, {"bufferView": 0, "mimeType": "image/png"}]);
    doc["textures"] = json!([{"source": 0}, {"source": 1}]);
    doc["materials"] = json!([{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}}]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    doc["cameras"] = json!([{"type": "orthographic", "perspective": {"yfov": 1.0, "znear": 0.1}}]);
    doc["nodes"] = json!([{"name": "n", "mesh": 0, "children": [1]}, {"name": "eye", "camera": 0}]);
    let (scene, report) = load(&write(dir.path(), "panics.gltf", &doc)).unwrap();
    assert_eq!(scene.textures.len(), 3);
    assert!(scene.textures.iter().all(|t| t.name.ends_with("(placeholder)")));
    assert!(scene.camera.is_none());
    let notes = report.notes.join("\n");
    for note in [
        "image 0 'nothing': it has neither a bufferView nor a uri; the placeholder texture is shown instead",
        "image 1 'no-mime': it has a bufferView but no mimeType (glTF requires one with a bufferView); the placeholder",
        "image 2: not a PNG or JPEG file (declared image/png)",
        "material 'm': its baseColorTexture (image 1 'no-mime') shows the placeholder",
        "node 'eye' (#1): camera 0 ignored: its type is orthographic but it has no orthographic properties",
    ] {
        assert!(notes.contains(note), "missing \"{note}\" in:\n{notes}");
    }
}

/// A scene that reaches the top of the coordinate range loads: the lights the importer places
/// above it stay within the range, so no light of its own is blamed.
#[test]
fn lights_placed_above_a_scene_at_the_edge_of_the_range_stay_in_it() {
    let dir = tempfile::tempdir().unwrap();
    let bin = triangle_bytes(-1.0);
    let mut doc = triangle_doc(json!({"byteLength": bin.len(), "uri": data_uri(&bin)}));
    doc["accessors"][0]["min"] = json!([0.0, -1.0, 0.0]);
    doc["accessors"][0]["max"] = json!([1.0, 0.0, 0.0]);
    doc["nodes"][0]["translation"] = json!([0.0, MAX_COORDINATE, 0.0]);
    let (scene, _) = load(&write(dir.path(), "edge.gltf", &doc)).unwrap();
    assert_eq!(scene.lights.len(), gltf_import::DEFAULT_FILE_LIGHTS);
    assert!(scene.lights.iter().all(|l| l.position.y == MAX_COORDINATE), "{:?}", scene.lights);
    validate_scene(&scene).unwrap();
}

/// The command line gives each hostile file's error and exit status 1; a file whose images the
/// crate would panic on renders, with the placeholder and a warning naming the image.
#[test]
fn the_command_line_exits_1_with_each_hostile_files_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    let render = |scene: &Path| {
        common::cli::run(&[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--size",
            "64x48",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    for hostile in hostile_files(dir.path()) {
        let (code, _, err) = render(&hostile.path);
        assert_eq!(code, 1, "{}: {err}", hostile.path.display());
        assert!(err.contains(&hostile.error), "{}: {err}", hostile.path.display());
        assert!(!err.contains("panicked") && !err.contains(BACKSTOP), "{err}");
        assert!(!out.exists());
    }
    let mut doc = embedded_triangle();
    doc["images"] = json!([{"name": "nothing"}]);
    let (code, _, err) = render(&write(dir.path(), "sourceless.gltf", &doc));
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("image 0 'nothing': it has neither a bufferView nor a uri"), "{err}");
    assert!(out.exists());
}
