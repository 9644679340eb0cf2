//! The first frame: indirect-count draws into a G-buffer, compute lighting, readback.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::{RenderSettings, Renderer};

#[test]
fn boxes_render_with_the_expected_colors() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut renderer = Renderer::new(&gpu, shaders, boxes_scene(), RenderSettings::new(96, 64)).unwrap();
    let (stats, image) = renderer.render_to_image(&boxes_camera()).unwrap();
    assert_eq!((stats.instances, stats.draws), (4, 1));
    image.save(std::env::temp_dir().join("cullgraph_boxes.png")).unwrap();
    // Top rows see the sky (blue-ish), the middle sees geometry.
    let sky = image.get_pixel(48, 1);
    assert!(sky[2] > sky[0], "sky pixel {sky:?}");
    let distinct: std::collections::HashSet<[u8; 4]> = image.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 50, "image looks flat: {} colors", distinct.len());
}

/// The G-buffer's color targets are not cleared by default: readers tell background by depth.
/// Whatever earlier frames left in background texels must never reach the image, with or
/// without MSAA (the per-sample lighting compares samples, background ones included).
#[test]
fn uncleared_gbuffer_colors_never_reach_the_image() {
    use cullgraph::graph::SettingOverride;
    use cullgraph::render::GraphSpec;
    use cullgraph::scene::CameraPath;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    for (graph, msaa) in [("two_phase", None), ("msaa_per_sample", Some("4")), ("msaa_zprepass", Some("4"))] {
        let render = |clear: bool| {
            let mut spec = GraphSpec::builtin(graph).unwrap();
            if clear {
                // Every pass that draws the G-buffer's colors first.
                let passes: &[&str] = if graph == "msaa_zprepass" { &["gbuffer"] } else { &["draw_early"] };
                spec = spec.with_settings(passes.iter().map(|p| SettingOverride {
                    pass: p.to_string(),
                    setting: "clear_colors".into(),
                    value: "true".into(),
                }));
            }
            if let Some(samples) = msaa {
                spec = spec.with_overrides([("msaa".to_string(), samples.to_string())]);
            }
            let mut r = Renderer::with_graph(&gpu, shaders, boxes_scene(), RenderSettings::new(48, 32), &spec).unwrap();
            // The orbit moves geometry over texels that were background and back.
            (0..4).map(|f| r.render_to_image(&CameraPath::Orbit.camera_at(&boxes_camera(), f * 2)).unwrap().1).collect()
        };
        let (cleared, uncleared): (Vec<_>, Vec<_>) = (render(true), render(false));
        for (f, (a, b)) in cleared.iter().zip(&uncleared).enumerate() {
            assert!(a.as_raw() == b.as_raw(), "{graph}, frame {f}: clearing the colors changes the image");
        }
    }
    gpu.assert_clean();
}
