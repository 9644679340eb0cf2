//! Headless frames that do not wait for each other (`FramePipeline`, what `cullgraph render`
//! uses): each frame's figures come back `FRAMES_IN_FLIGHT` frames after it was submitted, and
//! they are the same figures as when every frame is waited for.

mod common;

use common::GpuTest;
use cullgraph::render::{FramePipeline, GraphSpec, RenderSettings, Renderer, FRAMES_IN_FLIGHT};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{CameraPath, SceneSource};
use cullgraph::stats::FrameStats;

/// What must not depend on how the frames were submitted.
fn counters(s: &FrameStats) -> impl PartialEq + std::fmt::Debug {
    let passes: Vec<_> =
        s.culling.iter().map(|p| (p.pass.clone(), p.tested, p.frustum_culled, p.occlusion_culled, p.drawn)).collect();
    (s.frame, s.instances, s.frustum_culled, s.occlusion_culled, s.drawn, s.draws, s.triangles, passes)
}

#[test]
fn pipelined_frames_report_late_and_exactly_what_waited_frames_report() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(3000), ..Default::default() }).unwrap();
    let (w, h) = (96, 54);
    let base = scene.default_camera(w as f32 / h as f32);
    let frames = 8u32;
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let new_renderer =
        || Renderer::with_graph(&gpu, &shaders, scene.clone(), RenderSettings::new(w, h), &spec).unwrap();

    let mut waited = new_renderer();
    let expected: Vec<FrameStats> =
        (0..frames).map(|f| waited.render(&CameraPath::Orbit.camera_at(&base, f)).unwrap()).collect();

    let mut renderer = new_renderer();
    let mut pipeline = FramePipeline::new(&gpu).unwrap();
    let mut got = Vec::new();
    for f in 0..frames {
        let earlier = pipeline.submit(&mut renderer, &CameraPath::Orbit.camera_at(&base, f)).unwrap();
        // Nothing comes back until a command buffer comes round again, then the frame that used it.
        let late = (f as u64).checked_sub(FRAMES_IN_FLIGHT as u64);
        assert_eq!(earlier.as_ref().map(|s| s.frame), late, "submitting frame {f}");
        got.extend(earlier);
    }
    let rest = pipeline.finish(&renderer).unwrap();
    assert_eq!(rest.len(), FRAMES_IN_FLIGHT, "finish returns every frame still in flight");
    got.extend(rest);
    assert!(pipeline.finish(&renderer).unwrap().is_empty(), "each frame's figures come back once");

    assert_eq!(got.len(), frames as usize);
    // The orbit changes what is drawn, so equal figures are not a coincidence of a still view.
    assert!(expected.iter().any(|s| s.drawn != expected[0].drawn));
    for (g, e) in got.iter().zip(&expected) {
        assert_eq!(counters(g), counters(e));
        assert!(g.gpu_total_ms > 0.0 && g.gpu_ms.iter().any(|t| t.name == "cull_late"), "frame {}: timings", g.frame);
    }
}
