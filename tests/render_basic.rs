//! The first frame: indirect-count draws into a G-buffer, compute lighting, readback.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::{RenderSettings, Renderer};

#[test]
fn boxes_render_with_the_expected_colors() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut renderer = Renderer::new(&gpu, &shaders, boxes_scene(), RenderSettings::new(96, 64)).unwrap();
    let (stats, image) = renderer.render_to_image(&boxes_camera()).unwrap();
    assert_eq!((stats.instances, stats.draws), (4, 1));
    image.save(std::env::temp_dir().join("cullgraph_boxes.png")).unwrap();
    // Top rows see the sky (blue-ish), the middle sees geometry.
    let sky = image.get_pixel(48, 1);
    assert!(sky[2] > sky[0], "sky pixel {sky:?}");
    let distinct: std::collections::HashSet<[u8; 4]> = image.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 50, "image looks flat: {} colors", distinct.len());
}
