//! The AA baselines against the supersampled reference (lavapipe, validation on): the no-AA frame
//! (`two_phase`), FXAA (`fxaa`), the compressed-G-buffer MSAA frames (`msaa_compressed`,
//! `msaa_compressed_claim`) and the other MSAA baselines (`msaa_per_sample`, `msaa_zprepass`,
//! `visibility_buffer`), each measured by mean FLIP and PSNR against a 4 x 4 supersampled
//! `no_cull` render of the same frame of the city at 128x72; plus the reference's own checks and
//! errors.
//!
//! Measured on lavapipe (LLVM 15), city (10,000 instances, seed 1), default camera, 128x72, MSAA
//! graphs at 4x (the only count lavapipe has):
//!
//! | graph                   | mean FLIP | PSNR     |
//! |-------------------------|-----------|----------|
//! | `two_phase` no AA       | 0.0383    | 28.25 dB |
//! | `fxaa` (preset 39)      | 0.0424    | 30.18 dB |
//! | `msaa_compressed`       | 0.0104    | 41.60 dB |
//! | `msaa_compressed_claim` | 0.0104    | 41.60 dB |
//! | `msaa_per_sample`       | 0.0106    | 41.60 dB |
//! | `msaa_zprepass`         | 0.0106    | 41.60 dB |
//! | `visibility_buffer`     | 0.0101    | 41.60 dB |
//!
//! The rows come from one run, so they compare with each other. The MSAA rows agree because every
//! method shades the same inputs the same way: the visibility buffer shades the 8-bit albedo and
//! roughness every G-buffer method stores, not the material's floats (the 8-bit steps of a dark
//! albedo shift whole surfaces by about one output level, which FLIP counts everywhere), and the
//! per-sample lighting shades two parallel surfaces of one material in one pixel each at its own
//! depth.
//!
//! FXAA lowers the pixel error (PSNR +1.9 dB) but FLIP rates it slightly *worse* than no AA here
//! (and at 256x144 and 640x360, and on the test boxes scene, for every preset and with `subpix`
//! 0): FLIP's edge-feature term penalizes the blur FXAA puts on straight, axis-aligned edges more
//! than it credits the smoothed stair steps. The test states that ordering as measured instead
//! of asserting the hoped-for one.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::oracle::reference_error;
use cullgraph::oracle::ImageError;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::procedural;
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, Scene};
use std::sync::Arc;

const SIZE: (u32, u32) = (128, 72);

/// The city, shared by the renderers of every graph and reference made of it.
fn city() -> (Arc<Scene>, Camera) {
    let scene = procedural::generate("builtin:city", &LoadOptions::default()).unwrap();
    let camera = scene.default_camera(SIZE.0 as f32 / SIZE.1 as f32);
    (Arc::new(scene), camera)
}

fn error(gpu: &GpuTest, scene: &Arc<Scene>, camera: &Camera, graph: &str, n: u32) -> ImageError {
    error_with(gpu, scene, camera, graph, &[], n)
}

/// `error` of the graph with param overrides.
fn error_with(
    gpu: &GpuTest,
    scene: &Arc<Scene>,
    camera: &Camera,
    graph: &str,
    params: &[(&str, &str)],
    n: u32,
) -> ImageError {
    let spec =
        GraphSpec::builtin(graph).unwrap().with_overrides(params.iter().map(|(k, v)| (k.to_string(), v.to_string())));
    let e = reference_error(gpu, gpu.shaders(), scene, camera, &spec, SIZE, n).unwrap();
    eprintln!(
        "{} through {graph} {params:?}, {n}x{n} reference: mean FLIP {:.4}, PSNR {:.2} dB",
        scene.name, e.mean_flip, e.psnr_db
    );
    assert_eq!(e.samples_per_pixel, n * n);
    e
}

#[test]
fn msaa_beats_no_aa_and_fxaa_lowers_pixel_error_on_the_city() {
    let gpu = GpuTest::new();
    let (scene, camera) = city();
    let no_aa = error(&gpu, &scene, &camera, "two_phase", 4);
    let fxaa = error(&gpu, &scene, &camera, "fxaa", 4);
    let msaa = error(&gpu, &scene, &camera, "msaa_compressed", 4);

    // Bounds: the measured figures (module docs) with margin.
    assert!(no_aa.mean_flip > 0.02 && no_aa.mean_flip < 0.06, "no AA: {no_aa:?}");
    assert!(fxaa.mean_flip < 0.06, "FXAA: {fxaa:?}");
    assert!(msaa.mean_flip < 0.015, "MSAA: {msaa:?}");
    assert!(msaa.psnr_db > 38.0, "MSAA: {msaa:?}");

    // MSAA over the compressed G-buffer is far closer to the reference than no AA.
    assert!(msaa.mean_flip < no_aa.mean_flip * 0.5, "MSAA {msaa:?} against no AA {no_aa:?}");
    assert!(msaa.psnr_db > no_aa.psnr_db + 8.0, "MSAA {msaa:?} against no AA {no_aa:?}");
    // FXAA lowers the pixel error, and stays within FLIP's reach of no AA (see the module docs
    // for why its FLIP is not lower).
    assert!(fxaa.psnr_db > no_aa.psnr_db + 1.0, "FXAA {fxaa:?} against no AA {no_aa:?}");
    assert!(fxaa.mean_flip < no_aa.mean_flip * 1.25, "FXAA {fxaa:?} against no AA {no_aa:?}");
    assert!(msaa.mean_flip < fxaa.mean_flip && msaa.psnr_db > fxaa.psnr_db);
}

/// The other MSAA graphs at 4x (the only count lavapipe has) against the same reference: each
/// renders, stays within its measured error (module docs; bounds with about 15 % headroom on
/// FLIP, 2 dB on PSNR) and beats no AA by a wide margin.
#[test]
fn every_msaa_baseline_is_within_its_bound_and_beats_no_aa_on_the_city() {
    let gpu = GpuTest::new();
    let (scene, camera) = city();
    let no_aa = error(&gpu, &scene, &camera, "two_phase", 4);
    // (graph, mean FLIP below, PSNR above, FLIP below this fraction of no AA's)
    let cases = [
        ("msaa_per_sample", 0.0122, 39.5, 0.5),       // measured 0.0106, 41.60 dB
        ("msaa_zprepass", 0.0122, 39.5, 0.5),         // measured 0.0106, 41.60 dB
        ("visibility_buffer", 0.0116, 39.5, 0.5),     // measured 0.0101, 41.60 dB
        ("msaa_compressed_claim", 0.0120, 39.5, 0.5), // measured 0.0104, 41.60 dB
    ];
    let mut errors = Vec::new();
    for (graph, max_flip, min_psnr, of_no_aa) in cases {
        let e = error_with(&gpu, &scene, &camera, graph, &[("msaa", "4")], 4);
        assert!(e.mean_flip < max_flip && e.psnr_db > min_psnr, "{graph}: {e:?}");
        assert!(e.mean_flip < no_aa.mean_flip * of_no_aa, "{graph} {e:?} against no AA {no_aa:?}");
        assert!(e.psnr_db > no_aa.psnr_db + 8.0, "{graph} {e:?} against no AA {no_aa:?}");
        errors.push(e);
    }
    // The Z-prepass only moves the depth test: the same image as per-sample MSAA, the same error.
    assert_eq!(errors[0], errors[1], "per-sample and Z-prepass MSAA");
}

#[test]
fn a_one_sample_reference_is_the_unculled_frame_itself() {
    // With 1 x 1 samples the reference is the no_cull frame: no_cull and two_phase (which is
    // pixel-identical to it) have no error at all, which also shows that the reference renders
    // the same frame (scene, camera, shading) as the graph under test.
    let gpu = GpuTest::new();
    for graph in ["no_cull", "two_phase"] {
        let e = error(&gpu, &Arc::new(boxes_scene()), &boxes_camera(), graph, 1);
        assert_eq!((e.mean_flip, e.psnr_db), (0.0, f64::INFINITY), "{graph}");
    }
}

#[test]
fn fxaa_touches_only_edge_pixels_and_takes_its_settings() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let render = |spec: GraphSpec| {
        let settings = RenderSettings::new(SIZE.0, SIZE.1);
        let mut r = Renderer::with_graph(&gpu, shaders, boxes_scene(), settings, &spec).unwrap();
        r.render_to_image(&boxes_camera()).unwrap().1
    };
    let plain = render(GraphSpec::builtin("two_phase").unwrap());
    let fxaa = render(GraphSpec::builtin("fxaa").unwrap());
    let changed = plain.pixels().zip(fxaa.pixels()).filter(|(a, b)| a != b).count();
    let total = (SIZE.0 * SIZE.1) as usize;
    assert!(changed > 0 && changed < total / 5, "{changed} of {total} pixels changed");

    // Thresholds above any contrast: nothing is processed. Another preset still filters.
    let off = GraphSpec::builtin("fxaa")
        .unwrap()
        .with_overrides([("fxaa_edge_threshold_min".to_string(), "2.0".to_string())]);
    assert_eq!(render(off), plain);
    let preset12 = GraphSpec::builtin("fxaa").unwrap().with_overrides([("fxaa_preset".to_string(), "12".to_string())]);
    assert_ne!(render(preset12), plain);
    // A preset FXAA does not have is a load error, not a panic.
    let bad = GraphSpec::builtin("fxaa").unwrap().with_overrides([("fxaa_preset".to_string(), "13".to_string())]);
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let err = Renderer::with_graph(&gpu, shaders, boxes_scene(), settings, &bad).err().expect("preset 13 refused");
    assert!(err.to_string().contains("13"), "{err}");
}

#[test]
fn impossible_references_are_clear_errors() {
    let gpu = GpuTest::new();
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let (scene, camera) = (Arc::new(boxes_scene()), boxes_camera());
    let max = gpu.caps().limits.max_image_dimension2_d;
    let wide = (max / 2 + 1, 4);
    let err = reference_error(&gpu, gpu.shaders(), &scene, &camera, &spec, wide, 2).unwrap_err().to_string();
    assert!(err.contains("maxImageDimension2D"), "{err}");
    let err = reference_error(&gpu, gpu.shaders(), &scene, &camera, &spec, (8, 8), 0).unwrap_err().to_string();
    assert!(err.contains("not 0"), "{err}");
    let err = reference_error(&gpu, gpu.shaders(), &scene, &camera, &spec, (8, 8), u32::MAX).unwrap_err().to_string();
    assert!(err.contains("maxImageDimension2D"), "{err}");
}
