//! Rendered frames of real scenes: a checked-in reference image, coverage, determinism and
//! large-world precision.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::output::RgbaImage;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Scene, SceneSource};
use glam::DVec3;

fn render(
    gpu: &GpuTest,
    scene: Scene,
    settings: RenderSettings,
    camera: Option<cullgraph::scene::Camera>,
) -> RgbaImage {
    let camera = camera.unwrap_or_else(|| scene.default_camera(settings.width as f32 / settings.height as f32));
    let mut renderer = Renderer::new(gpu, gpu.shaders(), scene, settings).unwrap();
    renderer.render_to_image(&camera).unwrap().1
}

/// (pixels whose largest channel difference exceeds `threshold`, mean absolute channel difference)
fn difference(a: &RgbaImage, b: &RgbaImage, threshold: u8) -> (usize, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let mut over = 0;
    let mut sum = 0u64;
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0);
        over += (d > threshold) as usize;
        sum += (0..3).map(|c| p[c].abs_diff(q[c]) as u64).sum::<u64>();
    }
    (over, sum as f64 / (a.width() * a.height() * 3) as f64)
}

#[test]
fn city_frame_matches_the_checked_in_reference() {
    let gpu = GpuTest::new();
    let scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(2000), ..Default::default() }).unwrap();
    let image = render(&gpu, scene, RenderSettings::new(128, 72), None);

    // Not blank: the street view has sky above, darker street below, and many colors.
    let distinct: std::collections::HashSet<[u8; 4]> = image.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 200, "only {} distinct colors", distinct.len());
    let luma =
        |y: u32| (0..128).map(|x| image.get_pixel(x, y).0[..3].iter().map(|&c| c as u32).sum::<u32>()).sum::<u32>();
    assert!(luma(70) < luma(1), "the street should be darker than the sky");

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/city_128x72.png");
    if std::env::var_os("CULLGRAPH_UPDATE_REFERENCE").is_some() {
        image.save(&path).unwrap();
    }
    let reference = image::open(&path).expect("reference image (CULLGRAPH_UPDATE_REFERENCE=1 writes it)").to_rgba8();
    let (over, mean) = difference(&image, &reference, 12);
    // Tolerance for rasterizer/driver differences: a few edge pixels, a small mean error.
    assert!(over <= 128 * 72 / 100 && mean < 1.0, "{over} pixels differ by more than 12, mean difference {mean:.3}");
}

#[test]
fn monastery_draws_all_81_meshes_and_covers_the_view() {
    let gpu = GpuTest::new();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/monastery.glb");
    let source = if path.exists() { path } else { std::path::PathBuf::from("/work/shared/assets/monastery.glb") };
    let scene = SceneSource::File(source).load(&LoadOptions::default()).unwrap();
    let camera = scene.default_camera(96.0 / 54.0);
    let mut renderer = Renderer::new(&gpu, gpu.shaders(), scene.clone(), RenderSettings::new(96, 54)).unwrap();
    let (stats, _) = renderer.render_to_image(&camera).unwrap();
    assert_eq!((stats.instances, stats.draws, stats.triangles), (81, 81, 124_789));
    // The albedo view paints the uniform 0.64 grey of every monastery material: count it.
    let spec = GraphSpec::default_graph().with_overrides([("debug_view".to_string(), "albedo".to_string())]);
    let mut albedo_renderer =
        Renderer::with_graph(&gpu, gpu.shaders(), scene, RenderSettings::new(96, 54), &spec).unwrap();
    let albedo = albedo_renderer.render_to_image(&camera).unwrap().1;
    let grey = albedo.pixels().filter(|p| p[0] == p[1] && p[1] == p[2] && p[0].abs_diff(163) <= 1).count();
    let share = grey as f64 / (96.0 * 54.0);
    assert!((0.05..0.8).contains(&share), "monastery covers {share:.3} of the view");
}

#[test]
fn frames_are_deterministic() {
    let gpu = GpuTest::new();
    let scene =
        SceneSource::Builtin("field".into()).load(&LoadOptions { instances: Some(500), ..Default::default() }).unwrap();
    let camera = scene.default_camera(80.0 / 60.0);
    let mut renderer = Renderer::new(&gpu, gpu.shaders(), scene, RenderSettings::new(80, 60)).unwrap();
    let a = renderer.render_to_image(&camera).unwrap().1;
    let b = renderer.render_to_image(&camera).unwrap().1;
    assert!(a.as_raw() == b.as_raw(), "two renders of the same frame differ");
}

#[test]
fn a_scene_ten_million_units_from_the_origin_renders_the_same_image_as_at_the_origin() {
    let gpu = GpuTest::new();
    let settings = RenderSettings::new(96, 64);
    // The same frame moved by `offset`, scene and camera together.
    let moved = |scene: &Scene, camera: &cullgraph::scene::Camera, offset: DVec3| {
        let mut scene = scene.clone();
        scene.translate(offset);
        let mut camera = camera.clone();
        camera.eye += offset;
        camera.target += offset;
        render(&gpu, scene, settings.clone(), Some(camera))
    };
    let city =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(2000), ..Default::default() }).unwrap();
    let city_camera = city.default_camera(96.0 / 64.0);
    for (name, scene, camera) in [("boxes", boxes_scene(), boxes_camera()), ("city", city, city_camera)] {
        let near = render(&gpu, scene.clone(), settings.clone(), Some(camera.clone()));
        for offset in [DVec3::new(1.0e7, 0.0, -1.0e7), DVec3::new(-3.0e6, 250.0, 9_999_999.0)] {
            let far = moved(&scene, &camera, offset);
            let (over, mean) = difference(&near, &far, 0);
            // Whole offsets move only the hi parts of the positions (exact), so not one bit changes.
            assert_eq!(over, 0, "{name} at {offset}: {over} pixels differ (mean {mean:.4})");
        }
    }
}
