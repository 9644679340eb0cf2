//! Per-pixel motion vectors (`graph/post.ron`'s output `motion`): pixels from this frame's
//! position to last frame's, x right, y down, for moving instances and a moving camera, checked
//! against the same projection on the CPU; an instance that stopped has no motion the frame
//! after (its previous transform is refreshed although no update touched it); the command
//! line writes them as OpenEXR.

mod common;

use common::GpuTest;
use cullgraph::render::{GraphSpec, OutputF32, RenderSettings, Renderer, ViewId};
use cullgraph::scene::world::World;
use cullgraph::scene::{Camera, Instance, Material, Scene};
use glam::{DVec3, Vec2, Vec4};

const SIZE: (u32, u32) = (64, 48);
/// The side of each quad.
const SIDE: f64 = 0.8;

/// Two white quads facing [`common::camera_on_z`] in the plane z = 0, centred at `centres`.
fn two_quads(centres: [DVec3; 2]) -> Scene {
    let mut scene = common::sunlit_scene("two quads");
    let quad = scene.add_mesh("quad", &common::quad_mesh(), "quad").unwrap();
    let white = scene.add_material(Material { name: "white".into(), albedo: glam::Vec3::ONE, ..Default::default() });
    for centre in centres {
        scene.instances.push(Instance {
            transform: common::scaled_at(centre, SIDE),
            mesh: quad,
            material: white,
            flags: 0,
        });
    }
    scene
}

/// What a pixel shows, as the CPU sees it.
#[derive(Debug, PartialEq)]
enum Expected {
    /// Within a pixel of a quad's edge: not checked.
    Edge,
    /// No quad.
    Background,
    /// A quad, with this motion vector.
    Motion(Vec2),
}

/// The motion vector of pixel (`x`, `y`) seen by `camera` where last frame's camera was
/// `previous`, of quads in the plane z = 0 at `now` whose centres were at `before` last frame.
fn expected(camera: &Camera, previous: &Camera, now: &[DVec3], before: &[DVec3], x: u32, y: u32) -> Expected {
    let aspect = SIZE.0 as f32 / SIZE.1 as f32;
    let size = Vec2::new(SIZE.0 as f32, SIZE.1 as f32);
    let ndc = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) / size) * 2.0 - 1.0;
    let vp = camera.view_projection_rel_eye(aspect).as_dmat4();
    let on_ray = vp.inverse() * Vec4::new(ndc.x, ndc.y, 0.5, 1.0).as_dvec4();
    let direction = on_ray.truncate() / on_ray.w;
    let hit = camera.eye + direction * (-camera.eye.z / direction.z);
    // A pixel is one 64th of 2 * 3 * tan(30°) * 4 / 3 units across at the quads.
    let margin = 0.1;
    let mut near_edge = false;
    for (&centre, &was) in now.iter().zip(before) {
        let local = hit - centre;
        let inside = local.x.abs().max(local.y.abs());
        if inside < SIDE / 2.0 - margin {
            let then = hit - centre + was;
            let clip = previous.view_projection_rel_eye(aspect).as_dmat4() * (then - previous.eye).extend(1.0);
            let ndc_then = (clip.truncate().truncate() / clip.w).as_vec2();
            return Expected::Motion((ndc_then - ndc) * 0.5 * size);
        }
        near_edge |= inside < SIDE / 2.0 + margin;
    }
    if near_edge {
        Expected::Edge
    } else {
        Expected::Background
    }
}

/// Checks every pixel of `motion` against [`expected`]; returns how many pixels showed a quad.
fn check(motion: &OutputF32, camera: &Camera, previous: &Camera, now: &[DVec3], before: &[DVec3]) -> usize {
    assert_eq!((motion.width, motion.height, motion.channels), (SIZE.0, SIZE.1, 2));
    let mut quads = 0;
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let got = Vec2::from_slice(motion.pixel(x, y));
            match expected(camera, previous, now, before, x, y) {
                Expected::Edge => {}
                Expected::Background => assert_eq!(got, Vec2::ZERO, "background pixel ({x}, {y})"),
                Expected::Motion(m) => {
                    quads += 1;
                    // Halves keep 11 bits: a few thousandths of a pixel at these lengths.
                    let tolerance = 0.01 + 2e-3 * m.length();
                    assert!((got - m).abs().max_element() <= tolerance, "pixel ({x}, {y}): {got} vs {m}");
                }
            }
        }
    }
    quads
}

fn post() -> GraphSpec {
    GraphSpec::builtin("post").unwrap()
}

/// A moving instance's pixels carry its motion on screen, a still one's none; an instance that
/// moved last frame and not this one has none either (its previous transform is refreshed
/// although no update touched it this frame); and one that moves again after a pause moves from
/// where it stood.
#[test]
fn moving_instances_have_their_motion_and_stopped_ones_none() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut at = [DVec3::new(-0.6, 0.0, 0.0), DVec3::new(0.6, 0.0, 0.0)];
    let (mut world, handles) = World::new(two_quads(at)).unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut r = Renderer::from_world(&gpu, shaders, &world, settings, &post()).unwrap();
    let camera = common::camera_on_z();
    let frame = |world: &World, r: &mut Renderer| -> OutputF32 {
        r.sync(shaders, world).unwrap();
        r.render(&camera).unwrap();
        r.read_output_f32("motion").unwrap()
    };

    // The first frame: nothing moved.
    let still = frame(&world, &mut r);
    assert!(still.data.iter().all(|&v| v == 0.0), "no motion at the first frame");

    // The left quad moves right and up: its pixels came from the left and below.
    let before = at;
    at[0] += DVec3::new(0.1, 0.05, 0.0);
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    let moved = frame(&world, &mut r);
    assert!(check(&moved, &camera, &camera, &at, &before) > 100, "the quads cover pixels");
    let left = Vec2::from_slice(moved.pixel(SIZE.0 / 2 - 12, SIZE.1 / 2));
    assert!(left.x < -1.0 && left.y > 0.5, "came from the left and from below (y down): {left}");
    assert_eq!(moved.pixel(SIZE.0 / 2 + 12, SIZE.1 / 2), [0.0, 0.0], "the right quad stood still");

    // It moves on at the next frame: its motion is that frame's step alone.
    let before = at;
    at[0] += DVec3::new(0.04, -0.03, 0.0);
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    let again = frame(&world, &mut r);
    assert!(check(&again, &camera, &camera, &at, &before) > 100, "the quads cover pixels");

    // Nothing moves: no pixel has motion, although no update touched the left quad.
    let stopped = frame(&world, &mut r);
    assert!(stopped.data.iter().all(|&v| v == 0.0), "the quad that stopped has no motion");

    // The right quad moves down; the left one, which moved two frames ago, stays still.
    let before = at;
    at[1] += DVec3::new(0.0, -0.08, 0.0);
    world.set_transform(handles[1], common::scaled_at(at[1], SIDE)).unwrap();
    let other = frame(&world, &mut r);
    check(&other, &camera, &camera, &at, &before);
    assert_eq!(other.pixel(SIZE.0 / 2 - 12, SIZE.1 / 2), [0.0, 0.0], "the left quad stays still");
    assert!(other.pixel(SIZE.0 / 2 + 12, SIZE.1 / 2)[1] < -1.0, "the right quad came from above");
    gpu.assert_clean();
}

/// A still scene seen by a camera that moves and turns: every pixel's motion is the camera's,
/// from last frame's unjittered view relative to last frame's eye; the background (no geometry)
/// has none.
#[test]
fn a_moving_camera_gives_still_geometry_its_motion() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let at = [DVec3::new(-0.6, 0.0, 0.0), DVec3::new(0.6, 0.0, 0.0)];
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut r = Renderer::with_graph(&gpu, shaders, two_quads(at), settings, &post()).unwrap();
    let first = common::camera_on_z();
    r.render(&first).unwrap();
    let still = r.read_output_f32("motion").unwrap();
    assert!(still.data.iter().all(|&v| v == 0.0), "no motion without a previous camera");
    // Sideways, closer, and turned a little.
    let second = Camera { eye: DVec3::new(0.15, -0.1, 2.7), target: DVec3::new(0.05, 0.0, 0.0), ..first.clone() };
    r.render(&second).unwrap();
    let motion = r.read_output_f32("motion").unwrap();
    assert!(check(&motion, &second, &first, &at, &at) > 100, "the quads cover pixels");
    // The same camera again: no motion.
    r.render(&second).unwrap();
    let again = r.read_output_f32("motion").unwrap();
    assert!(again.data.iter().all(|&v| v == 0.0), "a camera that stopped gives no motion");
    gpu.assert_clean();
}

/// A still camera whose jitter changes every frame (as TAA's does) gives still geometry no
/// motion: motion compares this frame's and last frame's unjittered matrices, never a jittered
/// one with an unjittered one.
#[test]
fn a_jittering_still_camera_gives_no_motion() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let at = [DVec3::new(-0.6, 0.0, 0.0), DVec3::new(0.6, 0.0, 0.0)];
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut r = Renderer::with_graph(&gpu, shaders, two_quads(at), settings, &post()).unwrap();
    let camera = common::camera_on_z();
    for frame in 0..4 {
        let jittered = Camera { jitter: cullgraph::scene::projection::halton_jitter(frame + 1), ..camera.clone() };
        r.render(&jittered).unwrap();
        let motion = r.read_output_f32("motion").unwrap();
        assert!(motion.data.iter().all(|&v| v == 0.0), "frame {frame}: jitter shows as motion");
        // The quads are there: depth above 0 at many pixels.
        let depth = r.read_output_f32("depth").unwrap();
        assert!(depth.data.iter().filter(|&&d| d > 0.0).count() > 100, "frame {frame}: the quads cover pixels");
    }
    gpu.assert_clean();
}

/// `cullgraph render --motion-out` writes the motion output as OpenEXR (R = x, G = y, B = 0),
/// exactly what the library reads back for the same frames; the default graph is refused
/// before rendering, naming the flag, the graph and `--graph builtin:post`.
#[test]
fn the_command_line_writes_motion_as_openexr() {
    let dir = std::env::temp_dir().join(format!("cullgraph-motion-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("motion.exr");
    let (arg, png) = (path.to_str().unwrap(), dir.join("f.png").to_str().unwrap().to_string());
    let base = [
        "render",
        "--scene",
        "builtin:city",
        "--instances",
        "300",
        "--size",
        "64x48",
        "--out",
        &png,
        "--frames",
        "2",
        "--camera-path",
        "orbit",
    ];
    let with = |extra: &[&str]| common::cli::run(&[&base[..], extra].concat());

    let (status, _, err) = with(&["--motion-out", arg]);
    assert_eq!(status, 1, "{err}");
    assert!(
        err.contains("--motion-out") && err.contains("graph 'default'") && err.contains("--graph builtin:post"),
        "{err}"
    );

    let (status, _, err) = with(&["--graph", "builtin:post", "--motion-out", arg]);
    assert_eq!(status, 0, "{err}");
    let exr = image::open(&path).unwrap().to_rgba32f();
    assert_eq!((exr.width(), exr.height()), SIZE);

    let gpu = GpuTest::new();
    let (scene, camera) = common::city_view(300, SIZE);
    let mut r = Renderer::with_graph(&gpu, gpu.shaders(), scene, RenderSettings::new(SIZE.0, SIZE.1), &post()).unwrap();
    for frame in 0..2 {
        r.render(&cullgraph::scene::CameraPath::Orbit.camera_at(&camera, frame)).unwrap();
    }
    let motion = r.read_output_f32("motion").unwrap();
    let expected: Vec<f32> = motion.data.chunks_exact(2).flat_map(|m| [m[0], m[1], 0.0, 1.0]).collect();
    assert_eq!(exr.as_raw(), &expected, "the EXR holds the motion output in R and G");
    let moving = motion.data.chunks_exact(2).filter(|m| m[0] != 0.0 || m[1] != 0.0).count();
    assert!(moving > 500, "the orbiting camera moves most of the city: {moving} pixels");
    gpu.assert_clean();
}

/// A mesh registered while a quad moves is written in place: that frame shows the move. A world
/// laid out anew (here: its journal trimmed past the renderer's last sync) starts with previous
/// = current: that frame shows no motion, not the contents of a fresh buffer, and the next move
/// shows as before.
#[test]
fn a_rebuilt_scene_starts_without_motion() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut at = [DVec3::new(-0.6, 0.0, 0.0), DVec3::new(0.6, 0.0, 0.0)];
    let (mut world, handles) = World::new(two_quads(at)).unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut r = Renderer::from_world(&gpu, shaders, &world, settings, &post()).unwrap();
    let camera = common::camera_on_z();
    let frame = |world: &World, r: &mut Renderer| -> (OutputF32, bool) {
        let stats = r.sync(shaders, world).unwrap();
        r.render(&camera).unwrap();
        (r.read_output_f32("motion").unwrap(), stats.relayout)
    };
    frame(&world, &mut r);
    let before = at;
    at[0].x += 0.1;
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    world.add_mesh("another quad", &common::quad_mesh()).unwrap();
    let (registered, relayout) = frame(&world, &mut r);
    assert!(!relayout, "a registration keeps the layout");
    assert!(check(&registered, &camera, &camera, &at, &before) > 100, "the move shows beside a registration");
    at[0].x += 0.1;
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    world.trim_journal(world.version());
    let (rebuilt, relayout) = frame(&world, &mut r);
    assert!(relayout, "a journal that no longer reaches the last sync lays the world out anew");
    assert!(rebuilt.data.iter().all(|&v| v == 0.0), "a rebuilt scene shows no motion at its first frame");
    let before = at;
    at[0].x += 0.1;
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    let (moved, _) = frame(&world, &mut r);
    assert!(check(&moved, &camera, &camera, &at, &before) > 100, "the quads cover pixels");
    gpu.assert_clean();
}

/// A world renderer keeps the previous frame's instance records only while a view's graph
/// writes motion vectors: none for a graph without them; a view added with them gets them, made
/// from the records before the frame's moves, so that its first frame already shows the moves
/// since the last frame; removing it drops them again.
#[test]
fn previous_records_are_kept_only_while_a_view_writes_motion() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut at = [DVec3::new(-0.6, 0.0, 0.0), DVec3::new(0.6, 0.0, 0.0)];
    let (mut world, handles) = World::new(two_quads(at)).unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let spec = GraphSpec::builtin("two_phase").unwrap();
    let mut r = Renderer::from_world(&gpu, shaders, &world, settings.clone(), &spec).unwrap();
    let camera = common::camera_on_z();
    r.render(&camera).unwrap();
    assert!(r.gpu_scene().prev_instances.is_none(), "no view writes motion");

    let view = r.add_view(shaders, settings, &post()).unwrap();
    let before = at;
    let frame = |world: &World, r: &mut Renderer| -> OutputF32 {
        r.sync(shaders, world).unwrap();
        r.render_views(&[(ViewId::MAIN, &camera), (view, &camera)]).unwrap();
        r.read_view_output_f32(view, "motion").unwrap()
    };
    at[0].x += 0.1;
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    let first = frame(&world, &mut r);
    assert!(r.gpu_scene().prev_instances.is_some(), "a view writes motion");
    assert!(check(&first, &camera, &camera, &at, &before) > 100, "the quads cover pixels");
    let before = at;
    at[0].x += 0.1;
    world.set_transform(handles[0], common::scaled_at(at[0], SIDE)).unwrap();
    let moved = frame(&world, &mut r);
    assert!(check(&moved, &camera, &camera, &at, &before) > 100, "the quads cover pixels");

    r.remove_view(view).unwrap();
    r.render(&camera).unwrap();
    assert!(r.gpu_scene().prev_instances.is_none(), "no view writes motion any more");
    gpu.assert_clean();
}
