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
            let mut r = Renderer::with_graph(&gpu, &shaders, scene.clone(), settings, spec).unwrap();
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
