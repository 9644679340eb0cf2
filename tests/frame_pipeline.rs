//! Headless frames that do not wait for each other (`FramePipeline`, what `cullgraph render`
//! uses): each frame's figures come back `FRAMES_IN_FLIGHT` frames after it was submitted, and
//! they are the same figures as when every frame is waited for.

mod common;

use common::{city_view, GpuTest};
use cullgraph::passes::instance_cull::CullPassStats;
use cullgraph::render::{FramePipeline, GraphSpec, RenderSettings, Renderer, FRAMES_IN_FLIGHT};
use cullgraph::scene::CameraPath;
use cullgraph::stats::FrameStats;

/// What must not depend on how the frames were submitted.
fn counters(s: &FrameStats) -> impl PartialEq + std::fmt::Debug {
    let passes: Vec<_> = CullPassStats::of(s)
        .iter()
        .map(|p| (p.pass.clone(), p.tested, p.frustum_culled, p.occlusion_culled, p.drawn))
        .collect();
    (s.frame, s.instances, s.frustum_culled, s.occlusion_culled, s.drawn, s.draws, s.triangles, passes)
}

#[test]
fn pipelined_frames_report_late_and_exactly_what_waited_frames_report() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (w, h) = (96, 54);
    let (scene, base) = city_view(3000, (w, h));
    let frames = 8u32;
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let new_renderer = || Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(w, h), &spec).unwrap();

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

#[test]
fn pipelined_frames_wait_on_and_signal_the_hosts_timeline_semaphore() {
    use ash::vk;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (w, h) = (64, 36);
    let (scene, camera) = city_view(500, (w, h));
    let mut renderer = Renderer::new(&gpu, shaders, scene, RenderSettings::new(w, h)).unwrap();
    let device = gpu.device();
    let mut timeline = vk::SemaphoreTypeCreateInfo::default().semaphore_type(vk::SemaphoreType::TIMELINE);
    let semaphore =
        unsafe { device.create_semaphore(&vk::SemaphoreCreateInfo::default().push_next(&mut timeline), None) }.unwrap();
    let at = |value: u64| {
        vk::SemaphoreSubmitInfo::default()
            .semaphore(semaphore)
            .value(value)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
    };
    let counter = || unsafe { device.get_semaphore_counter_value(semaphore) }.unwrap();
    let wait_for = |value: u64| {
        let (semaphores, values) = ([semaphore], [value]);
        let info = vk::SemaphoreWaitInfo::default().semaphores(&semaphores).values(&values);
        unsafe { device.wait_semaphores(&info, 10_000_000_000) }.unwrap();
    };

    let mut pipeline = FramePipeline::new(&gpu).unwrap();
    // Frame 0 signals 1 once it has executed.
    assert!(pipeline.submit_with(&mut renderer, &camera, &[], &[at(1)]).unwrap().is_none());
    wait_for(1);
    // Frame 1 waits for 2, which the host signals from the CPU only later, and then signals 3.
    assert!(pipeline.submit_with(&mut renderer, &camera, &[at(2)], &[at(3)]).unwrap().is_none());
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert_eq!(counter(), 1, "frame 1 ran before the value it waits for was signalled");
    unsafe { device.signal_semaphore(&vk::SemaphoreSignalInfo::default().semaphore(semaphore).value(2)) }.unwrap();
    wait_for(3);
    let frames = pipeline.finish(&renderer).unwrap();
    assert_eq!(frames.iter().map(|s| s.frame).collect::<Vec<_>>(), [0, 1]);
    assert!(frames.iter().all(|s| s.drawn > 0 && s.drawn == frames[0].drawn), "both frames drew the same view");
    drop(pipeline);
    unsafe { device.destroy_semaphore(semaphore, None) };
}
