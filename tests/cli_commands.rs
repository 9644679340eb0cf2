//! The command line's other subcommands as a user runs them: `bench` (every suite, its JSON,
//! Markdown and plots), `graph check|plan|dot` and `devices`.

mod common;

use common::cli::{run, run_within};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

#[test]
fn bench_writes_speed_against_error_as_json_markdown_and_plots() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().to_str().unwrap();
    let monastery = format!("{ROOT}/../shared/assets/monastery.glb");
    let scenes = if std::path::Path::new(&monastery).exists() {
        format!("builtin:city,{monastery}")
    } else {
        "builtin:city".into()
    };
    let scene_count = scenes.split(',').count();
    #[rustfmt::skip]
    let (code, stdout, err) = run(&[
        "bench", "--suites", "culling,hiz,msaa,dynamic,shadows", "--out", out, "--size", "64x36", "--warmup", "1", "--frames", "2",
        "--shadow-resolution", "128", "--shadow-cascades", "2",
        "--moved", "10,100",
        "--instances", "1000,2000", "--graphs", "no_cull,two_phase", "--verify", "--hiz-sizes", "33x17",
        "--msaa-scenes", &scenes, "--msaa-lights", "5", "--msaa-samples", "4", "--reference", "2",
        "--msaa-methods", "two_phase,msaa_per_sample,msaa_zprepass,msaa_compressed_claim",
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("bench.json")).unwrap()).unwrap();

    // Culling: both sizes, both graphs, exact visibility checked, nothing visible culled.
    let culling = &json["culling"]["scenes"];
    assert_eq!(culling.as_array().unwrap().len(), 2);
    for scene in culling.as_array().unwrap() {
        let graphs = scene["graphs"].as_array().unwrap();
        assert_eq!(graphs.iter().map(|g| g["graph"].as_str().unwrap()).collect::<Vec<_>>(), ["no_cull", "two_phase"]);
        for g in graphs {
            assert_eq!(g["false_negatives"], 0, "{g}");
            assert!(g["frame_ms"].as_f64().unwrap() > 0.0);
        }
        let two_phase = &graphs[1];
        assert!(two_phase["drawn"].as_u64().unwrap() < graphs[0]["drawn"].as_u64().unwrap(), "two_phase culls");
    }
    // Dynamic: a row per moved count on the largest city, the update's bytes and times measured.
    let dynamic = &json["dynamic"];
    assert_eq!(dynamic["instances"], 2000);
    let moved: Vec<u64> = dynamic["rows"].as_array().unwrap().iter().map(|r| r["moved"].as_u64().unwrap()).collect();
    assert_eq!(moved, [10, 100]);
    for r in dynamic["rows"].as_array().unwrap() {
        assert!(r["bytes"].as_u64().unwrap() >= 32 * r["moved"].as_u64().unwrap(), "{r}");
        assert!(r["frame_ms"].as_f64().unwrap() > 0.0 && r["host_copy_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
    assert!(dynamic["rebuild_cpu_ms"].as_f64().unwrap() > 0.0);
    // Shadows: every configuration on the largest city; every caster drawn into both cascades
    // without caster culling, fewer with it, none while the maps are kept and nothing moves.
    let shadows = &json["shadows"];
    assert_eq!((shadows["instances"].as_u64(), shadows["cascades"].as_u64()), (Some(2000), Some(2)));
    let row =
        |config: &str| shadows["rows"].as_array().unwrap().iter().find(|r| r["config"] == config).unwrap().clone();
    assert_eq!(row("on, every caster drawn")["drawn"], serde_json::json!([2000, 2000]));
    assert!(row("on, casters culled")["drawn"].as_array().unwrap().iter().all(|d| d.as_u64().unwrap() < 2000));
    assert_eq!(row("on, casters culled, maps kept, camera still")["cascades_drawn"], 0.0);
    assert!(
        shadows["flip_on"].as_f64().unwrap() > 0.0
            && shadows["shadow_map_bytes"].as_u64().unwrap() >= 2 * 128 * 128 * 4
    );
    // Hi-Z: the size asked for, both methods.
    let hiz = json["hiz"].as_array().unwrap();
    assert!(hiz.iter().any(|h| h["method"] == "single") && hiz.iter().any(|h| h["method"] == "per_mip"));
    assert!(hiz.iter().all(|h| h["width"] == 33 && h["height"] == 17));

    // MSAA: one row per scene and method, each with memory and its error against the reference.
    let rows = json["msaa"]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), scene_count * 4);
    assert_eq!(json["msaa"]["reference_samples"], 4);
    for r in rows {
        let flip = r["mean_flip"].as_f64().unwrap();
        assert!(flip > 0.0 && flip < 0.2, "{r}");
        assert!(r["gbuffer_bytes"].as_u64().unwrap() > 0 && r["frame_ms"].as_f64().unwrap() > 0.0, "{r}");
        assert_eq!(r["samples"], if r["method"] == "two_phase" { 1 } else { 4 });
        assert_eq!(r["pool"].is_null(), r["method"] != "msaa_compressed_claim", "{r}");
    }
    let per_sample = |scene: &str, key: &str| {
        rows.iter().find(|r| r["scene"] == scene && r["method"] == "msaa_per_sample").unwrap()[key].as_f64().unwrap()
    };
    for r in rows.iter().filter(|r| r["method"] == "msaa_compressed_claim") {
        let scene = r["scene"].as_str().unwrap();
        // The compressed G-buffer holds less than a per-sample one, and shades alike.
        assert!(r["gbuffer_bytes"].as_f64().unwrap() < per_sample(scene, "gbuffer_bytes"), "{r}");
        assert!((r["mean_flip"].as_f64().unwrap() - per_sample(scene, "mean_flip")).abs() < 0.002, "{r}");
    }
    let markdown = std::fs::read_to_string(tmp.path().join("bench.md")).unwrap();
    assert_eq!(stdout.trim(), markdown.trim());
    assert!(
        markdown.contains("| frame / Z-prepass |") && markdown.contains("| city | 5 | 4x | msaa_compressed_claim |")
    );
    for (plot, names) in
        [("culling.svg", ["no_cull", "naive frustum peer"]), ("msaa.svg", ["msaa_per_sample", "city, 5 lights"])]
    {
        let svg = std::fs::read_to_string(tmp.path().join(plot)).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "{plot}");
        for name in names {
            assert!(svg.contains(name), "{plot} names {name}");
        }
    }

    let (code, _, err) = run(&["bench", "--suites", "culling,speed", "--out", out]);
    assert_eq!(code, 1);
    assert!(err.contains("unknown suite 'speed' (known: culling, hiz, msaa, dynamic, views, shadows, lod)"), "{err}");
}

#[test]
fn bench_lod_reports_speed_against_error_per_threshold() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().to_str().unwrap();
    let args =
        ["bench", "--suites", "lod", "--lod-scenes", "builtin:dense@6", "--lod-thresholds", "2", "--size", "48x27"];
    let (code, _, err) =
        run(&[&args[..], &["--warmup", "0", "--frames", "1", "--reference", "2", "--out", out]].concat());
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("bench.json")).unwrap()).unwrap();
    let rows = json["lod"]["rows"].as_array().unwrap();
    // Threshold 0 is measured first, as the full detail the others are compared with; each
    // threshold without cluster culling, then with it.
    let runs: Vec<(f64, bool)> =
        rows.iter().map(|r| (r["threshold"].as_f64().unwrap(), r["clusters"].as_bool().unwrap())).collect();
    assert_eq!(runs, [(0.0, false), (0.0, true), (2.0, false), (2.0, true)]);
    let triangles: Vec<u64> = rows.iter().map(|r| r["triangles"].as_u64().unwrap()).collect();
    assert!(triangles[2] * 3 <= triangles[0], "{triangles:?}");
    // Cluster culling draws fewer triangles for the same image, and reports its cost.
    assert!(triangles[1] < triangles[0] && triangles[3] <= triangles[2], "{triangles:?}");
    assert_eq!(rows[1]["flip_vs_full"].as_f64(), Some(0.0));
    assert!(rows[1]["cluster_ms_per_million"].as_f64().is_some_and(|ms| ms > 0.0));
    assert_eq!(rows[0]["flip_vs_full"].as_f64(), Some(0.0));
    // Full detail supersampled is the reference itself.
    assert_eq!(rows[0]["flip_vs_full_supersampled"].as_f64(), Some(0.0));
    assert!(rows.iter().all(|r| r["flip_vs_reference"].as_f64().is_some_and(|f| f > 0.0 && f < 1.0)));
    let svg = std::fs::read_to_string(tmp.path().join("lod.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("builtin:dense@6"));
    let (code, _, err) = run(&["bench", "--suites", "lod", "--lod-scenes", "builtin:dense@x", "--out", out]);
    assert_eq!(code, 1);
    assert!(err.contains("--lod-scenes: 'x' in 'builtin:dense@x' is not an instance count"), "{err}");
}

#[test]
fn bench_views_reports_each_view_count_and_the_resize() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().to_str().unwrap();
    let args =
        ["bench", "--suites", "views", "--instances", "300", "--size", "32x24", "--warmup", "0", "--frames", "2"];
    let (code, _, err) = run(&[&args[..], &["--out", out]].concat());
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("bench.json")).unwrap()).unwrap();
    let views = &json["views"];
    let rows = views["rows"].as_array().unwrap();
    assert_eq!(rows.iter().map(|r| r["views"].as_u64().unwrap()).collect::<Vec<_>>(), [1, 2, 4, 8, 16, 64]);
    for pair in rows.windows(2) {
        assert!(pair[1]["view_bytes"].as_u64() > pair[0]["view_bytes"].as_u64(), "each view adds its own resources");
    }
    assert_eq!(rows[4]["drawn"].as_array().unwrap().len(), 16);
    assert_eq!(views["resize_pipelines"], 0);
    assert_eq!(views["scene_kept"], true);
    // The shared dispatches were timed step by step.
    assert!(rows[4]["cull_test_ms"].as_f64().unwrap() > 0.0 && rows[4]["cull_compact_ms"].as_f64().unwrap() > 0.0);
    // A street camera and four sun cascades, culled together and one at a time.
    let cascades = &views["cascades"];
    assert_eq!(cascades["cascades"], 4);
    assert_eq!(cascades["drawn"].as_array().unwrap().len(), 5, "{cascades}");
    for key in ["camera_alone_ms", "together_ms", "separate_ms"] {
        assert!(cascades[key].as_f64().unwrap() > 0.0, "{key}: {cascades}");
    }
    // Two eyes of --size each, drawn both ways (lavapipe has multiview).
    let stereo = &views["multiview"];
    assert_eq!((&stereo["width"], &stereo["height"], &stereo["multiview"]), (&32.into(), &24.into(), &true.into()));
    let drawn: Vec<u64> = stereo["drawn"].as_array().unwrap().iter().map(|d| d.as_u64().unwrap()).collect();
    let union = stereo["union"].as_u64().unwrap();
    assert!(drawn.iter().all(|&d| d > 0 && d <= union) && union <= 300, "{stereo}");
    for key in ["separate_own_ms", "separate_union_ms", "multiview_union_ms"] {
        assert!(stereo[key].as_f64().unwrap() > 0.0, "{key}: {stereo}");
    }
    let markdown = std::fs::read_to_string(tmp.path().join("bench.md")).unwrap();
    assert!(markdown.contains("| one multiview pass, the union list |"), "{markdown}");
}

#[test]
fn bench_views_with_chosen_counts_checks_each_view_against_exact_visibility() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().to_str().unwrap();
    let args = [
        "bench",
        "--suites",
        "views",
        "--instances",
        "300",
        "--size",
        "32x24",
        "--warmup",
        "0",
        "--frames",
        "1",
        "--view-counts",
        "3",
        "--verify",
    ];
    let (code, _, err) = run(&[&args[..], &["--out", out]].concat());
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("bench.json")).unwrap()).unwrap();
    let rows = json["views"]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["views"], 3);
    assert_eq!(rows[0]["false_negatives"], 0);
    // Culled together or one at a time, each view culls the same share of what it cannot see.
    let together = rows[0]["invisible_culled"].as_array().unwrap();
    assert_eq!(together.len(), 3);
    assert_eq!(together, rows[0]["invisible_culled_alone"].as_array().unwrap());
    assert!(together.iter().all(|s| (0.0..=1.0).contains(&s.as_f64().unwrap())));

    let (code, _, err) = run(&["bench", "--suites", "views", "--view-counts", "65", "--out", out]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("65 views: a renderer holds 1 to 64"), "{err}");
}

#[test]
fn graph_check_plan_and_dot() {
    let tmp = tempfile::tempdir().unwrap();
    let two_phase = format!("{ROOT}/graph/two_phase.ron");
    let (code, stdout, err) = run(&["graph", "check", &two_phase]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("two_phase.ron: ok ("), "{stdout}");

    let bad = tmp.path().join("bad.ron");
    let text = std::fs::read_to_string(&two_phase).unwrap().replacen("kind: \"hiz_build\"", "kind: \"hiz_builder\"", 1);
    std::fs::write(&bad, &text).unwrap();
    let (code, _, err) = run(&["graph", "check", bad.to_str().unwrap()]);
    assert_eq!(code, 1);
    let line = text.lines().position(|l| l.contains("hiz_builder")).unwrap() + 1;
    assert!(err.contains(&format!("bad.ron:{line}:")) && err.contains("hiz_builder"), "{err}");

    // The plan: every pass in execution order, for the size and scene given.
    let (code, stdout, err) =
        run(&["graph", "plan", &two_phase, "--size", "320x180", "--scene", "builtin:city", "--instances", "1000"]);
    assert_eq!(code, 0, "{err}");
    let passes: Vec<&str> = stdout
        .lines()
        .filter_map(|l| {
            // "  N: name (kind) ..."
            let (index, rest) = l.strip_prefix("  ")?.split_once(": ")?;
            index.parse::<usize>().ok()?;
            rest.split(' ').next()
        })
        .collect();
    assert_eq!(
        passes,
        ["draw_early", "hiz", "cull_late", "draw_late", "lighting", "tonemap", "transparent_sort", "transparent"],
        "{stdout}"
    );
    // A buffer too small for this scene is refused at its binding.
    let small = tmp.path().join("small.ron");
    let text = std::fs::read_to_string(&two_phase).unwrap();
    let declared = text.replacen("resources: {", "resources: {\n        \"late_ids\": Buffer(size: 64),", 1);
    std::fs::write(&small, declared).unwrap();
    let (code, _, err) = run(&["graph", "plan", small.to_str().unwrap(), "--instances", "1000"]);
    assert_eq!(code, 1);
    assert!(err.contains("small.ron:") && err.contains("the slot takes instances * 4 = 4000 bytes"), "{err}");

    let dot = tmp.path().join("g.dot");
    let (code, _, err) = run(&["graph", "dot", &two_phase, "-o", dot.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let dot = std::fs::read_to_string(dot).unwrap();
    assert!(dot.starts_with("digraph") && dot.contains("cull_late") && dot.contains("->"), "{dot}");
}

#[test]
fn devices_lists_what_the_loader_sees() {
    let (code, stdout, err) = run(&["devices"]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.lines().any(|l| l.starts_with("0: ") || l.contains(": ")), "{stdout}");
    let device = std::env::var("CULLGRAPH_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    assert!(stdout.contains(&device), "{stdout}");
    // What the optional graphs need, per device; the test device runs the compressed G-buffer
    // (tests/msaa.rs), and whether it claims in draw order depends on its driver's version.
    let line = stdout.lines().find(|l| l.contains(&device)).unwrap();
    assert!(line.contains("compressed G-buffer: yes, draw-order sample claims: "), "{line}");
}

/// Special files never reach memory: each is refused at once, naming what it was meant to be.
#[test]
fn special_files_are_refused_instead_of_read() {
    for (args, what) in [
        (vec!["graph", "check", "/dev/zero"], "graph file"),
        (vec!["render", "--graph", "/dev/zero", "--size", "16x16", "--out", "/dev/null"], "graph file"),
        (vec!["render", "--scene", "/dev/zero", "--size", "16x16", "--out", "/dev/null"], "scene file"),
    ] {
        let (code, _, err) = run(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(&format!("the {what} is not a regular file")), "{args:?}: {err}");
    }
}

/// A failed write of the image or the statistics is an error with a non-zero exit, not a silently
/// short file.
#[test]
fn a_failed_write_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("frame.png");
    let png = png.to_str().unwrap();
    for (flag, args) in
        [("--out", ["--out", "/dev/full", "--stats", "/dev/null"]), ("--stats", ["--out", png, "--stats", "/dev/full"])]
    {
        let mut all = vec!["render", "--size", "16x16", "--frames", "1"];
        all.extend(args);
        let (code, _, err) = run(&all);
        assert_eq!(code, 1, "{flag}: {err}");
        assert!(err.contains("/dev/full") && err.contains("No space left"), "{flag}: {err}");
    }
}

/// A world offset or eye beyond the range where positions stay precise on the GPU is refused
/// with the range, not rendered wrong.
#[test]
fn world_offsets_beyond_the_precise_range_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let image = |offset: &str| {
        let out = dir.path().join(format!("{offset}.png"));
        let base = ["render", "--scene", "builtin:city", "--instances", "500", "--size", "32x18", "--frames", "1"];
        let (code, _, err) = run(&[&base[..], &["--world-offset", offset, "--out", out.to_str().unwrap()]].concat());
        (code, err, std::fs::read(&out).ok())
    };
    let (code, err, origin) = image("0,0,0");
    assert_eq!(code, 0, "{err}");
    // Whole-unit offsets below 2^24 change no bit; up to 2^40 positions keep 1/256 unit.
    let (code, err, far) = image("10000000,0,-10000000");
    assert_eq!((code, far.as_ref() == origin.as_ref()), (0, true), "{err}");
    let (code, err, farther) = image("1e12,0,-1e12");
    assert_eq!((code, farther.is_some()), (0, true), "{err}");
    for offset in ["1e16,0,0", "0,-3e12,0", "1e30,1e30,1e30"] {
        let (code, err, _) = image(offset);
        assert_eq!(code, 1, "{offset}: {err}");
        assert!(err.contains("is beyond ±1099511627776 (2^40) units"), "{offset}: {err}");
    }
}

/// A path flag that names something unusable is refused before any work, naming the flag: an
/// output that is a directory or a FIFO (whose opening would block until a reader comes), a
/// shader folder that is not one, a replayed fuzz input that is a FIFO or a device.
#[test]
fn unusable_paths_are_refused_before_any_work_naming_the_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let fifo = tmp.path().join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let (fifo, dir) = (fifo.to_str().unwrap(), tmp.path().to_str().unwrap());
    let png = tmp.path().join("f.png");
    let png = png.to_str().unwrap();
    let file = tmp.path().join("file");
    std::fs::write(&file, b"x").unwrap();
    let file = file.to_str().unwrap();
    let default = format!("{ROOT}/graph/default.ron");
    let render = ["render", "--instances", "100", "--size", "16x16"];
    #[rustfmt::skip]
    let cases: Vec<(Vec<&str>, String)> = vec![
        ([&render[..], &["--out", fifo]].concat(), format!("--out {fifo}: is not a regular file")),
        ([&render[..], &["--out", dir]].concat(), format!("--out {dir}: is a directory")),
        ([&render[..], &["--out", png, "--stats", fifo]].concat(), format!("--stats {fifo}: is not a regular file")),
        ([&render[..], &["--out", png, "--stats", dir]].concat(), format!("--stats {dir}: is a directory")),
        ([&render[..], &["--out", png, "--shader-dir", "/dev/zero"]].concat(), "--shader-dir /dev/zero: is not a directory".into()),
        ([&render[..], &["--out", png, "--shader-dir", "/no/such/dir"]].concat(), "--shader-dir /no/such/dir: No such file".into()),
        (vec!["graph", "dot", &default, "-o", fifo], format!("-o {fifo}: is not a regular file")),
        (vec!["fuzz", "graph", "--replay", fifo], format!("--replay {fifo}: the graph file is not a regular file")),
        (vec!["fuzz", "graph", "--replay", "/dev/zero"], "--replay /dev/zero: the graph file is not a regular file".into()),
        (vec!["fuzz", "gltf", "--replay", fifo], format!("--replay {fifo}: the scene file is not a regular file")),
        (vec!["fuzz", "graph", "--seconds", "1", "--seeds", "/no/such/dir", "--out", dir], "--seeds /no/such/dir: No such file".into()),
        (vec!["fuzz", "graph", "--seconds", "1", "--out", file], format!("--out {file}: is not a directory")),
        (vec!["bench", "--suites", "hiz", "--out", "/dev/null"], "--out /dev/null: is not a directory".into()),
    ];
    for (args, message) in cases {
        let (code, _, err) = run_within(&args, 60);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(&message), "{args:?}: {err}");
    }
    assert!(!std::path::Path::new(png).exists(), "nothing was rendered");
}

/// Numbers that would run a bench without end or measure nothing are refused, naming the flag;
/// so are moved counts the city cannot give.
#[test]
fn bench_counts_are_bounded() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().to_str().unwrap();
    for (flag, value, range) in [
        ("--frames", "0", "1..=100000"),
        ("--frames", "4294967295", "1..=100000"),
        ("--warmup", "100001", "0..=100000"),
    ] {
        let (code, _, err) = run(&["bench", "--suites", "hiz", flag, value, "--out", out]);
        assert_eq!(code, 2, "{flag} {value}: {err}");
        assert!(err.contains(&format!("'{flag} <{}>'", flag[2..].to_uppercase())) && err.contains(range), "{err}");
    }
    let (code, _, err) = run(&["bench", "--suites", "msaa", "--msaa-samples", "3", "--out", out]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--msaa-samples") && err.contains("2, 4 or 8"), "{err}");
    let (code, _, err) = run(&["bench", "--suites", "dynamic", "--instances", "1000", "--moved", "5000", "--out", out]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--moved 5000: more than the largest city's 1000 instances"), "{err}");
}

/// What the renderer requires of a compiled graph, `graph check --size` requires too, at the
/// text at fault: the first output is the image the host shows, an image of the output size.
#[test]
fn graph_check_applies_the_renderers_rules_on_the_shown_image() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = [
        (r#"Graph(name: "a", extends: "frustum", outputs: ["cull.stats", "color"])"#, "1:48: the first output 'cull.stats' is a buffer"),
        (
            r#"Graph(name: "b", extends: "two_phase", resources: {"color": Image(format: R8G8B8A8_UNORM, size: Scaled(0.5))})"#,
            "1:52: the first output 'color' is the image the host shows: it must be the output size, 64x48, with one sample a pixel; it is 32x24 with 1",
        ),
    ];
    for (text, expected) in cases {
        let file = tmp.path().join("g.ron");
        std::fs::write(&file, text).unwrap();
        let file = file.to_str().unwrap();
        let (code, _, err) = run(&["graph", "check", file]);
        assert_eq!(code, 0, "the graph alone is fine: {err}");
        let (code, _, err) = run(&["graph", "check", file, "--size", "64x48"]);
        assert_eq!(code, 1);
        assert!(err.contains(&format!("{file}:{expected}")), "{err}");
    }
}
