//! Cluster culling (lavapipe, validation on): a `cluster_cull` pass before each draw of a
//! culled list draws the clustered instances cluster by cluster, dropping the clusters outside
//! the frustum, facing away or behind the Hi-Z, and the image stays the one the list draws
//! whole: at any level of detail, for mirrored and stretched instances, and under two-phase
//! culling, whose late phase tests clusters against the pyramid.

mod common;

use common::dense::{dense, graph, near_camera, sphere};
use common::GpuTest;
use cullgraph::oracle::Verify;
use cullgraph::passes::cluster_cull::{ClusterPassStats, GROUP};
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::{Camera, Instance, Scene, Transform};
use cullgraph::stats::ClusterVerifyStats;
use glam::{DVec3, Mat3, Vec3};

const SIZE: (u32, u32) = (160, 90);

/// The last frame of `cameras` (one frame each) through `spec`: its cluster passes' figures
/// and its RGBA bytes; no frame missed a visible instance, nor a visible cluster of an
/// instance drawn cluster by cluster.
fn render(gpu: &GpuTest, scene: &Scene, cameras: &[Camera], spec: &GraphSpec) -> (Vec<ClusterPassStats>, Vec<u8>) {
    let (passes, image, _) = render_checked(gpu, scene, cameras, spec);
    (passes, image)
}

/// [`render`], with the last frame's cluster check.
fn render_checked(
    gpu: &GpuTest,
    scene: &Scene,
    cameras: &[Camera],
    spec: &GraphSpec,
) -> (Vec<ClusterPassStats>, Vec<u8>, Option<ClusterVerifyStats>) {
    let shaders = gpu.shaders();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut renderer = Renderer::with_graph(gpu, shaders, scene.clone(), settings, spec).unwrap();
    renderer.enable_verification(shaders).unwrap();
    let missed = |stats: &cullgraph::stats::FrameStats| {
        let v = stats.verify.as_ref().unwrap();
        v.false_negatives + v.clusters.as_ref().map_or(0, |c| c.false_negatives)
    };
    let (last, before) = cameras.split_last().unwrap();
    for camera in before {
        assert_eq!(missed(&renderer.render(camera).unwrap()), 0);
    }
    let (stats, image) = renderer.render_to_image(last).unwrap();
    assert_eq!(missed(&stats), 0, "{:?}", stats.verify);
    gpu.assert_clean();
    let clusters = stats.verify.as_ref().and_then(|v| v.clusters.clone());
    (stats.entries::<ClusterPassStats>(GROUP), image.into_raw(), clusters)
}

/// Clusters tested, drawn and dropped as back-facing and occluded over a frame's passes, and
/// triangles tested and drawn.
fn totals(passes: &[ClusterPassStats]) -> (u32, u32, u32, u32, u64, u64) {
    passes.iter().fold((0, 0, 0, 0, 0, 0), |t, p| {
        (
            t.0 + p.tested,
            t.1 + p.drawn,
            t.2 + p.backfacing,
            t.3 + p.occlusion_culled,
            t.4 + p.triangles_tested,
            t.5 + p.triangles_drawn,
        )
    })
}

#[test]
fn clusters_drop_triangles_and_keep_the_image() {
    let gpu = GpuTest::new();
    let scene = dense(40);
    let cameras = vec![near_camera(); 3];
    for threshold in [0.0, 2.0] {
        // Every exact graph draws the same image without clusters (tests/culling.rs and
        // tests/lod.rs hold them to it), so one of them gives each clustered graph its image.
        let (none, whole) = render(&gpu, &scene, &cameras, &graph("two_phase", threshold));
        assert!(none.is_empty());
        for name in ["frustum", "two_phase", "occluder_prepass"] {
            let clustered = format!("{name}_clusters");
            let (passes, image, check) = render_checked(&gpu, &scene, &cameras, &graph(&clustered, threshold));
            assert!(image == whole, "{clustered} at {threshold} px drew another image than two_phase");
            // Checked cluster by cluster: every visible cluster drawn, and some dropped that
            // were not visible.
            let check = check.expect("instances drawn cluster by cluster at full detail");
            assert!(check.instances > 0 && check.visible > 0 && check.false_negatives == 0, "{check:?}");
            assert!(check.drawn >= check.visible, "{check:?}");
            let (tested, drawn, backfacing, _, triangles_tested, triangles_drawn) = totals(&passes);
            eprintln!("{clustered} at {threshold} px: {drawn} of {tested} clusters, {triangles_drawn} of {triangles_tested} triangles");
            assert!(tested > 100 && drawn < tested && backfacing > 0, "{passes:?}");
            assert!(triangles_drawn * 10 < triangles_tested * 9, "{passes:?}");
        }
    }
}

#[test]
fn mirrored_and_stretched_instances_keep_their_image() {
    let gpu = GpuTest::new();
    let scene = dense(40);
    let mut odd = scene.clone();
    for (k, instance) in odd.instances.iter_mut().enumerate() {
        // Every other prop mirrored across x, every third stretched along y (no cone test).
        if k % 2 == 1 {
            instance.transform.linear *= Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
        }
        if k % 3 == 1 {
            instance.transform.linear *= Mat3::from_diagonal(Vec3::new(1.0, 1.6, 1.0));
        }
    }
    let cameras = vec![near_camera(); 3];
    let (_, whole) = render(&gpu, &odd, &cameras, &graph("two_phase", 0.0));
    let (passes, image) = render(&gpu, &odd, &cameras, &graph("two_phase_clusters", 0.0));
    assert!(image == whole, "mirrored or stretched instances drew another image cluster by cluster");
    let (tested, _, backfacing, ..) = totals(&passes);
    assert!(backfacing > 0 && backfacing < tested, "{passes:?}");
}

#[test]
fn the_late_phase_drops_clusters_behind_the_pyramid() {
    let gpu = GpuTest::new();
    let mut scene = dense(4);
    let rock = scene.instances.iter().find(|i| scene.meshes[i.mesh as usize].name == "dense/rock").unwrap().mesh;
    let wall = scene.add_mesh("wall", &common::cube_mesh(), "wall").unwrap();
    let at = |mesh, scale: Vec3, translation: DVec3| Instance {
        transform: Transform { linear: Mat3::from_diagonal(scale), translation },
        mesh,
        material: 0,
        flags: 0,
    };
    let size = scene.meshes[rock as usize].sphere.radius;
    // A wall 10 units ahead, and behind it a rock whose upper half shows over it.
    scene.instances = vec![
        at(wall, Vec3::new(0.4, 6.0, 40.0), DVec3::new(10.0, 0.0, 0.0)),
        at(rock, Vec3::splat(4.0 / size), DVec3::new(22.0, 3.0, 0.0)),
    ];
    let eye = DVec3::new(0.0, 1.0, 0.0);
    // The first frame looks down at the wall alone; the second turns to the rock, which only
    // the late phase tests, against a pyramid of the wall the early phase drew.
    let cameras = [
        Camera { eye, target: DVec3::new(10.0, -9.0, 0.0), ..Default::default() },
        Camera { eye, target: DVec3::new(22.0, 3.0, 0.0), ..Default::default() },
    ];
    let (_, whole) = render(&gpu, &scene, &cameras, &graph("two_phase", 0.0));
    let (passes, image) = render(&gpu, &scene, &cameras, &graph("two_phase_clusters", 0.0));
    assert!(image == whole, "the late phase drew another image cluster by cluster");
    let late = passes.iter().find(|p| p.pass == "clusters_late").unwrap();
    // The oracle checks the late phase's clusters too (render_checked asserts none missed).
    assert!(late.tested > 0 && late.occlusion_culled > 0 && late.drawn > 0, "{late:?}");
}

#[test]
fn the_command_line_switches_clusters_on_and_off() {
    use common::cli::run;
    let tmp = tempfile::tempdir().unwrap();
    let image = |clusters: &str| {
        let out = tmp.path().join(format!("{clusters}.png"));
        let stats = tmp.path().join(format!("{clusters}.json"));
        let args = ["render", "--scene", "builtin:dense", "--instances", "12", "--size", "96x54", "--frames", "2"];
        let (out_s, stats_s) = (out.to_str().unwrap(), stats.to_str().unwrap());
        let (code, _, err) = run(&[&args[..], &["--clusters", clusters, "--out", out_s, "--stats", stats_s]].concat());
        assert_eq!(code, 0, "{err}");
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        (std::fs::read(&out).unwrap(), json["frames"][1]["clusters"].as_array().map_or(0, |a| a.len()))
    };
    let (off, off_passes) = image("off");
    let (on, on_passes) = image("on");
    assert!(on == off, "--clusters on changed the image");
    assert_eq!((off_passes, on_passes), (0, 2));
    let (code, _, err) = run(&["render", "--clusters", "on", "--graph", "builtin:one_phase", "--out", "x.png"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("has no cluster variant"), "{err}");
}

#[test]
fn moving_instances_keep_their_image_cluster_by_cluster() {
    use cullgraph::scene::world::World;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = dense(40);
    let camera = near_camera();
    // The same world in two renderers, with and without cluster culling, moved alike each
    // frame: every prop turns and drifts, so its clusters face the eye anew.
    let (mut world, handles) = World::new(scene.clone()).unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut plain = Renderer::from_world(&gpu, shaders, &world, settings.clone(), &graph("two_phase", 0.0)).unwrap();
    let mut clustered =
        Renderer::from_world(&gpu, shaders, &world, settings, &graph("two_phase_clusters", 0.0)).unwrap();
    let mut dropped = 0;
    for frame in 0..4 {
        let angle = 0.35 * frame as f32;
        let changes: Vec<_> = handles
            .iter()
            .zip(&scene.instances)
            .skip(1)
            .map(|(&h, instance)| {
                let mut t = instance.transform;
                t.linear = Mat3::from_rotation_y(angle) * t.linear;
                t.translation += DVec3::new(0.3 * frame as f64, 0.0, -0.2 * frame as f64);
                (h, t)
            })
            .collect();
        world.set_transforms(&changes).unwrap();
        plain.sync(shaders, &world).unwrap();
        clustered.sync(shaders, &world).unwrap();
        let (_, whole) = plain.render_to_image(&camera).unwrap();
        let (stats, image) = clustered.render_to_image(&camera).unwrap();
        assert!(image.into_raw() == whole.into_raw(), "frame {frame}: moved instances drew another image");
        let passes = stats.entries::<ClusterPassStats>(GROUP);
        dropped += totals(&passes).2;
    }
    assert!(dropped > 0);
    gpu.assert_clean();
}

#[test]
fn a_camera_inside_a_prop_or_far_from_the_origin_sees_the_same_image() {
    let gpu = GpuTest::new();
    let scene = dense(40);
    // Inside the bound of a rock, a unit from its centre, looking out through its surface and
    // at the props beyond; and the whole scene 10^7 units out.
    let rock = scene.instances.iter().find(|i| scene.meshes[i.mesh as usize].name == "dense/rock").unwrap();
    let centre = rock.transform.translation;
    let inside =
        Camera { eye: centre + DVec3::new(0.4, 0.6, 0.3), target: DVec3::new(0.0, 1.0, 0.0), ..Default::default() };
    let offset = DVec3::new(1.0e7, 0.0, -1.0e7);
    let mut far = scene.clone();
    far.translate(offset);
    let near = near_camera();
    let far_camera = Camera { eye: near.eye + offset, target: near.target + offset, ..near.clone() };
    for (what, scene, camera) in [("inside a rock", &scene, inside), ("10^7 units out", &far, far_camera)] {
        let cameras = vec![camera; 3];
        let (_, whole) = render(&gpu, scene, &cameras, &graph("two_phase", 0.0));
        let (passes, image) = render(&gpu, scene, &cameras, &graph("two_phase_clusters", 0.0));
        assert!(image == whole, "{what}: another image cluster by cluster");
        assert!(totals(&passes).0 > 0, "{what}: {passes:?}");
    }
}

#[test]
fn meshes_registered_on_a_live_world_are_culled_cluster_by_cluster() {
    use cullgraph::scene::merge::SceneMerge;
    use cullgraph::scene::world::World;
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let camera = near_camera();
    let (mut world, _) = World::new(dense(4)).unwrap();
    let settings = RenderSettings::new(SIZE.0, SIZE.1);
    let mut plain = Renderer::from_world(&gpu, shaders, &world, settings.clone(), &graph("two_phase", 0.0)).unwrap();
    let mut clustered =
        Renderer::from_world(&gpu, shaders, &world, settings, &graph("two_phase_clusters", 0.0)).unwrap();
    clustered.enable_verification(shaders).unwrap();
    // Each step changes the world; both renderers follow it and draw the same image, the
    // clustered one checked cluster by cluster.
    let mut step = |world: &World, what: &str| {
        plain.sync(shaders, world).unwrap();
        clustered.sync(shaders, world).unwrap();
        for _ in 0..2 {
            plain.render(&camera).unwrap();
            clustered.render(&camera).unwrap();
        }
        let (_, whole) = plain.render_to_image(&camera).unwrap();
        let (stats, image) = clustered.render_to_image(&camera).unwrap();
        assert!(image.into_raw() == whole.into_raw(), "{what}: another image cluster by cluster");
        let verify = stats.verify.unwrap();
        let check = verify.clusters.clone().unwrap_or_default();
        assert_eq!((verify.false_negatives, check.false_negatives), (0, 0), "{what}: {verify:?}");
        check
    };
    step(&world, "the world as loaded");
    // Props streamed in beside the first: their meshes come with clusters.
    let placement = Transform { linear: Mat3::IDENTITY, translation: DVec3::new(-6.0, 0.0, 4.0) };
    SceneMerge::new(dense(24), placement).unwrap().add_all(&mut world).unwrap();
    let merged = step(&world, "a scene merged in");
    assert!(merged.instances > 4, "{merged:?}");
    // A mesh the engine registers gets clusters; unregistered, its pool space and index go
    // to the next one, whose clusters replace its own.
    let ball = world.add_mesh("ball", &sphere(64, 128)).unwrap();
    assert!(!world.scene().meshes[ball as usize].clusters.is_empty());
    let at = |mesh| Instance {
        transform: Transform { linear: Mat3::from_diagonal(Vec3::splat(2.0)), translation: DVec3::new(6.0, 2.0, 6.0) },
        mesh,
        material: 0,
        flags: 0,
    };
    let handle = world.insert(at(ball)).unwrap();
    let with_ball = step(&world, "a registered mesh");
    assert!(with_ball.instances > merged.instances, "{with_ball:?}");
    world.remove(handle).unwrap();
    world.remove_mesh(ball).unwrap();
    step(&world, "a mesh unregistered");
    let again = world.add_mesh("ball again", &sphere(48, 160)).unwrap();
    world.insert(at(again)).unwrap();
    step(&world, "another mesh in its place");
    gpu.assert_clean();
}

/// A UV sphere of radius 1 with texture coordinates (u around, v pole to pole), 16 384
/// triangles: clustered, and holed where a masked material's texture is transparent.
fn textured_sphere() -> cullgraph::scene::MeshData {
    let (rings, segments) = (64u32, 128u32);
    let mut mesh = sphere(rings, segments);
    mesh.uvs = (0..=rings)
        .flat_map(|r| (0..=segments).map(move |s| glam::Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32)))
        .collect();
    mesh
}

/// Spheres in a row, opaque, masked and double-sided (bars of a texture whose gaps discard),
/// and masked one-sided, before the camera.
fn masked_spheres() -> Scene {
    use cullgraph::scene::Material;
    let mut scene = Scene::default();
    let ball = scene.add_mesh("ball", &textured_sphere(), "ball").unwrap();
    let opaque = scene.add_material(Material { name: "opaque".into(), ..Default::default() });
    let double_sided = common::bars_material(&mut scene, 16, true);
    let mut one_sided = scene.materials[double_sided as usize].clone();
    one_sided.name = "bars, one-sided".into();
    one_sided.double_sided = false;
    let one_sided = scene.add_material(one_sided);
    for (k, material) in [opaque, double_sided, one_sided, double_sided, one_sided, opaque].into_iter().enumerate() {
        scene.instances.push(Instance {
            transform: Transform {
                linear: Mat3::from_diagonal(Vec3::splat(1.5)),
                translation: DVec3::new(k as f64 * 3.5 - 8.75, 1.5, 0.0),
            },
            mesh: ball,
            material,
            flags: 0,
        });
    }
    scene
}

#[test]
fn masked_instances_are_culled_cluster_by_cluster_and_keep_their_holes() {
    let gpu = GpuTest::new();
    let scene = masked_spheres();
    let cameras =
        vec![Camera { eye: DVec3::new(0.0, 4.0, 11.0), target: DVec3::new(0.0, 1.5, 0.0), ..Default::default() }; 3];
    for name in ["frustum", "two_phase", "occluder_prepass"] {
        let (_, whole) = render(&gpu, &scene, &cameras, &graph(name, 0.0));
        let clustered = format!("{name}_clusters");
        let (passes, image, check) = render_checked(&gpu, &scene, &cameras, &graph(&clustered, 0.0));
        assert!(image == whole, "{clustered} drew another image than {name}");
        let check = check.expect("instances drawn cluster by cluster");
        assert!(check.false_negatives == 0 && check.visible > 0, "{check:?}");
        let (tested, drawn, backfacing, ..) = totals(&passes);
        assert!(drawn < tested && backfacing > 0, "{clustered}: {passes:?}");
    }
    // Every sphere masked: drawn cluster by cluster all the same.
    let mut masked = scene.clone();
    for instance in &mut masked.instances {
        instance.material = 2;
    }
    let (_, whole) = render(&gpu, &masked, &cameras, &graph("two_phase", 0.0));
    let (passes, image) = render(&gpu, &masked, &cameras, &graph("two_phase_clusters", 0.0));
    assert!(image == whole, "masked spheres drew another image cluster by cluster");
    let (tested, drawn, backfacing, ..) = totals(&passes);
    assert!(tested > 0 && drawn < tested && backfacing > 0, "{passes:?}");
    assert!(passes.iter().all(|p| p.whole_commands == 0), "a masked command was drawn whole: {passes:?}");
}
