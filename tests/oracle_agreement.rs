//! The two exact-visibility oracles agree on a real scene: the GPU's unculled instance-id render
//! at every sample (what `--verify` compares culling with) and the `obvhs` ray cast through the
//! same sample positions (`src/oracle/raycast.rs`).

mod common;

use common::GpuTest;
use cullgraph::oracle::raycast::{RaycastOracle, SamplePattern};
use cullgraph::oracle::Verify;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{CameraPath, SceneSource};

/// The 2000-instance city at 128x72 along an orbit, at one sample and at 4x. Measured on
/// lavapipe: the two sets are equal in 11 of the 12 frames; in the other the id render also sees
/// one instance that no ray hits (a sliver within the rasterizer's sub-pixel snapping of a
/// sample, the limit the ray cast's docs name).
#[test]
fn the_id_render_and_the_ray_cast_see_the_same_instances_in_the_city() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (w, h) = (128, 72);
    let scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(2000), ..Default::default() }).unwrap();
    let base = scene.default_camera(w as f32 / h as f32);
    let msaa = [("msaa".to_string(), "4".to_string())];
    let (mut frames, mut equal) = (0, 0);
    for (graph, params, pattern) in
        [("two_phase", &[][..], SamplePattern::Center), ("msaa_compressed", &msaa[..], SamplePattern::Standard4x)]
    {
        let spec = GraphSpec::builtin(graph).unwrap().with_overrides(params.to_vec());
        let mut renderer =
            Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
        renderer.enable_verification(shaders).unwrap();
        for f in 0..6 {
            let camera = CameraPath::Orbit.camera_at(&base, f * 3);
            renderer.render(&camera).unwrap();
            let ids = renderer.exactly_visible();
            let rays = RaycastOracle::new(&scene, camera.eye).cast(&camera, w, h, pattern).unwrap();
            let differ: Vec<_> = ids.symmetric_difference(&rays.visible).collect();
            println!(
                "{graph} frame {f}: {} visible by ids, {} by rays, differing {differ:?}",
                ids.len(),
                rays.visible.len()
            );
            assert!(!ids.is_empty() && differ.len() <= 1, "{graph} frame {f}: the oracles differ on {differ:?}");
            frames += 1;
            equal += differ.is_empty() as u32;
        }
    }
    assert!(equal + 1 >= frames, "{equal} of {frames} frames agree exactly");
}
