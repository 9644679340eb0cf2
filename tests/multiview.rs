//! Two VR eyes drawn with multiview (`cullgraph::bench::multiview`): one multiview pass into a
//! 2-layer target gives each layer the image of that eye's own pass, pixel for pixel, and
//! each eye's own culled list draws the image the union of both eyes' lists draws.

mod common;

use common::GpuTest;
use cullgraph::bench::multiview::{self, EyeList, StereoDraws};
use cullgraph::passes::shared::scene_buffers::DrawList;
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, SceneSource};
use glam::DVec3;
use std::collections::BTreeSet;

const SIZE: (u32, u32) = (64, 48);

/// Whether the device draws every view of a multiview pass into its own layer. Lavapipe
/// (Mesa 22.3) does not: given the same camera for both eyes, its two layers differ (the
/// second layer misses most of the draws), with no validation message. The layers are then
/// compared on other devices only (`CULLGRAPH_TEST_DEVICE`); the pass still runs here, under
/// validation.
fn renders_multiview_layers(ctx: &GpuTest) -> bool {
    !ctx.caps().name.contains("llvmpipe")
}

#[test]
fn each_layer_of_the_multiview_pass_is_that_eyes_own_pass() {
    let ctx = GpuTest::new();
    assert!(ctx.caps().multiview, "lavapipe has multiview");
    let shaders = ctx.shaders();
    let scene =
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(300), ..Default::default() }).unwrap();
    // A head in the middle of the city looking down a street: the frustum cuts through the
    // city, so the eyes, each seeing further to its own side, see different instances.
    let (min, max) = scene.world_bounds().unwrap();
    let center = (min + max) * 0.5;
    let head = Camera {
        eye: DVec3::new(center.x, 2.0, center.z),
        target: DVec3::new(max.x, 1.5, center.z),
        ..Default::default()
    };
    let eyes = multiview::eye_cameras(&head, SIZE.0, SIZE.1);
    let (renderer, drawn) = multiview::drawn_by_eyes(&ctx, shaders, scene, &eyes, SIZE, 2).unwrap();
    let union: BTreeSet<u32> = drawn[0].union(&drawn[1]).copied().collect();
    // Each eye culls on its own: the eyes' lists differ, and the union is more than either.
    assert!(!drawn[0].is_empty() && !drawn[1].is_empty());
    assert!(union.len() > drawn[0].len().max(drawn[1].len()) && union.len() < 300, "{}", union.len());

    let all = DrawList::all_instances(renderer.scene());
    let upload = |name, ids: &BTreeSet<u32>| EyeList::upload(&ctx, name, &all, ids).unwrap();
    let (left, right, both) = (upload("left", &drawn[0]), upload("right", &drawn[1]), upload("both", &union));
    assert_eq!(
        (left.instances, right.instances, both.instances),
        (drawn[0].len() as u32, drawn[1].len() as u32, union.len() as u32)
    );
    let draws = StereoDraws::new(&ctx, shaders, &eyes, SIZE.0, SIZE.1).unwrap();
    let scene = renderer.gpu_scene();
    let images = |lists: [&EyeList; 2]| {
        ctx.submit_and_wait(|cmd| {
            draws.record_separate(cmd, scene, lists);
            draws.record_multiview(cmd, scene, &both)
        })
        .unwrap();
        draws.read_colors().unwrap()
    };
    let colors = images([&both, &both]);
    let (separate, layers) = (colors.separate, colors.multiview.expect("multiview is on"));
    for eye in 0..2 {
        let covered = separate[eye].chunks_exact(4).filter(|p| p[3] == 255).count();
        assert!(covered > (SIZE.0 * SIZE.1 / 4) as usize, "eye {eye} sees the city: {covered} pixels");
        if renders_multiview_layers(&ctx) {
            assert!(layers[eye] == separate[eye], "eye {eye}: the multiview layer differs from the eye's own pass");
        }
    }
    assert!(separate[0] != separate[1], "the eyes see from two places");

    // What an eye's culling left out of its own list is invisible to it: its own list draws
    // the image the union draws.
    let own = images([&left, &right]).separate;
    for eye in 0..2 {
        assert!(own[eye] == separate[eye], "eye {eye}: its own list draws another image than the union");
    }
    ctx.assert_clean();
}
