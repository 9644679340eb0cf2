//! Textured and alpha-masked materials through the G-buffer, culling and the visibility oracle
//! (lavapipe, validation on).

mod common;

use common::GpuTest;
use cullgraph::oracle::Verify;
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::texture::{Sampler, Wrap};
use cullgraph::scene::{AlphaMode, Camera, Instance, Material, Scene, Texture, TextureRef, Transform};
use glam::{DVec3, Mat3, Vec2, Vec3};
use std::sync::Arc;

const SIZE: (u32, u32) = (160, 120);

fn render(gpu: &GpuTest, scene: &Scene, graph: &str, verify: bool) -> (cullgraph::stats::FrameStats, RgbaImage) {
    let shaders = gpu.shaders();
    let spec = GraphSpec::builtin(graph).unwrap();
    let mut r = Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    if verify {
        r.enable_verification(shaders).unwrap();
    }
    // Two frames: the second has last frame's culling history.
    r.render_to_image(&common::camera_on_z()).unwrap();
    r.render_to_image(&common::camera_on_z()).unwrap()
}

/// The channel that dominates a pixel (0 red, 1 green, 2 blue).
fn dominant(p: [u8; 3]) -> usize {
    (0..3).max_by_key(|&c| p[c]).unwrap()
}

/// A 2x2 texture on a quad shows each texel in its quarter: red top left, green top right,
/// blue bottom left, white bottom right (nearest filtering).
#[test]
fn a_textured_quad_shows_its_texels_where_its_coordinates_put_them() {
    let gpu = GpuTest::new();
    let mut scene = common::sunlit_scene("textures");
    let rgba = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 255, 255]].concat();
    scene.textures.push(Arc::new(Texture { name: "2x2".into(), width: 2, height: 2, rgba }));
    let sampler = Sampler { nearest_mag: true, nearest_min: true, ..Default::default() };
    let mut material = Material { name: "textured".into(), albedo: Vec3::ONE, ..Default::default() };
    material.textures[0] = Some(TextureRef { sampler, ..TextureRef::new(0) });
    let m = scene.add_material(material);
    let mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    scene.instances.push(Instance { transform: common::scaled_at(DVec3::ZERO, 2.0), mesh, material: m, flags: 0 });
    let (_, image) = render(&gpu, &scene, "default", false);
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    let d = 20;
    assert_eq!(
        dominant(common::rgb(&image, cx - d, cy - d)),
        0,
        "top left red: {:?}",
        common::rgb(&image, cx - d, cy - d)
    );
    assert_eq!(
        dominant(common::rgb(&image, cx + d, cy - d)),
        1,
        "top right green: {:?}",
        common::rgb(&image, cx + d, cy - d)
    );
    assert_eq!(
        dominant(common::rgb(&image, cx - d, cy + d)),
        2,
        "bottom left blue: {:?}",
        common::rgb(&image, cx - d, cy + d)
    );
    let white = common::rgb(&image, cx + d, cy + d);
    assert!(
        white.iter().all(|&c| c > 60) && white.iter().max().unwrap() - white.iter().min().unwrap() < 30,
        "{white:?}"
    );
    gpu.assert_clean();
}

/// A texture transform (KHR_texture_transform: scale 2 with repeat) tiles the texture: the quad
/// shows it four times, so the colour left of the centre is the texture's right column.
#[test]
fn a_texture_transform_and_wrap_mode_tile_the_texture() {
    let gpu = GpuTest::new();
    let mut scene = common::sunlit_scene("textures");
    let rgba = [[255, 0, 0, 255], [0, 255, 0, 255], [255, 0, 0, 255], [0, 255, 0, 255]].concat();
    scene.textures.push(Arc::new(Texture { name: "columns".into(), width: 2, height: 2, rgba }));
    let sampler = Sampler { nearest_mag: true, nearest_min: true, wrap_u: Wrap::Repeat, ..Default::default() };
    let mut tiled = TextureRef { sampler, ..TextureRef::new(0) };
    tiled.transform.scale = Vec2::splat(2.0);
    let mut material = Material { name: "tiled".into(), albedo: Vec3::ONE, ..Default::default() };
    material.textures[0] = Some(tiled);
    let m = scene.add_material(material);
    let mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    scene.instances.push(Instance { transform: common::scaled_at(DVec3::ZERO, 2.0), mesh, material: m, flags: 0 });
    let (_, image) = render(&gpu, &scene, "default", false);
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    // u across the quad: 0..2, so columns red, green, red, green from left to right.
    let quarter = 16;
    let colours: Vec<usize> = [-3, -1, 1, 3]
        .iter()
        .map(|&k| dominant(common::rgb(&image, (cx as i32 + k * quarter / 2) as u32, cy)))
        .collect();
    assert_eq!(
        colours,
        [0, 1, 0, 1],
        "{:?}",
        [-3, -1, 1, 3].map(|k: i32| common::rgb(&image, (cx as i32 + k * quarter / 2) as u32, cy))
    );
    gpu.assert_clean();
}

/// A fence of `columns` vertical bars (an alpha-masked material: opaque grey bars, transparent
/// gaps; `nearest` or bilinear filtering) filling the view, and a red box of side `box_side`
/// behind it.
fn fence_and_box(columns: u32, nearest: bool, box_side: f64) -> Scene {
    let mut scene = common::sunlit_scene("textures");
    let fence = common::bars_material(&mut scene, columns, nearest);
    let red =
        scene.add_material(Material { name: "red".into(), albedo: Vec3::new(0.9, 0.05, 0.05), ..Default::default() });
    let quad_mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    let cube = scene.add_mesh("cube", &common::cube_mesh(), "cube").unwrap();
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, 0.0, 1.0), 4.0),
        mesh: quad_mesh,
        material: fence,
        flags: 0,
    });
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, 0.0, -1.0), box_side),
        mesh: cube,
        material: red,
        flags: 0,
    });
    scene
}

/// A fence of vertical bars (an alpha-masked material: opaque bars, transparent gaps) in front
/// of a red box. The box shows through the gaps, the bars hide it elsewhere, and two-phase
/// occlusion culling never culls it: the masked fence occludes only where it is opaque, so the
/// culled image equals the unculled one and the oracle finds no false negative.
#[test]
fn a_box_behind_a_masked_fence_shows_through_its_holes_and_is_never_culled() {
    let gpu = GpuTest::new();
    let scene = fence_and_box(32, true, 1.0);
    let (stats, culled) = render(&gpu, &scene, "two_phase", true);
    let verify = stats.verify.expect("verified");
    assert_eq!(verify.false_negatives, 0, "missed {:?}", verify.missed);
    assert_eq!(verify.visible, 2, "the box is seen through the gaps");
    let (_, unculled) = render(&gpu, &scene, "no_cull", false);
    assert!(culled == unculled, "culling changed the image");
    // Along the middle row: red pixels (the box through gaps) and grey ones (bars) alternate.
    let cy = SIZE.1 / 2;
    let row: Vec<[u8; 3]> = (SIZE.0 / 2 - 12..SIZE.0 / 2 + 12).map(|x| common::rgb(&culled, x, cy)).collect();
    let reds = row.iter().filter(|p| p[0] as u32 > 2 * p[1] as u32 && p[0] > 40).count();
    let greys = row.iter().filter(|p| p[0].abs_diff(p[1]) < 12 && p[1] > 40).count();
    assert!(reds >= 6 && greys >= 6, "bars and gaps alternate over the box: {row:?}");
    gpu.assert_clean();
}

/// Writes `json` as `scene.gltf` in a temporary folder.
fn gltf_file(json: &serde_json::Value) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec(json).unwrap()).unwrap();
    (dir, path)
}

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    use base64::Engine;
    format!("data:{mime};base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

fn png(width: u32, height: u32, rgba: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    image::ImageEncoder::write_image(encoder, rgba, width, height, image::ExtendedColorType::Rgba8).unwrap();
    out
}

/// One triangle with positions, normals and texture coordinates (FLOAT), and a second
/// primitive whose TEXCOORD_0 accessor has the wrong type; two images, one a PNG and one not an
/// image at all; a material with a texture transform and a clamping sampler, and a masked one
/// on the broken image.
fn textured_gltf() -> serde_json::Value {
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut bin = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // positions 0..36
    bin.extend(f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0])); // normals 36..72
    bin.extend(f32s(&[0.0, 1.0, 1.0, 1.0, 0.0, 0.0])); // uvs 72..96
    let texture = png(2, 1, &[255, 0, 0, 255, 0, 0, 255, 128]);
    serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_texture_transform"],
        "buffers": [{"byteLength": bin.len(), "uri": data_uri("application/octet-stream", &bin)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
            {"buffer": 0, "byteOffset": 72, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}
        ],
        "images": [
            {"uri": data_uri("image/png", &texture), "name": "red-blue"},
            {"uri": data_uri("image/png", b"not a png at all"), "name": "broken"}
        ],
        "samplers": [{"wrapS": 33071, "wrapT": 33648, "magFilter": 9728}],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
        "materials": [
            {"name": "tiled", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                "extensions": {"KHR_texture_transform": {"scale": [2.0, 3.0], "offset": [0.5, 0.0]}}}}},
            {"name": "leaves", "alphaMode": "MASK", "alphaCutoff": 0.3,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}}
        ],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "material": 0},
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 1}
        ]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    })
}

/// The importer reads textures, samplers, texture transforms, alpha modes and texture
/// coordinates; an image that is not an image becomes the placeholder, and a texture
/// coordinate accessor of the wrong type is dropped, each with a note naming it, and the rest
/// of the scene still loads.
#[test]
fn gltf_textures_samplers_transforms_and_bad_images_import_as_documented() {
    use cullgraph::scene::gltf_import::load_with_report;
    use cullgraph::scene::source::LoadOptions;
    let (_dir, path) = gltf_file(&textured_gltf());
    let (scene, report) = load_with_report(&path, &LoadOptions::default()).unwrap();
    assert_eq!(scene.textures.len(), 2);
    let t = &scene.textures[0];
    assert_eq!((t.width, t.height), (2, 1));
    assert_eq!(t.texel(1, 0), [0, 0, 255, 128]);
    assert!(scene.textures[1].name.contains("placeholder"), "{}", scene.textures[1].name);
    let notes = report.notes.join("\n");
    assert!(notes.contains("image 1 'broken'") && notes.contains("placeholder"), "{notes}");
    assert!(notes.contains("material 'leaves'") && notes.contains("baseColorTexture"), "{notes}");
    assert!(notes.contains("TEXCOORD_0 accessor 1") && notes.contains("ignored"), "{notes}");
    assert!(!notes.contains("extensions are ignored"), "{notes}");
    let tiled = scene.materials.iter().find(|m| m.name == "tiled").unwrap();
    let r = tiled.textures[0].unwrap();
    assert_eq!(r.texture, 0);
    assert_eq!((r.transform.scale, r.transform.offset), (Vec2::new(2.0, 3.0), Vec2::new(0.5, 0.0)));
    assert_eq!(
        (r.sampler.wrap_u, r.sampler.wrap_v, r.sampler.nearest_mag),
        (Wrap::ClampToEdge, Wrap::MirroredRepeat, true)
    );
    let leaves = scene.materials.iter().find(|m| m.name == "leaves").unwrap();
    assert_eq!(leaves.alpha_mode, AlphaMode::Mask { cutoff: 0.3 });
    let uvs: Vec<[f32; 2]> = scene.vertices[..3].iter().map(|v| v.uv).collect();
    assert_eq!(uvs, [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0]]);
    assert!(scene.vertices[3..6].iter().all(|v| v.uv == [0.0, 0.0]), "the dropped coordinates are zero");
}

/// A shared test asset.
fn asset(name: &str) -> std::path::PathBuf {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets").join(name);
    if path.exists() {
        path
    } else {
        std::path::Path::new("/work/shared/assets").join(name)
    }
}

/// The first player spawn of `map` in `nexuiz_spawns.txt`: (eye, target).
fn spawn(map: &str) -> (DVec3, DVec3) {
    let text = std::fs::read_to_string(asset("nexuiz_spawns.txt")).unwrap();
    let line = text.lines().find(|l| l.starts_with(&format!("{map} "))).unwrap();
    let v = |s: &str| {
        let c: Vec<f64> = s.split(',').map(|x| x.parse().unwrap()).collect();
        DVec3::new(c[0], c[1], c[2])
    };
    let parts: Vec<&str> = line.split_whitespace().collect();
    (v(parts[1]), v(parts[2]))
}

/// The two real game levels render textured from a player's spawn point: many colours (flat
/// white-grey materials would give few), no visible instance lost to two-phase culling, and the
/// culled image equal to the unculled one (ons-reborn has alpha-masked foliage).
#[test]
fn the_real_levels_render_textured_from_a_spawn_and_culling_stays_exact() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    for (map, file) in [("aneurysm", "nexuiz_aneurysm.glb"), ("ons-reborn", "nexuiz_ons-reborn.glb")] {
        let scene = cullgraph::scene::gltf_import::load(&asset(file), &Default::default()).unwrap();
        assert!(scene.textures.len() >= 40, "{map}: {} textures", scene.textures.len());
        let (eye, target) = spawn(map);
        let camera = Camera { eye, target, ..Default::default() };
        let render = |graph: &str, verify: bool| {
            let spec = GraphSpec::builtin(graph).unwrap();
            let settings = RenderSettings::new(SIZE.0, SIZE.1);
            let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), settings, &spec).unwrap();
            if verify {
                r.enable_verification(shaders).unwrap();
            }
            r.render_to_image(&camera).unwrap();
            r.render_to_image(&camera).unwrap()
        };
        let (stats, culled) = render("two_phase", true);
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "{map}: missed {:?}", verify.missed);
        let (_, unculled) = render("no_cull", false);
        assert!(culled == unculled, "{map}: culling changed the image");
        let colours: std::collections::HashSet<[u8; 4]> = culled.pixels().map(|p| p.0).collect();
        assert!(colours.len() > 1500, "{map}: only {} distinct colours: untextured?", colours.len());
    }
    gpu.assert_clean();
}

/// The stats JSON reports the textures' device memory: at least every texel of mip 0 once
/// resampled to its class, and a third more for the mips.
#[test]
fn the_stats_report_texture_memory() {
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("stats.json");
    let scene = asset("nexuiz_aneurysm.glb");
    let (code, out, err) = common::cli::run(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--size",
        "64x36",
        "--out",
        dir.path().join("a.png").to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let bytes = json["texture_bytes"].as_u64().unwrap();
    let loaded = cullgraph::scene::gltf_import::load(&scene, &Default::default()).unwrap();
    let texels: u64 = loaded
        .textures
        .iter()
        .map(|t| {
            let side = cullgraph::passes::shared::textures::class_side(cullgraph::passes::shared::textures::class_of(
                t.width, t.height,
            )) as u64;
            side * side * 4
        })
        .sum();
    assert!(bytes >= texels * 4 / 3 && bytes < texels * 2, "{bytes} bytes for {texels} bytes of texels");
}

/// A live world registers a texture and a material that uses it; an instance given that
/// material shows the texture at the next frame. A material naming a texture that does not
/// exist is refused with an error naming the material.
#[test]
fn textured_materials_register_on_a_live_world() {
    use cullgraph::scene::world::{World, WorldError};
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = common::sunlit_scene("textures");
    let white = scene.add_material(Material { name: "white".into(), albedo: Vec3::ONE, ..Default::default() });
    let mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    scene.instances.push(Instance { transform: common::scaled_at(DVec3::ZERO, 2.0), mesh, material: white, flags: 0 });
    let (mut world, handles) = World::new(scene).unwrap();
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    let centre = |image: &RgbaImage| common::rgb(image, SIZE.0 / 2, SIZE.1 / 2);
    let before = centre(&r.render_to_image(&common::camera_on_z()).unwrap().1);
    assert!(before.iter().all(|&c| c > 100), "white first: {before:?}");

    let bad = Material {
        name: "dangling".into(),
        textures: [Some(TextureRef::new(7)), None, None, None, None],
        ..Default::default()
    };
    match world.add_material(bad) {
        Err(WorldError::Invalid { handle, message }) => {
            assert!(handle.contains("dangling") && message.contains("texture 7 does not exist"), "{handle}: {message}")
        }
        other => panic!("{other:?}"),
    }
    let blue = world.add_texture(Texture::solid("blue", [10, 20, 230, 255])).unwrap();
    let mut material = Material { name: "blue".into(), albedo: Vec3::ONE, ..Default::default() };
    material.textures[0] = Some(TextureRef::new(blue));
    let m = world.add_material(material).unwrap();
    world.set_materials(&[(handles[0], m)]).unwrap();
    r.sync(shaders, &world).unwrap();
    let after = centre(&r.render_to_image(&common::camera_on_z()).unwrap().1);
    assert_eq!(dominant(after), 2, "blue now: {after:?}");
    gpu.assert_clean();
}

/// Every method shades textures: from the aneurysm spawn, the visibility buffer (which
/// rebuilds texture coordinates and their derivatives by casting rays through neighbouring
/// pixel centres) and the compressed G-buffer, both at 4x MSAA, stay within a small FLIP of the
/// per-sample MSAA G-buffer method, and far from an untextured image.
#[test]
fn every_msaa_method_shades_the_same_textures() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = cullgraph::scene::gltf_import::load(&asset("nexuiz_aneurysm.glb"), &Default::default()).unwrap();
    let (eye, target) = spawn("aneurysm");
    let camera = Camera { eye, target, ..Default::default() };
    let render = |graph: &str, scene: &Scene| {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r =
            Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
        r.render_to_image(&camera).unwrap().1
    };
    let flip = |a: &RgbaImage, b: &RgbaImage| {
        cullgraph::oracle::image_error::mean_flip(a.as_raw(), b.as_raw(), SIZE.0, SIZE.1).unwrap()
    };
    let reference = render("msaa_per_sample", &scene);
    let mut untextured = scene.clone();
    untextured.materials.iter_mut().for_each(|m| m.textures = [None; 5]);
    let flat = flip(&reference, &render("msaa_per_sample", &untextured));
    for graph in ["visibility_buffer", "msaa_compressed"] {
        let error = flip(&reference, &render(graph, &scene));
        assert!(
            error < 0.05 && error < flat / 3.0,
            "{graph}: FLIP {error:.4} against the per-sample method (untextured: {flat:.4})"
        );
    }
    gpu.assert_clean();
}

/// Both levels from their first spawn at 320x180 through the default graph, first frame, match
/// the images in `tests/reference/` (written by this test with `CULLGRAPH_UPDATE_REFERENCE=1`)
/// within a small mean FLIP.
#[test]
fn the_real_levels_match_their_reference_images() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    for map in ["aneurysm", "ons-reborn"] {
        let scene =
            cullgraph::scene::gltf_import::load(&asset(&format!("nexuiz_{map}.glb")), &Default::default()).unwrap();
        let (eye, target) = spawn(map);
        let camera = Camera { eye, target, ..Default::default() };
        let spec = GraphSpec::builtin("default").unwrap();
        let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(320, 180), &spec).unwrap();
        let image = r.render_to_image(&camera).unwrap().1;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/reference/nexuiz_{map}.png"));
        if std::env::var_os("CULLGRAPH_UPDATE_REFERENCE").is_some() {
            image.save(&path).unwrap();
        }
        let reference = image::open(&path).unwrap().to_rgba8();
        let flip = cullgraph::oracle::image_error::mean_flip(reference.as_raw(), image.as_raw(), 320, 180).unwrap();
        assert!(flip < 0.01, "{map}: mean FLIP {flip:.4} against {}", path.display());
    }
    gpu.assert_clean();
}

/// At 4x MSAA a masked fence keeps a share of each pixel's samples where its filtered alpha
/// crosses the cutoff (alpha-to-coverage): pixels along the bars' edges mix fence and box,
/// every MSAA method and the oracle keep the same samples (0 false negatives; the compressed
/// G-buffer's image within a small FLIP of the per-sample method's).
#[test]
fn msaa_methods_give_masked_edges_partial_coverage_and_stay_exact() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    // Wide bars, filtered bilinearly: alpha ramps across each edge over a texel.
    let scene = fence_and_box(16, false, 1.5);
    let render = |graph: &str| {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r =
            Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
        r.enable_verification(shaders).unwrap();
        r.render_to_image(&common::camera_on_z()).unwrap();
        r.render_to_image(&common::camera_on_z()).unwrap()
    };
    let (stats, per_sample) = render("msaa_per_sample");
    let verify = stats.verify.expect("verified");
    assert_eq!(verify.false_negatives, 0, "missed {:?}", verify.missed);
    let cy = SIZE.1 / 2;
    let row: Vec<[u8; 3]> = (SIZE.0 / 2 - 20..SIZE.0 / 2 + 20).map(|x| common::rgb(&per_sample, x, cy)).collect();
    // The lit box is about (213, 75, 73), the fence grey; a pixel between keeps part of each.
    let red_only = |p: &[u8; 3]| p[0] as i32 - p[1] as i32 > 110;
    let grey = |p: &[u8; 3]| p[0].abs_diff(p[1]) < 12 && p[1] > 40;
    let mixed = row.iter().filter(|p| !red_only(p) && !grey(p) && p[0] as i32 - p[1] as i32 > 20).count();
    assert!(row.iter().any(red_only) && row.iter().any(grey) && mixed >= 1, "edges mix fence and box: {row:?}");
    for graph in ["msaa_compressed", "visibility_buffer"] {
        let (stats, image) = render(graph);
        assert_eq!(stats.verify.expect("verified").false_negatives, 0, "{graph}");
        let flip =
            cullgraph::oracle::image_error::mean_flip(per_sample.as_raw(), image.as_raw(), SIZE.0, SIZE.1).unwrap();
        assert!(flip < 0.02, "{graph}: mean FLIP {flip:.4} against the per-sample method");
    }
    gpu.assert_clean();
}

/// The glTF sample `TextureTransformTest` (Debian's assimp-testmodels) seen head-on: its top
/// row shows a green, a blue and a teal check mark only where `KHR_texture_transform`'s offsets
/// are applied.
#[test]
fn the_texture_transform_conformance_model_shows_its_check_marks() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let path = std::path::Path::new("/usr/share/assimp/models/glTF2/textureTransform/TextureTransformTest.gltf");
    let scene = cullgraph::scene::gltf_import::load(path, &Default::default()).unwrap();
    let camera = Camera { eye: DVec3::new(0.0, 0.0, 4.5), target: DVec3::ZERO, ..Default::default() };
    let spec = GraphSpec::builtin("default").unwrap();
    let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(320, 240), &spec).unwrap();
    let image = r.render_to_image(&camera).unwrap().1;
    let [green, blue, teal]: [[u8; 3]; 3] = [(97, 88), (160, 88), (222, 88)].map(|(x, y)| common::rgb(&image, x, y));
    let over = |a: u8, b: u8| a as i32 - b as i32 > 80;
    // Without the transforms these tiles are yellowish (the texture's unshifted corner).
    assert!(over(green[1], green[0]) && over(green[1], green[2]), "the U tile: {green:?}");
    assert!(over(blue[2], blue[0]) && over(blue[2], blue[1]), "the V tile: {blue:?}");
    assert!(over(teal[1], teal[0]) && over(teal[2], teal[0]), "the UV tile: {teal:?}");
    gpu.assert_clean();
}

/// The glTF sample `BoxTextured` (assimp-testmodels) renders its texture: the face toward the
/// camera shows many colours, where its untextured material would show a few shades.
#[test]
fn the_box_textured_conformance_model_shows_its_texture() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let path = std::path::Path::new("/usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    let scene = cullgraph::scene::gltf_import::load(path, &Default::default()).unwrap();
    let camera = Camera { eye: DVec3::new(1.5, 1.2, 2.0), target: DVec3::ZERO, ..Default::default() };
    let spec = GraphSpec::builtin("default").unwrap();
    let colours = |scene: Scene| {
        let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
        let image = r.render_to_image(&camera).unwrap().1;
        image.pixels().map(|p| p.0).collect::<std::collections::HashSet<[u8; 4]>>().len()
    };
    let mut untextured = scene.clone();
    untextured.materials.iter_mut().for_each(|m| m.textures = [None; 5]);
    let (textured, flat) = (colours(scene), colours(untextured));
    assert!(textured > 3 * flat, "{textured} colours textured, {flat} untextured");
    gpu.assert_clean();
}

/// The glTF sample `ClearCoatTest` (assimp-testmodels; `KHR_materials_clearcoat` is ignored with
/// a note): its labels are black cards whose text is an emissive texture, and its partial
/// coating is a transparent (`BLEND`) material. The labels' text glows (bright pixels the
/// same scene without emission lacks), and every instance, the transparent one included, is
/// drawn with 0 false negatives.
#[test]
fn the_clear_coat_conformance_model_shows_emissive_labels_and_its_blended_coating() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let path = std::path::Path::new("/usr/share/assimp/models/glTF2/ClearCoat-glTF/ClearCoatTest.gltf");
    let scene = cullgraph::scene::gltf_import::load(path, &Default::default()).unwrap();
    assert!(scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Blend), "the partial coating blends");
    let camera = Camera { eye: DVec3::new(0.0, 0.0, 12.0), target: DVec3::ZERO, ..Default::default() };
    let spec = GraphSpec::builtin("default").unwrap();
    let bright = |scene: Scene| {
        let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(320, 240), &spec).unwrap();
        r.enable_verification(shaders).unwrap();
        r.render_to_image(&camera).unwrap();
        let (stats, image) = r.render_to_image(&camera).unwrap();
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "missed {:?}", verify.missed);
        image.pixels().filter(|p| p.0[..3].iter().all(|&c| c > 200)).count()
    };
    let mut dark = scene.clone();
    dark.materials.iter_mut().for_each(|m| m.emissive = Vec3::ZERO);
    let (glowing, unlit) = (bright(scene), bright(dark));
    assert!(glowing > unlit + 200, "{glowing} bright pixels with emission, {unlit} without");
    gpu.assert_clean();
}

/// Every lighting method uses the occlusion and emissive textures. Under sky light alone (no
/// sun), a quad whose occlusion texture is 0 on its left half and 1 on its right is black on the
/// left and lit on the right; a quad whose emissive texture is red on its left half and black on
/// its right glows red on the left only.
#[test]
fn every_method_shades_occlusion_and_emissive_textures() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = common::sunlit_scene("textures");
    scene.sun.color = Vec3::ZERO;
    let halves = |left: [u8; 4], right: [u8; 4]| [left, right].concat();
    scene.textures.push(Arc::new(Texture {
        name: "ao".into(),
        width: 2,
        height: 1,
        rgba: halves([0, 0, 0, 255], [255; 4]),
    }));
    scene.textures.push(Arc::new(Texture {
        name: "glow".into(),
        width: 2,
        height: 1,
        rgba: halves([255, 0, 0, 255], [0, 0, 0, 255]),
    }));
    let sampler = Sampler { nearest_mag: true, nearest_min: true, ..Default::default() };
    let mut occluded = Material { name: "occluded".into(), albedo: Vec3::ONE, ..Default::default() };
    occluded.textures[3] = Some(TextureRef { sampler, ..TextureRef::new(0) });
    let mut glowing = Material { name: "glowing".into(), albedo: Vec3::ONE, emissive: Vec3::ONE, ..Default::default() };
    glowing.textures[4] = Some(TextureRef { sampler, ..TextureRef::new(1) });
    let occluded = scene.add_material(occluded);
    let glowing = scene.add_material(glowing);
    let mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, 0.6, 0.0), 1.0),
        mesh,
        material: occluded,
        flags: 0,
    });
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(0.0, -0.6, 0.0), 1.0),
        mesh,
        material: glowing,
        flags: 0,
    });
    // 0.6 world units at 3 from the eye are about 25 pixels; the quads' halves are 20 wide.
    let (cx, cy) = (SIZE.0 as i32 / 2, SIZE.1 as i32 / 2);
    let (top, bottom, side) = ((cy - 25) as u32, (cy + 25) as u32, 10);
    for graph in [
        "default",
        "fxaa",
        "msaa_per_sample",
        "msaa_zprepass",
        "msaa_compressed",
        "msaa_compressed_claim",
        "visibility_buffer",
    ] {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r =
            Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
        let image = r.render_to_image(&common::camera_on_z()).unwrap().1;
        let (shadow, lit) =
            (common::rgb(&image, (cx - side) as u32, top), common::rgb(&image, (cx + side) as u32, top));
        assert!(shadow.iter().all(|&c| c < 4), "{graph}: occluded half {shadow:?}");
        assert!(lit.iter().all(|&c| c > 40), "{graph}: unoccluded half {lit:?}");
        let (glow, plain) =
            (common::rgb(&image, (cx - side) as u32, bottom), common::rgb(&image, (cx + side) as u32, bottom));
        assert!(glow[0] > 200 && glow[0] > plain[0] + 100, "{graph}: glowing half {glow:?}, plain half {plain:?}");
        assert_eq!(dominant(plain), 2, "{graph}: the plain half has the sky's blue: {plain:?}");
    }
    gpu.assert_clean();
}

/// More bad texture input: an image file that does not exist and an image in a format the
/// importer does not decode become the placeholder with a note naming the image and the
/// material, and the scene still loads; a texture index past the file's textures is an error
/// naming the material, never a panic.
#[test]
fn missing_and_unsupported_images_and_bad_texture_indices_are_reported() {
    use cullgraph::scene::gltf_import::load_with_report;
    use cullgraph::scene::source::LoadOptions;
    let mut json = textured_gltf();
    json["images"] = serde_json::json!([
        {"uri": "no_such_file.png", "name": "missing"},
        {"uri": data_uri("image/webp", b"RIFF....WEBPVP8 "), "mimeType": "image/webp", "name": "webp"}
    ]);
    let (_dir, path) = gltf_file(&json);
    let (scene, report) = load_with_report(&path, &LoadOptions::default()).unwrap();
    let notes = report.notes.join("\n");
    assert!(notes.contains("image 0 'missing'") && notes.contains("placeholder"), "{notes}");
    assert!(notes.contains("image 1 'webp'") && notes.contains("placeholder"), "{notes}");
    assert!(scene.textures.iter().all(|t| t.name.contains("placeholder")));
    assert_eq!(scene.instances.len(), 2, "the rest of the scene loads (two primitives)");

    json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = serde_json::json!(7);
    let (_dir, path) = gltf_file(&json);
    let Err(error) = load_with_report(&path, &LoadOptions::default()) else { panic!("an index out of range loads") };
    let error = error.to_string();
    assert!(
        error.contains("scene.gltf")
            && error.contains("materials[0].pbrMetallicRoughness.baseColorTexture.index")
            && error.contains("out of bounds"),
        "{error}"
    );
}

/// A double-sided quad seen from behind is lit with its normal flipped: under a sun from the
/// camera's side its back face is as bright as the front face of the same quad turned towards the
/// camera, in every method (unflipped, it would get the sky's light alone).
#[test]
fn double_sided_back_faces_are_lit_with_the_flipped_normal() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = common::sunlit_scene("textures");
    let paper = scene.add_material(Material {
        name: "paper".into(),
        albedo: Vec3::splat(0.7),
        roughness: 1.0,
        double_sided: true,
        ..Default::default()
    });
    let mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    // Left: facing the camera. Right: turned half a turn about y, its back towards the camera.
    let turned = Mat3::from_rotation_y(std::f32::consts::PI);
    scene.instances.push(Instance {
        transform: common::scaled_at(DVec3::new(-0.6, 0.0, 0.0), 1.0),
        mesh,
        material: paper,
        flags: 0,
    });
    scene.instances.push(Instance {
        transform: Transform { linear: turned, translation: DVec3::new(0.6, 0.0, 0.0) },
        mesh,
        material: paper,
        flags: 0,
    });
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    for graph in ["default", "msaa_compressed", "visibility_buffer"] {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r =
            Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
        let image = r.render_to_image(&common::camera_on_z()).unwrap().1;
        let (front, back) = (common::rgb(&image, cx - 25, cy), common::rgb(&image, cx + 25, cy));
        assert!(front[0] > 100, "{graph}: the front face is lit: {front:?}");
        let off = (0..3).map(|c| front[c].abs_diff(back[c])).max().unwrap();
        assert!(off <= 2, "{graph}: back face {back:?} against front face {front:?}");
    }
    gpu.assert_clean();
}

/// A live world without masked materials draws with pipelines that have no alpha test; when it
/// registers a masked material and gives it to the fence, the next frame takes the alpha-tested
/// ones: the box shows through the gaps, with 0 false negatives.
#[test]
fn a_world_that_gains_a_masked_material_cuts_its_holes_at_the_next_frame() {
    use cullgraph::scene::world::World;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut scene = fence_and_box(32, true, 1.0);
    let fence = scene.instances[0].material as usize;
    let masked = scene.materials[fence].clone();
    scene.materials[fence].alpha_mode = AlphaMode::Opaque;
    let (mut world, handles) = World::new(scene).unwrap();
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.enable_verification(shaders).unwrap();
    let reds = |r: &mut Renderer| {
        r.render_to_image(&common::camera_on_z()).unwrap();
        let (stats, image) = r.render_to_image(&common::camera_on_z()).unwrap();
        let verify = stats.verify.expect("verified");
        assert_eq!(verify.false_negatives, 0, "missed {:?}", verify.missed);
        let cy = SIZE.1 / 2;
        (SIZE.0 / 2 - 12..SIZE.0 / 2 + 12)
            .map(|x| common::rgb(&image, x, cy))
            .filter(|p| p[0] as u32 > 2 * p[1] as u32 && p[0] > 40)
            .count()
    };
    assert_eq!(reds(&mut r), 0, "the opaque fence hides the box");
    let masked = world.add_material(masked).unwrap();
    world.set_materials(&[(handles[0], masked)]).unwrap();
    r.sync(shaders, &world).unwrap();
    assert!(reds(&mut r) >= 6, "the box shows through the gaps");
    gpu.assert_clean();
}

/// One texture more than a size class's array can hold (the device's `maxImageArrayLayers`,
/// 2048 on lavapipe, of distinct 16x16 textures): the scene loads; the class keeps all but its
/// last layer for the first textures, in scene order, and the two that do not fit show the
/// magenta and black placeholder there, named by `placeholder_textures`.
#[test]
fn textures_beyond_a_full_size_class_show_the_placeholder() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let layers = gpu.caps().limits.max_image_array_layers as usize;
    assert!(layers <= 4096, "a device with {layers} layers an array would make this test slow");
    let mut scene = common::sunlit_scene("textures");
    for i in 0..=layers {
        // Distinct greens, and red first.
        let texel = if i == 0 { [230, 10, 10, 255] } else { [10, 100 + (i % 150) as u8, (i / 150) as u8, 255] };
        let rgba = texel.repeat(16 * 16);
        scene.textures.push(Arc::new(Texture { name: format!("t{i}"), width: 16, height: 16, rgba }));
    }
    let mesh = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    let sampler = Sampler { nearest_mag: true, nearest_min: true, ..Default::default() };
    for (texture, x) in [(0u32, -0.6), (layers as u32, 0.6)] {
        let mut material = Material { name: format!("t{texture}"), albedo: Vec3::ONE, ..Default::default() };
        material.textures[0] = Some(TextureRef { sampler, ..TextureRef::new(texture) });
        let m = scene.add_material(material);
        let transform = common::scaled_at(DVec3::new(x, 0.0, 0.0), 1.0);
        scene.instances.push(Instance { transform, mesh, material: m, flags: 0 });
    }
    let (w, h) = (64, 48);
    let spec = GraphSpec::builtin("default").unwrap();
    let mut r = Renderer::with_graph(&gpu, shaders, scene, RenderSettings::new(w, h), &spec).unwrap();
    assert_eq!(r.gpu_scene().textures.placeholder_textures(), [layers as u32 - 1, layers as u32]);
    let image = r.render_to_image(&common::camera_on_z()).unwrap().1;
    let (left, right) = (w / 2 - 12, w / 2 + 12);
    assert_eq!(dominant(common::rgb(&image, left, h / 2)), 0, "red: {:?}", common::rgb(&image, left, h / 2));
    // The checker's texels are magenta or black: no green anywhere on the right quad.
    let texels: Vec<[u8; 3]> = (h / 2 - 6..h / 2 + 6).map(|y| common::rgb(&image, right, y)).collect();
    assert!(texels.iter().all(|p| p[1] < 40), "{texels:?}");
    assert!(texels.iter().any(|p| p[0] > 100 && p[2] > 100), "no magenta: {texels:?}");
    gpu.assert_clean();
}
