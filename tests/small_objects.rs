//! Small-object culling: an instance whose screen bound covers no sample position of the
//! standard patterns is culled, and the image stays what it was, at one sample and at four,
//! with a sub-pixel jitter, frame after frame of two-phase culling (lavapipe, validation on).

mod common;

use common::GpuTest;
use cullgraph::oracle::Verify;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, Scene, SceneSource};
use glam::{DVec3, Vec2};

/// `base` (a built-in graph) with its cull pass `pass` testing small objects or not.
fn with_small_objects(base: &str, pass: &str, on: bool) -> GraphSpec {
    GraphSpec::from_text(
        &format!("{base} small_objects={on}"),
        format!(
            "Graph(name: \"{base}_{on}\", extends: \"{base}\", edits: [Set(pass: \"{pass}\", settings: {{\"small_objects\": {on}}})])"
        ),
    )
}

fn city_from_afar() -> (Scene, Camera) {
    let scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(8000), ..Default::default() }).unwrap();
    let camera = Camera { eye: DVec3::new(260.0, 190.0, 260.0), target: DVec3::ZERO, ..Default::default() };
    (scene, camera)
}

/// Renders `frames` frames of `camera` (jittered by `jitter`) through `spec` with verification
/// on; the last image, the instances drawn in the last frame, and the false negatives of all.
fn render(gpu: &GpuTest, scene: &Scene, camera: &Camera, spec: &GraphSpec, frames: u32) -> (Vec<u8>, u32, u32) {
    let shaders = gpu.shaders();
    let mut renderer = Renderer::with_graph(gpu, shaders, scene.clone(), RenderSettings::new(96, 54), spec).unwrap();
    renderer.enable_verification(shaders).unwrap();
    let mut missed = 0;
    for _ in 1..frames {
        missed += renderer.render(camera).unwrap().verify.unwrap().false_negatives;
    }
    let (stats, image) = renderer.render_to_image(camera).unwrap();
    missed += stats.verify.unwrap().false_negatives;
    (image.into_raw(), stats.drawn, missed)
}

#[test]
fn specks_are_culled_and_the_image_does_not_change_at_one_sample() {
    let gpu = GpuTest::new();
    let (scene, camera) = city_from_afar();
    let (on, drawn_on, missed_on) = render(&gpu, &scene, &camera, &with_small_objects("frustum", "cull", true), 1);
    let (off, drawn_off, missed_off) = render(&gpu, &scene, &camera, &with_small_objects("frustum", "cull", false), 1);
    let (all, _, _) = render(&gpu, &scene, &camera, &GraphSpec::builtin("no_cull").unwrap(), 1);
    assert_eq!((missed_on, missed_off), (0, 0));
    assert!(drawn_on < drawn_off, "small objects culled: {drawn_on} drawn with, {drawn_off} without");
    assert!(on == off && off == all, "culling small objects changed the image");
}

#[test]
fn specks_are_culled_and_the_image_does_not_change_at_four_samples_with_jitter() {
    let gpu = GpuTest::new();
    let (scene, mut camera) = city_from_afar();
    camera.jitter = Vec2::new(0.37, -0.21);
    let spec =
        |on| with_small_objects("msaa_per_sample", "cull_late", on).with_overrides([("msaa".into(), "4".into())]);
    // Three frames: the early phase draws what the late phase kept the frame before.
    let (on, drawn_on, missed_on) = render(&gpu, &scene, &camera, &spec(true), 3);
    let (off, drawn_off, missed_off) = render(&gpu, &scene, &camera, &spec(false), 3);
    assert_eq!((missed_on, missed_off), (0, 0));
    assert!(drawn_on < drawn_off, "small objects culled: {drawn_on} drawn with, {drawn_off} without");
    assert!(on == off, "culling small objects changed the 4-sample image");
}
