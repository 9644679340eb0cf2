//! Graph params changed at run time: the exposure and the debug view take effect on the next
//! frame without making anything again, and give the image of a graph loaded with them; a param
//! that changes what the graph is made of rebuilds it; a bad value changes nothing.

mod common;

use common::{city_view, GpuTest};
use cullgraph::render::{GraphSpec, ParamsApplied, RenderSettings, Renderer};

const SIZE: (u32, u32) = (48, 32);

/// The image of the second frame of a renderer loaded with `params`.
fn loaded_with(gpu: &GpuTest, params: &[(&str, &str)]) -> Vec<u8> {
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(400, SIZE);
    let spec = GraphSpec::default_graph().with_overrides(params.iter().map(|(n, v)| (n.to_string(), v.to_string())));
    let mut r = Renderer::with_graph(gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1), &spec).unwrap();
    r.render(&camera).unwrap();
    r.render_to_rgba8(&camera).unwrap().1
}

#[test]
fn exposure_and_debug_view_change_live_and_match_a_graph_loaded_with_them() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(400, SIZE);
    let mut r = Renderer::new(&gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1)).unwrap();
    let first = r.render_to_rgba8(&camera).unwrap().1;
    let pipelines = gpu.pipelines_made();

    assert_eq!(r.set_graph_params(shaders, &[("exposure", "2.5")]).unwrap(), ParamsApplied::Live);
    let brighter = r.render_to_rgba8(&camera).unwrap().1;
    assert_eq!(gpu.pipelines_made(), pipelines, "a live change made pipelines");
    assert!(brighter != first, "the exposure took effect");
    assert!(brighter == loaded_with(&gpu, &[("exposure", "2.5")]), "the image of a graph loaded with it");

    // A later value of the same param replaces the earlier one.
    assert_eq!(
        r.set_graph_params(shaders, &[("exposure", "0.8"), ("debug_view", "normals")]).unwrap(),
        ParamsApplied::Live
    );
    let normals = r.render_to_rgba8(&camera).unwrap().1;
    assert!(normals == loaded_with(&gpu, &[("debug_view", "normals")]));
    assert_eq!(gpu.pipelines_made(), pipelines);
    gpu.assert_clean();
}

#[test]
fn a_param_that_changes_the_passes_rebuilds_and_a_bad_one_changes_nothing() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(400, SIZE);
    let mut r = Renderer::new(&gpu, shaders, scene, RenderSettings::new(SIZE.0, SIZE.1)).unwrap();
    let before = r.render_to_rgba8(&camera).unwrap().1;

    let err = r.set_graph_params(shaders, &[("hiz_test", "sideways")]).unwrap_err().to_string();
    assert!(err.contains("sideways"), "{err}");
    assert!(r.render_to_rgba8(&camera).unwrap().1 == before, "a refused change left the graph as it was");

    assert_eq!(r.set_graph_params(shaders, &[("hiz_test", "finer")]).unwrap(), ParamsApplied::Rebuilt);
    assert!(r.render_to_rgba8(&camera).unwrap().1 == loaded_with(&gpu, &[("hiz_test", "finer")]));
    gpu.assert_clean();
}

#[test]
fn every_shipped_lighting_method_takes_the_exposure_live() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let (scene, camera) = city_view(200, (16, 12));
    for graph in ["default", "msaa_per_sample", "msaa_zprepass", "msaa_compressed", "visibility_buffer", "fxaa", "post"]
    {
        let spec = GraphSpec::builtin(graph).unwrap();
        let mut r = Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(16, 12), &spec).unwrap();
        r.render(&camera).unwrap();
        assert_eq!(r.set_graph_params(shaders, &[("exposure", "1.7")]).unwrap(), ParamsApplied::Live, "{graph}");
        r.render(&camera).unwrap();
    }
    gpu.assert_clean();
}
