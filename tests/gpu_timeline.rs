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
    // The steps each graph's multi-dispatch passes time (a scene that never changes has block
    // bounds, which the cull decides blocks from before its test).
    let graphs = [
        ("two_phase", &["cull_late/blocks", "cull_late/test", "cull_late/compact"][..]),
        (
            "msaa_compressed",
            &["cull_late/blocks", "cull_late/test", "cull_late/compact", "gbuffer/clear", "gbuffer/draw"][..],
        ),
    ];
    for (graph, expected_steps) in graphs {
        let (scene, camera) = city_view(500, (w, h));
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut renderer = Renderer::with_graph(&gpu, gpu.shaders(), scene, RenderSettings::new(w, h), &spec).unwrap();
        renderer.set_step_timing(true);
        let stats = (0..3).map(|_| renderer.render(&camera).unwrap()).last().unwrap();
        gpu.assert_clean();
        let passes: Vec<String> = renderer.plan().passes.iter().map(|p| p.name.clone()).collect();
        let timings = &stats.gpu_ms;
        let of = |name: &str| {
            timings.iter().find(|t| t.name == name).unwrap_or_else(|| panic!("{graph}: {name} in {timings:?}"))
        };
        let end = |t: &cullgraph::gpu::PassTiming| t.start_ms + t.ms;
        // Ticks convert to milliseconds with rounding: allow a nanosecond.
        let eps = 1e-6;
        for pair in passes.windows(2) {
            let (a, b) = (of(&pair[0]), of(&pair[1]));
            assert!(
                a.start_ms >= 0.0 && b.start_ms + eps >= end(a),
                "{graph}: {} then {}: {timings:?}",
                a.name,
                b.name
            );
        }
        assert!(end(of(passes.last().unwrap())) <= stats.gpu_total_ms + eps, "{graph}: {timings:?}");
        let steps: Vec<&str> = timings.iter().filter(|t| t.name.contains('/')).map(|t| t.name.as_str()).collect();
        assert_eq!(steps, expected_steps, "{graph}: the timed steps");
        for step in steps.iter().map(|name| of(name)) {
            let pass = of(step.name.split('/').next().unwrap());
            assert!(step.start_ms + eps >= pass.start_ms && end(step) <= end(pass) + eps, "{step:?} within {pass:?}");
        }
    }
}
