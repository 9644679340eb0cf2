//! The instance-cull pass's draw lists are exactly what a CPU reference computes from the same
//! packed bounds: per draw group, the survivors in slot order, one command per non-empty
//! group in group order. Many mesh kinds (groups spanning and sharing blocks), sparse and dense
//! survivors, sizes that are not multiples of the block.

mod common;

use common::GpuTest;
use cullgraph::cull::math::{aabb_in_frustum, CullView};
use cullgraph::oracle::Verify;
use cullgraph::passes::instance_cull::CullPassStats;
use cullgraph::passes::shared::cull_data::{CullData, CULL_HUGE};
use cullgraph::passes::shared::scene_buffers::DrawList;
use cullgraph::render::DrawnInstances;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, CameraPath, SceneSource};
use glam::Vec3;

/// What the frustum graph must draw for `camera`: ids in draw order.
fn expected(scene: &cullgraph::scene::Scene, camera: &Camera, w: u32, h: u32) -> Vec<u32> {
    let draws = DrawList::all_instances(scene);
    let data = CullData::new(scene, &draws);
    let view = CullView::from_camera(camera, w, h);
    let (eye_hi, eye_lo) = cullgraph::passes::shared::gpu_types::split_hi_lo(camera.eye);
    let mut out = Vec::new();
    for group in &data.groups {
        for slot in group.first_slot..group.first_slot + group.slot_count {
            let r = &data.records[slot as usize];
            let (hi, lo, _, half) = r.unpack();
            // The shader's eye-relative center: (hi - eye_hi) + (lo - eye_lo), in f32.
            let c = (hi - eye_hi) + (lo - eye_lo);
            let inside = r.group_flags & CULL_HUGE != 0 || aabb_in_frustum(&view, c - half, c + half);
            if inside {
                out.push(draws.instance_ids[slot as usize]);
            }
        }
    }
    out
}

/// What each draw pass of the last frame drew (the graphs here all cull).
fn draw_lists(renderer: &Renderer) -> Vec<Vec<u32>> {
    renderer
        .drawn()
        .unwrap()
        .unwrap()
        .into_iter()
        .map(|d| match d {
            DrawnInstances::Some(ids) => ids,
            DrawnInstances::All => panic!("the graph culls"),
        })
        .collect()
}

fn drawn(renderer: &Renderer) -> Vec<u32> {
    draw_lists(renderer).concat()
}

#[test]
fn frustum_lists_equal_the_cpu_reference_exactly() {
    let gpu = GpuTest::new();
    let (w, h) = (64, 48);
    // 40003: more test workgroups than done-counter lanes (64), so lanes count several. The
    // city: its street view, three face-cull regions.
    let scenes: [(&str, usize, Option<usize>); 5] = [
        ("field", 1000, Some(7)),
        ("field", 5003, Some(1000)),
        ("field", 777, Some(700)),
        ("field", 40_003, Some(300)),
        ("city", 20_003, None),
    ];
    for (name, instances, kinds) in scenes {
        let scene = SceneSource::Builtin(name.into())
            .load(&LoadOptions { instances: Some(instances), kinds, ..Default::default() })
            .unwrap();
        let base = scene.default_camera(w as f32 / h as f32);
        let spec = GraphSpec::builtin("frustum").unwrap();
        let mut renderer =
            Renderer::with_graph(&gpu, gpu.shaders(), scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
        renderer.enable_verification(gpu.shaders()).unwrap();
        // From everything in view to a narrow slice: dense and sparse survivors.
        let mut cameras: Vec<Camera> = (0..6).map(|f| CameraPath::Orbit.camera_at(&base, f * 5)).collect();
        let mut close = base.clone();
        close.eye = base.target + (base.eye - base.target) * 0.15;
        cameras.push(close);
        let mut narrow = base.clone();
        narrow.projection = cullgraph::scene::Projection::Perspective { fov_y_deg: 3.0 };
        cameras.push(narrow);
        // Looking away: nothing survives.
        let mut away = base.clone();
        away.target = base.eye + (base.eye - base.target);
        cameras.push(away);
        for (i, camera) in cameras.iter().enumerate() {
            let stats = renderer.render(camera).unwrap();
            let want = expected(&scene, camera, w, h);
            let got = drawn(&renderer);
            assert_eq!(got.len(), want.len(), "{instances} instances, camera {i}: survivor count ({stats:?})");
            assert!(
                got == want,
                "{instances} instances, camera {i}: lists differ at {:?}",
                got.iter().zip(&want).position(|(a, b)| a != b)
            );
            let groups_with_survivors = {
                let draws = DrawList::all_instances(&scene);
                draws
                    .commands
                    .iter()
                    .filter(|c| {
                        (c.first_instance..c.first_instance + c.instance_count)
                            .any(|s| want.contains(&draws.instance_ids[s as usize]))
                    })
                    .count() as u32
            };
            assert_eq!(stats.draws, groups_with_survivors, "camera {i}: one command per non-empty group");
            // Every slot is tested and counted once.
            let pass = &CullPassStats::of(&stats)[0];
            assert_eq!(pass.tested, instances as u32, "camera {i}: tested ({stats:?})");
            assert_eq!(pass.frustum_culled, (instances - want.len()) as u32, "camera {i}: frustum-culled");
        }
    }
    let _ = Vec3::ZERO;
}

/// Masked, double-sided and mirrored instances each take a region of their own in every list
/// (back, front and none for opaque materials, the same for masked ones): the lists still equal
/// the CPU reference exactly, region after region, over more draw groups than one scan chunk
/// of the compaction holds (255), so that regions start and end inside chunks.
#[test]
fn masked_materials_have_regions_of_their_own_in_exact_lists() {
    use cullgraph::passes::shared::face_cull::FaceCull;
    let gpu = GpuTest::new();
    let (w, h) = (64, 48);
    let options = LoadOptions { instances: Some(40_003), kinds: Some(300), ..Default::default() };
    let mut scene = SceneSource::Builtin("field".into()).load(&options).unwrap();
    for (i, material) in scene.materials.iter_mut().enumerate() {
        if i % 3 == 1 {
            material.alpha_mode = cullgraph::scene::AlphaMode::Mask { cutoff: 0.5 };
        }
        material.double_sided = i % 4 == 0;
    }
    let draws = DrawList::all_instances(&scene);
    let regions = draws.regions;
    for region in FaceCull::ALL.into_iter().filter(|&r| r != FaceCull::Blended) {
        assert!(regions.len[region as usize] > 0, "the scene has {region:?} groups");
    }
    assert!(regions.groups() > 2 * 255, "several scan chunks");
    let spec = GraphSpec::builtin("frustum").unwrap();
    let mut renderer =
        Renderer::with_graph(&gpu, gpu.shaders(), scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
    renderer.enable_verification(gpu.shaders()).unwrap();
    let base = scene.default_camera(w as f32 / h as f32);
    let mut close = base.clone();
    close.eye = base.target + (base.eye - base.target) * 0.2;
    for (i, camera) in [base.clone(), close, CameraPath::Orbit.camera_at(&base, 20)].iter().enumerate() {
        let stats = renderer.render(camera).unwrap();
        let want = expected(&scene, camera, w, h);
        let got = drawn(&renderer);
        assert_eq!(got.len(), want.len(), "camera {i}: survivor count");
        assert!(got == want, "camera {i}: lists differ at {:?}", got.iter().zip(&want).position(|(a, b)| a != b));
        let masked_drawn = want.iter().filter(|&&id| FaceCull::of(&scene, &scene.instances[id as usize]).is_masked());
        assert!(masked_drawn.count() > 0, "camera {i}: masked instances in view");
        assert_eq!(stats.verify.as_ref().map(|v| v.false_negatives), Some(0), "camera {i}");
    }
}

/// Ids of the instances whose bound the frustum graph keeps for `camera` (the CPU reference).
fn in_frustum(scene: &cullgraph::scene::Scene, camera: &Camera, w: u32, h: u32) -> std::collections::HashSet<u32> {
    expected(scene, camera, w, h).into_iter().collect()
}

/// The two-phase graph's early phase draws last frame's visible list as it is (the late
/// phase's `visible_ids` with its commands; no early cull pass). Against an early phase that
/// tests every slot's visibility bit and the frustum (`tests/graphs/gpu/two_phase_bits.ron`),
/// on a camera moving fast enough that part of last frame's visible set leaves the view: the
/// early lists agree exactly (same ids, same order) inside the frustum, the late lists are
/// identical, the early and late lists never share an instance, and neither misses anything
/// visible.
#[test]
fn early_phase_from_last_frames_list_matches_the_tested_early_phase() {
    let gpu = GpuTest::new();
    let (w, h) = (64, 48);
    for (source, instances, kinds) in [("field", 5003usize, Some(1000usize)), ("city", 3000, None)] {
        let options = LoadOptions { instances: Some(instances), kinds, ..Default::default() };
        let scene = SceneSource::Builtin(source.into()).load(&options).unwrap();
        // Close in, so that turning around the scene moves instances out of view.
        let mut base = scene.default_camera(w as f32 / h as f32);
        base.eye = base.target + (base.eye - base.target) * 0.3;
        let renderer_for = |spec: &GraphSpec| {
            let mut r =
                Renderer::with_graph(&gpu, gpu.shaders(), scene.clone(), RenderSettings::new(w, h), spec).unwrap();
            r.enable_verification(gpu.shaders()).unwrap();
            r
        };
        let mut from_list = renderer_for(&GraphSpec::builtin("two_phase").unwrap());
        let bits_graph = std::path::Path::new("tests/graphs/gpu/two_phase_bits.ron");
        let mut tested = renderer_for(&GraphSpec::from_file(bits_graph).unwrap());
        let mut left_view = 0;
        for frame in 0..8 {
            let camera = CameraPath::Orbit.camera_at(&base, frame * 12);
            let a = from_list.render(&camera).unwrap();
            let b = tested.render(&camera).unwrap();
            let (la, lb) = (draw_lists(&from_list), draw_lists(&tested));
            let inside = in_frustum(&scene, &camera, w, h);
            let (early_inside, early_outside): (Vec<u32>, Vec<u32>) = la[0].iter().partition(|id| inside.contains(id));
            assert_eq!(early_inside, lb[0], "{source}, frame {frame}: early lists inside the frustum");
            assert_eq!(la[1], lb[1], "{source}, frame {frame}: late lists");
            left_view += early_outside.len();
            let early: std::collections::HashSet<u32> = la[0].iter().copied().collect();
            assert_eq!(early.len(), la[0].len(), "{source}, frame {frame}: an instance twice in the early list");
            assert!(la[1].iter().all(|id| !early.contains(id)), "{source}, frame {frame}: drawn early and late");
            // The early list's counters (written by last frame's late phase) are what was drawn.
            let early_stats = &CullPassStats::of(&a)[0];
            let early_triangles: u64 = la[0].iter().map(|&id| triangles_of(&scene, id)).sum();
            assert_eq!(
                (early_stats.pass.as_str(), early_stats.tested, early_stats.drawn as usize, early_stats.triangles),
                ("draw_early", 0, la[0].len(), early_triangles),
                "{source}, frame {frame}: the early draw's counters"
            );
            let (va, vb) = (a.verify.unwrap(), b.verify.unwrap());
            assert_eq!((va.false_negatives, vb.false_negatives), (0, 0), "{source}, frame {frame}");
            assert_eq!(va.visible, vb.visible, "{source}, frame {frame}");
        }
        assert!(left_view > 0, "{source}: the camera path never moved a visible instance out of view");
    }
}

/// Triangles one instance draws.
fn triangles_of(scene: &cullgraph::scene::Scene, id: u32) -> u64 {
    scene.meshes[scene.instances[id as usize].mesh as usize].index_count as u64 / 3
}

/// A cull laid out in rows of workgroups (as on devices whose `maxComputeWorkGroupCount[0]` is
/// 65535, which one workgroup per 256 instances reaches at 2^24 instances) draws the same lists,
/// counts and image as in one row, and so does a late test step dispatched with the number of
/// blocks its block step listed. The width is forced down so that a small city takes rows.
#[test]
fn culls_laid_out_in_rows_of_workgroups_equal_one_row() {
    let gpu = GpuTest::new();
    let (w, h) = (64, 48);
    let scene = SceneSource::Builtin("city".into())
        .load(&LoadOptions { instances: Some(20_003), ..Default::default() })
        .unwrap();
    let base = scene.default_camera(w as f32 / h as f32);
    // With `listed`, the late test step is dispatched with the number of blocks its block step
    // listed (as it is from 16 384 blocks on) instead of a workgroup per block.
    let run = |width: u32, listed: bool| {
        cullgraph::gpu::line_dispatch::set_width_for_tests(width);
        cullgraph::passes::instance_cull::set_listed_dispatch_from_for_tests(listed.then_some(1));
        let spec = GraphSpec::builtin("two_phase").unwrap();
        let mut renderer =
            Renderer::with_graph(&gpu, gpu.shaders(), scene.clone(), RenderSettings::new(w, h), &spec).unwrap();
        renderer.enable_verification(gpu.shaders()).unwrap();
        let mut frames = Vec::new();
        for frame in 0..3 {
            let camera = CameraPath::Orbit.camera_at(&base, frame * 10);
            let (stats, image) = renderer.render_to_image(&camera).unwrap();
            assert_eq!(stats.verify.as_ref().map(|v| v.false_negatives), Some(0), "width {width}, frame {frame}");
            let counts: Vec<_> =
                CullPassStats::of(&stats).iter().map(|c| (c.tested, c.frustum_culled, c.drawn)).collect();
            frames.push((draw_lists(&renderer), counts, image.into_raw()));
        }
        cullgraph::gpu::line_dispatch::set_width_for_tests(0);
        cullgraph::passes::instance_cull::set_listed_dispatch_from_for_tests(None);
        frames
    };
    // 79 blocks: rows of 7 (and the compact step's 80 workgroups, rows of 7 with one left over).
    let rows = run(7, false);
    let one_row = run(0, false);
    let listed = run(0, true);
    for (frame, ((a, b), c)) in rows.iter().zip(&one_row).zip(&listed).enumerate() {
        for (other, name) in [(b, "one row"), (c, "the listed number")] {
            assert_eq!(a.0, other.0, "frame {frame}, {name}: draw lists");
            assert_eq!(a.1, other.1, "frame {frame}, {name}: counters");
            assert!(a.2 == other.2, "frame {frame}, {name}: images differ");
        }
    }
}
