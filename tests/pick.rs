//! Picking: the object id of each pixel (`builtin:post`'s `object_id`) names the instance seen
//! there, and 0 (no instance) exactly where the depth shows the background.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer, ViewId};
use cullgraph::scene::world::World;

#[test]
fn each_pixel_names_the_instance_it_shows() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (w, h) = (64, 48);
    let (world, handles) = World::new(boxes_scene()).unwrap();
    // The albedo debug view shows each pixel's material: the picked instance's must match it.
    let spec = GraphSpec::builtin("post").unwrap().with_overrides([("debug_view".to_string(), "albedo".to_string())]);
    let mut r = Renderer::from_world(&gpu, shaders, &world, RenderSettings::new(w, h), &spec).unwrap();
    r.render(&boxes_camera()).unwrap();
    let (_, image) = r.render_to_rgba8(&boxes_camera()).unwrap();
    let depth = r.read_output_f32("depth").unwrap();
    let mut seen = std::collections::BTreeSet::new();
    for y in 0..h {
        for x in 0..w {
            let picked = r.pick_handle(ViewId::MAIN, x, y).unwrap();
            let background = depth.pixel(x, y)[0] == 0.0;
            assert_eq!(picked.is_none(), background, "pixel ({x}, {y})");
            let Some(handle) = picked else { continue };
            seen.insert(handle);
            let material = world.instance(handle).unwrap().material;
            let p = &image[((y * w + x) * 4) as usize..][..3];
            let (r8, g8, b8) = (p[0] as i32, p[1] as i32, p[2] as i32);
            match material {
                0 => assert!((r8 - g8).abs() < 8 && (g8 - b8).abs() < 8, "ground at ({x}, {y}): {p:?}"),
                1 => assert!(r8 > g8 + 40 && r8 > b8 + 40, "red at ({x}, {y}): {p:?}"),
                2 => assert!(b8 > r8 + 40 && b8 > g8 + 20, "blue at ({x}, {y}): {p:?}"),
                other => panic!("material {other}"),
            }
        }
    }
    assert_eq!(seen.len(), handles.len(), "every box and the ground are in view");
    let e = r.pick(ViewId::MAIN, w, 0).unwrap_err().to_string();
    assert!(e.contains("pixel (64, 0) is outside the 64x48 output"), "{e}");
    let mut plain = Renderer::new(&gpu, shaders, boxes_scene(), RenderSettings::new(w, h)).unwrap();
    plain.render(&boxes_camera()).unwrap();
    assert!(plain.pick(ViewId::MAIN, 0, 0).unwrap_err().to_string().contains("has no output 'object_id'"));
    gpu.assert_clean();
}
