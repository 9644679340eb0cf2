//! Outputs for an engine's post-processing: linear HDR colour with tone mapping as a pass of its
//! own, depth, motion vectors, and their f32 readback.

mod common;

use common::GpuTest;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};

const SIZE: (u32, u32) = (64, 48);

/// A graph file (in a fresh temporary folder) extending the shipped graph `base` with `body`.
fn graph_file(name: &str, base: &str, body: &str) -> GraphSpec {
    let dir = std::env::temp_dir().join(format!("cullgraph-post-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.ron"));
    std::fs::write(&path, format!("Graph(name: \"{name}\", extends: \"{base}\", {body})")).unwrap();
    GraphSpec::from_file(&path).unwrap()
}

/// Tone mapping moved out of the lighting passes into a pass of its own changes the shipped
/// graphs' images by at most one 8-bit level in a few pixels: the HDR image holds halves, whose
/// rounding (2^-11 relative) crosses an 8-bit step now and then. The same graph with the
/// lighting tone-mapping in place (what every lighting kind still does into an 8-bit output) is
/// the image before the split.
#[test]
fn tone_mapping_as_a_pass_keeps_the_shipped_images_within_one_level() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = common::city_view(400, SIZE);
    // (FXAA, after it, turns a level of difference at an edge into several: it is left out.)
    for base in ["default", "msaa_per_sample", "msaa_compressed", "visibility_buffer"] {
        let render = |spec: &GraphSpec| {
            let settings = RenderSettings::new(SIZE.0, SIZE.1);
            let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), settings, spec).unwrap();
            r.render_to_rgba8(&camera).unwrap();
            r.render_to_rgba8(&camera).unwrap().1
        };
        let split = render(&GraphSpec::builtin(base).unwrap());
        let in_place = render(&graph_file(
            &format!("in_place_{base}"),
            base,
            r#"edits: [Remove(pass: "tonemap"), Set(pass: "lighting", writes: {"output": "color"})]"#,
        ));
        let diffs: Vec<u8> = split.iter().zip(&in_place).map(|(a, b)| a.abs_diff(*b)).collect();
        let pixels = diffs.chunks(4).filter(|d| d.iter().any(|&x| x > 0)).count();
        let max = diffs.iter().copied().max().unwrap_or(0);
        println!("{base}: {pixels} of {} pixels differ, by at most {max}", SIZE.0 * SIZE.1);
        assert!(max <= 1, "{base}: a channel differs by {max} levels");
        assert!(pixels * 8 <= (SIZE.0 * SIZE.1) as usize, "{base}: {pixels} pixels differ");
    }
    gpu.assert_clean();
}

/// A white quad of side 1.92 at the origin facing [`common::camera_on_z`] (3 units away, near
/// 0.1), lit by a bright point light just in front of its centre. At 64x48 its edges cross
/// pixels short of their centres, so that MSAA sees them where one sample does not.
fn lit_quad() -> cullgraph::scene::Scene {
    use cullgraph::scene::{Instance, Material, PointLight};
    let mut scene = common::sunlit_scene("lit quad");
    let quad = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    let white = scene.add_material(Material { name: "white".into(), albedo: glam::Vec3::ONE, ..Default::default() });
    scene.instances.push(Instance {
        transform: common::scaled_at(glam::DVec3::ZERO, 1.92),
        mesh: quad,
        material: white,
        flags: 0,
    });
    let light = PointLight::point(glam::DVec3::new(0.0, 0.0, 0.5), glam::Vec3::splat(40.0), 4.0);
    scene.lights.push(light);
    scene
}

/// The depth output holds reversed-Z depth (near / distance along the view axis: 0.1 / 3 at the
/// quad, 0 for the background), and the HDR output linear colour above 1.0 where the light is,
/// which the tonemap pass turned into the 8-bit colour.
#[test]
fn depth_and_hdr_outputs_read_back_as_f32() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let spec = GraphSpec::builtin("post").unwrap();
    let mut r = Renderer::with_graph(&gpu, shaders, lit_quad(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    let color = r.render_to_rgba8(&common::camera_on_z()).unwrap().1;
    let depth = r.read_output_f32("depth").unwrap();
    let hdr = r.read_output_f32("hdr").unwrap();
    assert_eq!((depth.width, depth.height, depth.channels, hdr.channels), (SIZE.0, SIZE.1, 1, 4));
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    let expected = 0.1f32 / 3.0;
    assert!((depth.pixel(cx, cy)[0] - expected).abs() < expected * 1e-5, "centre depth {:?}", depth.pixel(cx, cy));
    assert_eq!(depth.pixel(0, 0), [0.0], "the corner is background");
    let centre = hdr.pixel(cx, cy);
    assert!(centre[..3].iter().all(|&c| c > 1.0), "the lit centre is brighter than 1.0: {centre:?}");
    // The tonemap pass's curve, on the CPU, gives the 8-bit image from the HDR one.
    let aces = |x: f32| ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
    let srgb = |c: f32| if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    for (x, y) in [(cx, cy), (cx + 10, cy - 7), (0, 0)] {
        let at = ((y * SIZE.0 + x) * 4) as usize;
        for c in 0..3 {
            let expected = srgb(aces(hdr.pixel(x, y)[c] * 0.8)) * 255.0;
            assert!(
                (color[at + c] as f32 - expected).abs() <= 0.51,
                "({x}, {y}) channel {c}: {} vs {expected}",
                color[at + c]
            );
        }
    }
    // An unknown name and a graph without the output are clear errors.
    let err = r.read_output_f32("motion_vectors").unwrap_err().to_string();
    assert!(err.contains("no output 'motion_vectors'") && err.contains("color, hdr, depth"), "{err}");
    gpu.assert_clean();
}

/// An MSAA graph exports one depth per pixel: the nearest sample (reversed-Z: the largest), so
/// the quad's silhouette keeps the quad's depth, and its HDR colour resolved per pixel.
#[test]
fn msaa_depth_resolves_to_the_nearest_sample() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("graph/examples/msaa_post.ron");
    let spec = GraphSpec::from_file(&path).unwrap();
    let mut r = Renderer::with_graph(&gpu, shaders, lit_quad(), RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.render(&common::camera_on_z()).unwrap();
    let depth = r.read_output_f32("depth_resolved").unwrap();
    let quad = 0.1f32 / 3.0;
    let values: std::collections::BTreeSet<u32> = depth.data.iter().map(|d| d.to_bits()).collect();
    // Only two depths: the flat quad's (within its rasterised rounding) and the background's.
    assert!(depth.data.iter().all(|&d| d == 0.0 || (d - quad).abs() < quad * 1e-4), "{} depths", values.len());
    // Every pixel that the single-sample graph's quad covers, or that an edge touches, is the quad.
    let covered = depth.data.iter().filter(|&&d| d > 0.0).count();
    let mut single = Renderer::with_graph(
        &gpu,
        shaders,
        lit_quad(),
        RenderSettings::new(SIZE.0, SIZE.1),
        &GraphSpec::builtin("post").unwrap(),
    )
    .unwrap();
    single.render(&common::camera_on_z()).unwrap();
    let single_covered = single.read_output_f32("depth").unwrap().data.iter().filter(|&&d| d > 0.0).count();
    assert!(covered > single_covered, "edge pixels keep the quad: {covered} vs {single_covered} pixels");
    let err = r.read_output_f32("depth").unwrap_err().to_string();
    assert!(err.contains("no output 'depth'"), "{err}");
    gpu.assert_clean();
}

/// `cullgraph render --hdr-out --depth-out` write 32-bit float OpenEXR images holding exactly
/// what the library reads back; a graph without the outputs is refused before rendering, naming
/// the flag, the graph and the graph that has them.
#[test]
fn the_command_line_writes_hdr_and_depth_as_openexr() {
    let dir = std::env::temp_dir().join(format!("cullgraph-post-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (hdr_path, depth_path) = (dir.join("hdr.exr"), dir.join("depth.exr"));
    let (hdr_arg, depth_arg, png) =
        (hdr_path.to_str().unwrap(), depth_path.to_str().unwrap(), dir.join("f.png").to_str().unwrap().to_string());
    let base = ["render", "--scene", "builtin:city", "--instances", "300", "--size", "64x48", "--out", &png];
    let with = |extra: &[&str]| common::cli::run(&[&base[..], extra].concat());

    let (status, _, err) = with(&["--hdr-out", hdr_arg]);
    assert_eq!(status, 1, "{err}");
    assert!(
        err.contains("--hdr-out") && err.contains("graph 'default'") && err.contains("--graph builtin:post"),
        "{err}"
    );

    let (status, _, err) = with(&["--graph", "builtin:post", "--hdr-out", hdr_arg, "--depth-out", depth_arg]);
    assert_eq!(status, 0, "{err}");
    let hdr = image::open(&hdr_path).unwrap().to_rgba32f();
    let depth = image::open(&depth_path).unwrap().to_rgba32f();
    assert_eq!((hdr.width(), hdr.height(), depth.width(), depth.height()), (64, 48, 64, 48));

    let gpu = GpuTest::new();
    let (scene, camera) = common::city_view(300, (64, 48));
    let spec = GraphSpec::builtin("post").unwrap();
    let mut r = Renderer::with_graph(&gpu, gpu.shaders(), scene, RenderSettings::new(64, 48), &spec).unwrap();
    r.render(&camera).unwrap();
    let (lib_hdr, lib_depth) = (r.read_output_f32("hdr").unwrap(), r.read_output_f32("depth").unwrap());
    assert_eq!(hdr.as_raw(), &lib_hdr.data, "the EXR holds the HDR output");
    let grey: Vec<f32> = lib_depth.data.iter().flat_map(|&d| [d, d, d, 1.0]).collect();
    assert_eq!(depth.as_raw(), &grey, "the EXR holds the depth output in R, G and B");
    let centre = lib_depth.pixel(32, 24)[0];
    assert!(centre > 0.0 && centre < 1.0, "the city's centre is a surface: {centre}");
    gpu.assert_clean();
}
