//! GPU timestamps as plain data: each pass's pair on the frame's GPU timeline.
//! (Apart from tests/profiling.rs, whose puffin frames must see only their own renderer.)

mod common;

use common::{city_view, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};

/// GPU times come as timestamp pairs on the frame's timeline (`start_ms`, `ms`), from which a
/// host can draw GPU zones in its own profiler: the passes follow one another in execution
/// order (each timestamp waits for the commands before it), each step of a multi-dispatch pass
/// lies within its pass, and everything within the frame.
#[test]
fn gpu_timings_place_each_pass_on_the_frames_timeline() {
    let gpu = GpuTest::new();
    let (w, h) = (64, 36);
    let (scene, camera) = city_view(500, (w, h));
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let mut renderer = Renderer::with_graph(&gpu, &gpu.shaders(), scene, RenderSettings::new(w, h), &spec).unwrap();
    renderer.set_step_timing(true);
    let stats = (0..3).map(|_| renderer.render(&camera).unwrap()).last().unwrap();
    gpu.assert_clean();
    let passes: Vec<String> = renderer.plan().passes.iter().map(|p| p.name.clone()).collect();
    let timings = &stats.gpu_ms;
    let of = |name: &str| timings.iter().find(|t| t.name == name).unwrap_or_else(|| panic!("{name} in {timings:?}"));
    let end = |t: &cullgraph::gpu::PassTiming| t.start_ms + t.ms;
    // Ticks convert to milliseconds with rounding: allow a nanosecond.
    let eps = 1e-6;
    for pair in passes.windows(2) {
        let (a, b) = (of(&pair[0]), of(&pair[1]));
        assert!(a.start_ms >= 0.0 && b.start_ms + eps >= end(a), "{} then {}: {timings:?}", a.name, b.name);
    }
    assert!(end(of(passes.last().unwrap())) <= stats.gpu_total_ms + eps, "{timings:?}");
    let steps: Vec<_> = timings.iter().filter(|t| t.name.contains('/')).collect();
    assert!(!steps.is_empty(), "the cull pass's steps are timed: {timings:?}");
    for step in steps {
        let pass = of(step.name.split('/').next().unwrap());
        assert!(step.start_ms + eps >= pass.start_ms && end(step) <= end(pass) + eps, "{step:?} within {pass:?}");
    }
}
