//! Render graphs executed on the GPU (lavapipe, validation and synchronization validation on):
//! compute chains with aliased transients, history resources across frames, user compute passes,
//! and hot reload.

mod common;

use common::{boxes_camera, boxes_scene, GpuTest};
use cullgraph::gpu::transfer::read_buffer;
use cullgraph::graph::plan::ResourceClass;
use cullgraph::render::{GraphSpec, RenderSettings, Renderer};
use std::path::Path;

fn spec(file: &str) -> GraphSpec {
    GraphSpec::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join(file)).unwrap()
}

#[test]
fn compute_chain_with_aliased_transients_and_history_gives_exact_results() {
    let gpu = GpuTest::new();
    let mut renderer = Renderer::with_graph(
        &gpu,
        gpu.shaders(),
        boxes_scene(),
        RenderSettings::new(8, 8),
        &spec("tests/graphs/gpu/chain.ron"),
    )
    .unwrap();
    let plan = renderer.plan().clone();
    assert_eq!(
        plan.passes.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
        ["fill", "square", "offset", "accumulate"]
    );
    // `a` (fill..square) and `c` (offset..accumulate) never live at the same time: they share memory.
    let memory = renderer.runtime().memory();
    let id = |n: &str| plan.resources.iter().position(|r| r.name == n).unwrap();
    assert_eq!(plan.resources[id("sum")].class, ResourceClass::History);
    let (pa, pc) = (memory.placements[id("a")].unwrap(), memory.placements[id("c")].unwrap());
    assert_eq!((pa.heap, pa.offset), (pc.heap, pc.offset), "a and c should alias: {memory:?}");
    assert!(memory.bytes_with_aliasing < memory.bytes_without_aliasing);

    let n = 1000u32;
    for frame in 1..=3u32 {
        renderer.render(&boxes_camera()).unwrap();
        let out = read_buffer(&gpu, renderer.runtime().output_buffer(0).unwrap()).unwrap();
        let out: &[u32] = bytemuck::cast_slice(&out);
        assert_eq!(out.len(), n as usize);
        for (i, &v) in out.iter().enumerate() {
            let c = (i as u32 + 1) * (i as u32 + 1) + 7;
            assert_eq!(v, frame * 2 * c, "frame {frame}, element {i}");
        }
    }
}

#[test]
fn user_compute_pass_tints_the_lit_image() {
    let gpu = GpuTest::new();
    let settings = RenderSettings::new(64, 48);
    let lit = Renderer::new(&gpu, gpu.shaders(), boxes_scene(), settings.clone())
        .unwrap()
        .render_to_image(&boxes_camera())
        .unwrap()
        .1;
    let mut tint =
        Renderer::with_graph(&gpu, gpu.shaders(), boxes_scene(), settings, &spec("graph/examples/tint.ron")).unwrap();
    let tinted = tint.render_to_image(&boxes_camera()).unwrap().1;
    for (a, b) in lit.pixels().zip(tinted.pixels()) {
        for (c, scale) in [(0, 1.0f32), (1, 0.85), (2, 0.7)] {
            let expected = (a[c] as f32 * scale).round();
            assert!((b[c] as f32 - expected).abs() <= 1.0, "{a:?} tinted to {b:?}");
        }
    }
}

#[test]
fn history_image_converges_on_a_still_camera() {
    let gpu = GpuTest::new();
    let settings = RenderSettings::new(32, 24);
    let lit = Renderer::new(&gpu, gpu.shaders(), boxes_scene(), settings.clone())
        .unwrap()
        .render_to_image(&boxes_camera())
        .unwrap()
        .1;
    let mut blend =
        Renderer::with_graph(&gpu, gpu.shaders(), boxes_scene(), settings, &spec("graph/examples/history.ron"))
            .unwrap();
    let mean_gap = |img: &cullgraph::render::output::RgbaImage| {
        lit.pixels().zip(img.pixels()).map(|(a, b)| a[0].abs_diff(b[0]) as f64).sum::<f64>() / (32.0 * 24.0)
    };
    let first = blend.render_to_image(&boxes_camera()).unwrap().1;
    let mut later = first.clone();
    for _ in 0..12 {
        later = blend.render_to_image(&boxes_camera()).unwrap().1;
    }
    // Starting from a cleared (black) history, each frame moves towards the lit image.
    assert!(mean_gap(&first) > 10.0, "first frame gap {}", mean_gap(&first));
    assert!(mean_gap(&later) < mean_gap(&first) / 4.0, "gap {} -> {}", mean_gap(&first), mean_gap(&later));
}

#[test]
fn a_broken_reload_keeps_the_last_good_graph_running() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut renderer = Renderer::new(&gpu, shaders, boxes_scene(), RenderSettings::new(48, 32)).unwrap();
    let before = renderer.render_to_image(&boxes_camera()).unwrap().1;

    let mut broken = GraphSpec::builtin("two_phase").unwrap();
    broken.text = broken
        .text
        .replace("\"emissive_occlusion\", \"depth\": \"depth\"}", "\"emissive_occlusion\", \"depth\": \"dept\"}");
    let err = renderer.reload_graph(shaders, &broken).unwrap_err().to_string();
    assert!(err.starts_with("graph/two_phase.ron:") && err.contains("'dept'"), "{err}");
    let still = renderer.render_to_image(&boxes_camera()).unwrap().1;
    assert!(before.as_raw() == still.as_raw(), "the old graph must keep rendering the same frame");

    // A good edit takes effect: brighter exposure, brighter image.
    let brighter = GraphSpec::default_graph().with_overrides([("exposure".to_string(), "2.0".to_string())]);
    renderer.reload_graph(shaders, &brighter).unwrap();
    let after = renderer.render_to_image(&boxes_camera()).unwrap().1;
    let sum = |img: &cullgraph::render::output::RgbaImage| {
        img.pixels().map(|p| p[0] as u64 + p[1] as u64 + p[2] as u64).sum::<u64>()
    };
    assert!(sum(&after) > sum(&before) * 11 / 10);
}

#[test]
fn buffers_too_small_for_their_slots_are_refused_at_the_binding_when_the_graph_is_compiled() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let scene = boxes_scene();
    let refused = |spec: &GraphSpec| {
        Renderer::with_graph(&gpu, shaders, scene.clone(), RenderSettings::new(48, 32), spec)
            .err()
            .expect("refused before any frame")
            .to_string()
    };
    // The position of the `n`-th binding of `resource` in the graph's text, as `line:col`.
    let binding_pos = |text: &str, resource: &str, n: usize| {
        let quoted = format!("\"{resource}\"");
        let offset = text.match_indices(&quoted).nth(n).expect("bound").0;
        let line = text[..offset].matches('\n').count() + 1;
        let col = offset - text[..offset].rfind('\n').map_or(0, |i| i + 1) + 1;
        format!("{line}:{col}")
    };

    // The two-phase graph with one more resource declared (the kinds create the rest).
    let declaring = |declaration: &str| {
        let mut spec = GraphSpec::builtin("two_phase").unwrap();
        spec.text = spec.text.replacen("resources: {", &format!("resources: {{\n        {declaration},"), 1);
        spec
    };
    // A count buffer that holds one count, where the cull pass writes one per face-cull region.
    let old = declaring("\"late_count\": Buffer(size: 4)");
    let err = refused(&old);
    assert!(
        err.contains(&format!("two_phase.ron:{}", binding_pos(&old.text, "late_count", 1)))
            && err.contains("pass 'cull_late' writes \"draw_count\": 'late_count' holds 4 bytes; the slot takes 28"),
        "{err}"
    );
    // The draw that reads it is refused at its own binding too.
    assert!(err.contains("pass 'draw_late' reads \"draw_count\": 'late_count' holds 4 bytes"), "{err}");

    // Sizes that depend on the scene: an id per instance.
    let instances = scene.instances.len();
    let small = declaring("\"late_ids\": Buffer(size: 8)");
    let err = refused(&small);
    assert!(
        err.contains(&format!(
            "'late_ids' holds 8 bytes; the slot takes instances * 4 = {} bytes for this scene (instances = {instances})",
            instances * 4
        )),
        "{err}"
    );

    // A pyramid at the depth's own size (as if it stored level 0 too, which the pass does not).
    let full = declaring("\"hiz\": Image(format: R32_SFLOAT, size: Fixed(\"width\", \"height\"), mips: All)");
    let err = refused(&full);
    assert!(
        err.contains(&format!("two_phase.ron:{}", binding_pos(&full.text, "hiz", 3)))
            && err.contains("pass 'hiz': the pyramid 'hiz' is 48x32; it must be 24x16"),
        "{err}"
    );
}

#[test]
fn a_reload_that_fails_at_its_first_frame_reverts_to_the_graph_it_replaced() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let settings = RenderSettings::new(48, 32);
    let mut renderer = Renderer::new(&gpu, shaders, boxes_scene(), settings).unwrap();
    let before = renderer.render_to_image(&boxes_camera()).unwrap().1;
    // Loads and compiles, but its frames need an image the host has not given.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let needs_host = GraphSpec::from_file(&root.join("graph/examples/host_target.ron")).unwrap();
    renderer.reload_graph(shaders, &needs_host).unwrap();
    let err = renderer.render(&boxes_camera()).unwrap_err().to_string();
    // At the declaration of what is missing.
    let missing = "graph/examples/host_target.ron:14:9: resource 'color': is imported, but the host provided nothing";
    assert!(err.contains(missing), "{err}");
    renderer.revert_reload().unwrap();
    assert_eq!(renderer.plan().name, "default");
    let after = renderer.render_to_image(&boxes_camera()).unwrap().1;
    assert_eq!(before.as_raw(), after.as_raw(), "the reverted graph renders as before");
    // Only a reload that recorded nothing can be reverted, once.
    assert!(renderer.revert_reload().is_err());
    renderer.reload_graph(shaders, &GraphSpec::default_graph()).unwrap();
    renderer.render(&boxes_camera()).unwrap();
    assert!(renderer.revert_reload().is_err(), "the new graph has recorded a frame");
}

/// A pass placed twice, the second copy after everything that reads what the first wrote
/// (and after the executor copied its counters to the host), is ordered like any other
/// write-after-read: no hazard for synchronization validation, as `graph check` promised.
#[test]
fn a_cull_pass_placed_twice_renders_without_a_hazard() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let mut spec = GraphSpec::builtin("two_phase").unwrap();
    spec.text = r#"Graph(
    name: "twice",
    extends: "two_phase",
    passes: [Pass(
        name: "cull_again",
        kind: "instance_cull",
        reads: {"visibility_prev": "visibility.prev", "hiz": "hiz"},
        writes: {
            "draw_commands": "late_commands", "draw_count": "late_count", "draw_instance_ids": "late_ids",
            "visibility": "visibility", "stats": "cull_late.stats",
        },
        settings: {"phase": "late"},
    )],
)"#
    .into();
    spec.file = "twice.ron".into();
    let mut renderer = Renderer::with_graph(&gpu, shaders, boxes_scene(), RenderSettings::new(48, 32), &spec).unwrap();
    let names: Vec<&str> = renderer.plan().passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names.last(), Some(&"cull_again"), "{names:?}");
    for _ in 0..3 {
        renderer.render(&boxes_camera()).unwrap();
    }
    gpu.assert_clean();
}

/// A compute shader's shared memory is counted from its SPIR-V: exactly the device's limit
/// renders, four bytes more are refused when the graph is loaded, at the pass's shader.
#[test]
fn shared_memory_up_to_the_device_limit_runs_and_beyond_it_is_refused_at_the_shader() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let limit = gpu.caps().limits.max_compute_shared_memory_size;
    let dir = tempfile::tempdir().unwrap();
    // Every workgroup fills `words` (all of its shared memory at the limit), then each thread
    // reads the word at the other end and writes it as red.
    let write = |words: u32| {
        let shader = format!(
            "#version 460\n\
             layout(local_size_x = 8, local_size_y = 8) in;\n\
             layout(binding = 0, rgba8) uniform writeonly image2D dst;\n\
             shared uint words[{words}];\n\
             void main() {{\n\
                 uint i = gl_LocalInvocationIndex;\n\
                 for (uint k = i; k < {words}u; k += 64u) words[k] = k;\n\
                 barrier();\n\
                 imageStore(dst, ivec2(gl_GlobalInvocationID.xy), vec4(float(words[{words}u - 1u - i] % 256u) / 255.0, 0, 0, 1));\n\
             }}\n"
        );
        std::fs::write(dir.path().join("shared.comp"), shader).unwrap();
        let graph = "Graph(\n    name: \"shared\",\n    resources: {\"out\": Image(format: R8G8B8A8_UNORM)},\n    passes: [\n        \
                     Pass(name: \"fill\", kind: \"compute\", shader: \"shared.comp\", writes: {\"dst\": \"out\"}, dispatch: PerPixel(\"out\")),\n    ],\n    outputs: [\"out\"],\n)\n";
        let path = dir.path().join("shared.ron");
        std::fs::write(&path, graph).unwrap();
        GraphSpec::from_file(&path).unwrap()
    };
    let words = limit / 4;
    let mut renderer =
        Renderer::with_graph(&gpu, shaders, boxes_scene(), RenderSettings::new(16, 8), &write(words)).unwrap();
    let image = renderer.render_to_image(&boxes_camera()).unwrap().1;
    for (x, y, pixel) in image.enumerate_pixels() {
        let i = x % 8 + 8 * (y % 8);
        assert_eq!(pixel[0] as u32, (words - 1 - i) % 256, "pixel {x},{y}");
    }

    let err = Renderer::with_graph(&gpu, shaders, boxes_scene(), RenderSettings::new(16, 8), &write(words + 4))
        .err()
        .expect("refused when loaded")
        .to_string();
    let expected = format!(
        "shared.ron:5:53: shader 'shared.comp' of pass 'fill' uses {} bytes of shared memory, more than {} allows \
         (maxComputeSharedMemorySize {limit})",
        limit + 16,
        gpu.caps().name
    );
    assert!(err.contains(&expected), "{err}\nexpected: {expected}");
}
