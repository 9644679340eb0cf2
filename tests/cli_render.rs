//! The `cullgraph render` command as a user runs it: bad input gives a clear message and a
//! non-zero exit; `--watch` hot-reloads a graph, keeping the last good one on errors.

mod common;

use common::cli::{cullgraph, run, run_with_memory_limit, run_within};
use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::sync::mpsc;
use std::time::{Duration, Instant};

#[test]
fn bad_flags_and_files_are_reported_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x.png");
    let out = out.to_str().unwrap();
    let (code, _, err) = run(&["render", "--size", "0x10", "--out", out]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("between 1 and 16384"), "{err}");
    let (code, _, err) = run(&["render", "--scene", "/no/such/scene.glb", "--out", out]);
    assert_eq!(code, 1);
    assert!(err.contains("/no/such/scene.glb"), "{err}");
    let (code, _, err) = run(&["render", "--scene", "builtin:nowhere", "--out", out]);
    assert_eq!(code, 1);
    assert!(err.contains("unknown built-in scene 'builtin:nowhere'"), "{err}");
    let (code, _, err) = run(&["render", "--eye", "1,2", "--out", out]);
    assert_eq!(code, 2);
    assert!(err.contains("not x,y,z"), "{err}");
    let (code, _, err) = run(&["render", "--param", "nonsense", "--out", out]);
    assert_eq!(code, 2, "{err}");
    let bad = tmp.path().join("bad.ron");
    std::fs::write(&bad, "Graph(name: \"x\", passes: [Pass(name: 1)])").unwrap();
    let (code, _, err) = run(&["render", "--graph", bad.to_str().unwrap(), "--out", out]);
    assert_eq!(code, 1);
    assert!(err.contains("bad.ron:1:"), "{err}");
    assert!(!std::path::Path::new(out).exists(), "nothing is written when the frame cannot be made");
}

/// A scene larger than the machine or the device holds is refused before it is generated, with
/// the memory it needs and the flag that asked for it: here under an 8 GB address-space limit,
/// like a smaller machine (lavapipe also offers only a 2 GiB heap, which 16 million instances
/// exceed anywhere). Beyond 2^31 - 1 instances, what a draw's instance index can hold, the flag
/// itself is refused.
#[test]
fn scene_sizes_beyond_memory_are_refused_with_the_memory_they_need() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x.png");
    for n in ["16000000", "16777215"] {
        let args = ["render", "--instances", n, "--size", "16x16", "--out", out.to_str().unwrap()];
        let (code, _, err) = run_with_memory_limit(&args, 8_000_000);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains(&format!("error: --instances {n} needs about ")), "{err}");
        assert!(err.contains(" GiB of ") && err.contains("ask for less"), "{err}");
        for flags in [&["graph", "plan", "graph/default.ron"][..], &["bench", "--suites", "culling", "--out"]] {
            let out_dir = tmp.path().join("bench");
            let mut args: Vec<&str> = flags.to_vec();
            if flags[0] == "bench" {
                args.push(out_dir.to_str().unwrap());
            }
            args.extend(["--instances", n, "--size", "16x16"]);
            let (code, _, err) = run_with_memory_limit(&args, 2_000_000);
            assert_eq!(code, 1, "{args:?}: {err}");
            assert!(err.contains(&format!("--instances {n} needs about ")), "{args:?}: {err}");
        }
    }
    // An image (and its supersampled reference) too large for the memory names its flags.
    let args =
        ["render", "--instances", "1000", "--size", "1024x1024", "--reference", "16", "--out", out.to_str().unwrap()];
    let (code, _, err) = run_with_memory_limit(&args, 2_000_000);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("error: --size 1024x1024 with --reference 16 needs about "), "{err}");
    assert!(!out.exists());
    // Beyond the documented maximum, the flag's parser refuses at once.
    let (code, _, err) = run(&["render", "--instances", "2147483648", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("'--instances <N>'") && err.contains("1..=2147483647"), "{err}");
}

/// Durations are finite and at most a day: anything else is refused naming the flag, instead of
/// watching (or fuzzing) forever or panicking on a duration the clock cannot hold.
#[test]
fn durations_must_be_finite_and_at_most_a_day() {
    for value in ["inf", "NaN", "-1", "86401", "1e300"] {
        for args in [
            vec!["render", "--size", "16x16", "--watch", "--watch-for", value, "--out", "/dev/null"],
            vec!["fuzz", "graph", "--seconds", value, "--out", "/dev/null"],
        ] {
            let (code, _, err) = run_within(&args, 60);
            assert_eq!(code, 2, "{args:?}: {err}");
            let flag = if args[0] == "render" { "'--watch-for <SECONDS>'" } else { "'--seconds <SECONDS>'" };
            assert!(err.contains(flag) && err.contains("between 0 and 86400 (a day)"), "{args:?}: {err}");
        }
    }
}

/// Memory the device cannot give is reported at the declaration of the resource that asked for
/// it (two 4 GiB images: more than lavapipe allocates at once).
#[test]
fn a_failed_allocation_names_the_resource_and_its_declaration() {
    let tmp = tempfile::tempdir().unwrap();
    let shader = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/graphs/shaders/rw_image.comp");
    // The same shader for the float image: a storage image's format qualifier is its format.
    let float_shader = tmp.path().join("rw_float_image.comp");
    std::fs::write(&float_shader, std::fs::read_to_string(shader).unwrap().replace("rgba8", "rgba32f")).unwrap();
    let graph = tmp.path().join("huge.ron");
    let pass = |name: &str, image: &str, shader: &str| {
        format!(
            "Pass(name: \"{name}\", kind: \"compute\", shader: \"{shader}\", writes: {{\"img\": \"{image}\"}}, \
             dispatch: PerPixel(\"{image}\")),"
        )
    };
    let text = format!(
        "Graph(\n    name: \"huge\",\n    resources: {{\n        \"small\": Image(format: R8G8B8A8_UNORM),\n        \
         \"huge\": Image(format: R32G32B32A32_SFLOAT, size: Fixed(16384, 16384)),\n    }},\n    passes: [{} {}],\n    \
         outputs: [\"small\", \"huge\"],\n)\n",
        pass("a", "small", shader),
        pass("b", "huge", float_shader.to_str().unwrap())
    );
    std::fs::write(&graph, text).unwrap();
    let out = tmp.path().join("x.png");
    let (code, _, err) =
        run(&["render", "--graph", graph.to_str().unwrap(), "--size", "8x8", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("huge.ron:5:9: resource 'huge': memory allocation for 'huge' failed"), "{err}");
}

#[test]
fn renders_an_image_and_stats() {
    let tmp = tempfile::tempdir().unwrap();
    let (png, json) = (tmp.path().join("f.png"), tmp.path().join("f.json"));
    let (code, stdout, err) = run(&[
        "render",
        "--scene",
        "builtin:field",
        "--instances",
        "300",
        "--size",
        "40x30",
        "--frames",
        "2",
        "--validation",
        "--out",
        png.to_str().unwrap(),
        "--stats",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}{err}");
    let image = image::open(&png).unwrap();
    assert_eq!((image.width(), image.height()), (40, 30));
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(stats["frames"].as_array().unwrap().len(), 2);
    assert_eq!(stats["frames"][1]["instances"], 300);
    let passes: Vec<&str> =
        stats["frames"][1]["gpu_ms"].as_array().unwrap().iter().map(|t| t["name"].as_str().unwrap()).collect();
    assert_eq!(
        passes,
        ["draw_early", "hiz", "cull_late", "draw_late", "lighting", "tonemap", "transparent_sort", "transparent"]
    );
    // Two-phase culling: frame 1 draws early what frame 0 found visible, the list frame 0's
    // late phase wrote (reported under the draw that drew it; frame 0 had none).
    let culling = |frame: usize| stats["frames"][frame]["culling"].as_array().unwrap().clone();
    let passes: Vec<String> = culling(1).iter().map(|c| c["pass"].as_str().unwrap().to_string()).collect();
    assert_eq!(passes, ["draw_early", "cull_late"]);
    assert_eq!(culling(0)[0]["drawn"], 0, "{:?}", culling(0));
    assert!(culling(1)[0]["drawn"].as_u64().unwrap() > 0, "{:?}", culling(1));
    assert_eq!(culling(1)[0]["tested"], 0, "the early draw list is drawn without a test");
}

/// `--verify` under `--camera-path` far from the origin (`--world-offset`): every frame is
/// checked against exact visibility and loses nothing; `--no-cull` draws everything.
#[test]
fn verify_camera_path_world_offset_and_no_cull_from_the_command_line() {
    let tmp = tempfile::tempdir().unwrap();
    let (png, json) = (tmp.path().join("f.png"), tmp.path().join("f.json"));
    let frames = |extra: &[&str]| -> (String, Vec<serde_json::Value>) {
        let mut args = vec!["render", "--instances", "2000", "--size", "64x36", "--frames", "4", "--validation"];
        args.extend(["--out", png.to_str().unwrap(), "--stats", json.to_str().unwrap()]);
        args.extend(extra);
        let (code, stdout, err) = run(&args);
        assert_eq!(code, 0, "{args:?}: {stdout}{err}");
        let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (stdout, stats["frames"].as_array().unwrap().clone())
    };
    let moving = ["--camera-path", "orbit", "--world-offset", "1e7,0,-1e7"];
    let (stdout, culled) = frames(&[&moving[..], &["--verify"]].concat());
    assert!(stdout.contains("verify: 4 frame(s)") && stdout.contains(" 0 false negatives"), "{stdout}");
    for (f, frame) in culled.iter().enumerate() {
        let verify = &frame["verify"];
        assert_eq!(verify["false_negatives"], 0, "frame {f}: {verify}");
        assert!(verify["visible"].as_u64().unwrap() > 0, "frame {f}: {verify}");
        assert!(frame["drawn"].as_u64().unwrap() < 2000, "frame {f} culls");
    }
    let visible: Vec<&serde_json::Value> = culled.iter().map(|f| &f["verify"]["visible"]).collect();
    assert!(visible.windows(2).any(|w| w[0] != w[1]), "the orbit moves the view: {visible:?}");
    let (_, unculled) = frames(&[&moving[..], &["--no-cull"]].concat());
    for frame in &unculled {
        assert_eq!((frame["drawn"].as_u64(), frame["frustum_culled"].as_u64()), (Some(2000), Some(0)));
    }
}

/// A pool far too small overflows, the lost samples are counted, and `--pool-adapt` grows it from
/// those counters (read a few frames late) until nothing overflows.
#[test]
fn pool_adaptation_grows_a_pool_that_overflows() {
    let tmp = tempfile::tempdir().unwrap();
    let (png, json) = (tmp.path().join("f.png"), tmp.path().join("f.json"));
    let mut args = vec!["render", "--graph", "builtin:msaa_compressed", "--param", "msaa=4", "--instances", "1000"];
    args.extend([
        "--size",
        "48x32",
        "--param",
        "pool_fraction=0.002",
        "--pool-adapt",
        "--frames",
        "10",
        "--validation",
    ]);
    args.extend(["--out", png.to_str().unwrap(), "--stats", json.to_str().unwrap()]);
    let (code, stdout, err) = run(&args);
    assert_eq!(code, 0, "{stdout}{err}");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let pools: Vec<(u64, u64)> = stats["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (f["gbuffer"][0]["pool_blocks"].as_u64().unwrap(), f["gbuffer"][0]["overflow_samples"].as_u64().unwrap())
        })
        .collect();
    let (first, last) = (pools[0], *pools.last().unwrap());
    assert!(first.1 > 0, "the small pool overflows: {pools:?}");
    assert!(last.0 > first.0 && last.1 == 0, "the pool grew until nothing overflowed: {pools:?}");
}

/// With `--pool-adapt` the stats report the memory of the graph the last frame ran, after the
/// pool was re-planned, not of the graph the run started with.
#[test]
fn pool_adaptation_is_reflected_in_the_reported_memory() {
    let tmp = tempfile::tempdir().unwrap();
    let pool_bytes = |adapt: bool, frames: &str| -> (u64, u64) {
        let (png, json) = (tmp.path().join("f.png"), tmp.path().join("f.json"));
        // A pool far larger than the frame needs (4 blocks per pixel), so adapting shrinks it.
        let mut args = vec!["render", "--graph", "builtin:msaa_compressed", "--instances", "1000", "--size", "32x24"];
        args.push("--validation");
        args.extend(["--param", "pool_fraction=4"]);
        args.extend(["--frames", frames, "--out", png.to_str().unwrap(), "--stats", json.to_str().unwrap()]);
        if adapt {
            args.push("--pool-adapt");
        }
        let (code, stdout, err) = run(&args);
        assert_eq!(code, 0, "{stdout}{err}");
        let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let resources = stats["resources"].as_array().unwrap();
        let gbuffer = resources.iter().find(|r| r["name"] == "gbuffer_pool").unwrap()["bytes"].as_u64().unwrap();
        let frames = stats["frames"].as_array().unwrap();
        let pool = frames.last().unwrap()["gbuffer"][0]["pool_blocks"].as_u64().unwrap();
        (gbuffer, pool)
    };
    let (fixed_bytes, fixed_pool) = pool_bytes(false, "1");
    // The pool shrinks after 30 mostly empty frames; the new graph runs from the next frame.
    let (adapted_bytes, adapted_pool) = pool_bytes(true, "36");
    assert!(adapted_pool < fixed_pool, "the pool did not shrink: {adapted_pool} of {fixed_pool} blocks");
    assert!(adapted_bytes < fixed_bytes, "reported {adapted_bytes} bytes after adapting, {fixed_bytes} before");
}

/// `cullgraph render --watch` on `graph`, its stdout and stderr lines merged into one stream.
struct Watching {
    child: std::process::Child,
    lines: mpsc::Receiver<String>,
    seen: Vec<String>,
}

impl Watching {
    fn start(graph: &std::path::Path, png: &std::path::Path) -> Self {
        #[rustfmt::skip]
        let mut child = cullgraph()
            .args(["render", "--scene", "builtin:field", "--instances", "100", "--size", "32x24", "--watch", "--watch-for", "60"])
            .arg("--graph").arg(graph).arg("--out").arg(png)
            .stdout(Stdio::piped()).stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (tx, lines) = mpsc::channel::<String>();
        for stream in [
            Box::new(child.stdout.take().unwrap()) as Box<dyn std::io::Read + Send>,
            Box::new(child.stderr.take().unwrap()),
        ] {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stream).lines().map_while(Result::ok) {
                    let _ = tx.send(line);
                }
            });
        }
        Self { child, lines, seen: Vec::new() }
    }

    /// Whether a line containing `needle` comes within 40 s.
    fn wait_for(&mut self, needle: &str) -> bool {
        let deadline = Instant::now() + Duration::from_secs(40);
        while Instant::now() < deadline {
            if let Ok(line) = self.lines.recv_timeout(Duration::from_millis(200)) {
                self.seen.push(line.clone());
                if line.contains(needle) {
                    return true;
                }
            }
        }
        false
    }
}

impl Drop for Watching {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn watch_reloads_on_change_and_keeps_the_last_good_graph_on_error() {
    let tmp = tempfile::tempdir().unwrap();
    let graph = tmp.path().join("g.ron");
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/graph/two_phase.ron")).unwrap();
    std::fs::write(&graph, &good).unwrap();
    let png = tmp.path().join("w.png");
    let mut watch = Watching::start(&graph, &png);
    assert!(watch.wait_for("watching"), "no start: {:?}", watch.seen);
    // Break the graph: an unknown resource, positioned.
    std::fs::write(&graph, good.replace("writes: {\"output\": \"color\"}", "writes: {\"output\": \"colour\"}"))
        .unwrap();
    assert!(watch.wait_for("still running the last good graph"), "no error reported: {:?}", watch.seen);
    assert!(watch.seen.iter().any(|l| l.contains("g.ron:") && l.contains("colour")), "{:?}", watch.seen);
    // Fix it with a visible change.
    std::fs::write(&graph, good.replace("\"exposure\": 0.8", "\"exposure\": 1.6")).unwrap();
    assert!(watch.wait_for("reloaded"), "no reload: {:?}", watch.seen);
    // A graph that compiles but cannot record a frame (it lights into an image only an engine
    // provides): the last good graph comes back and keeps rendering.
    let host = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples/host_target.ron")).unwrap();
    std::fs::write(&graph, host).unwrap();
    assert!(watch.wait_for("back to the last good graph"), "no fallback: {:?}", watch.seen);
    assert!(
        watch.seen.iter().any(|l| l.contains("14:9: resource 'color': is imported, but the host provided nothing")),
        "{:?}",
        watch.seen
    );
    assert!(watch.wait_for("rendered 'two_phase'"), "the last good graph renders again: {:?}", watch.seen);
    drop(watch);
    assert!(png.exists());
}

#[test]
fn watch_follows_the_headers_a_user_shader_includes() {
    let tmp = tempfile::tempdir().unwrap();
    let examples = concat!(env!("CARGO_MANIFEST_DIR"), "/graph/examples");
    let graph = tmp.path().join("tint.ron");
    std::fs::copy(format!("{examples}/tint.ron"), &graph).unwrap();
    // The tint's factor moves to a header next to the shader.
    let shader = std::fs::read_to_string(format!("{examples}/tint.comp")).unwrap();
    let shader = shader
        .replace("layout(local_size_x", "#include \"tint_factor.glsl\"\nlayout(local_size_x")
        .replace("vec3(1.0, 0.85, 0.7)", "TINT_FACTOR");
    std::fs::write(tmp.path().join("tint.comp"), shader).unwrap();
    let header = tmp.path().join("tint_factor.glsl");
    std::fs::write(&header, "#define TINT_FACTOR vec3(1.0, 0.85, 0.7)\n").unwrap();
    let png = tmp.path().join("w.png");
    let mut watch = Watching::start(&graph, &png);
    assert!(watch.wait_for("watching"), "no start: {:?}", watch.seen);
    let first = std::fs::read(&png).unwrap();
    // An error in the header is reported against the header, and the last good graph stays.
    std::fs::write(&header, "#define TINT_FACTOR vec3(1.0, 0.85, 0.7)\nconst float broken = ;\n").unwrap();
    assert!(watch.wait_for("still running the last good graph"), "header edit not seen: {:?}", watch.seen);
    assert!(watch.seen.iter().any(|l| l.contains("tint_factor.glsl")), "{:?}", watch.seen);
    std::fs::write(&header, "#define TINT_FACTOR vec3(0.5)\n").unwrap();
    // (A reload is announced once its first frame is written.)
    assert!(watch.wait_for("reloaded"), "no reload: {:?}", watch.seen);
    assert_ne!(std::fs::read(&png).unwrap(), first, "the header's new factor reached the image");
}

#[test]
fn reference_reports_flip_and_psnr_and_refuses_what_the_device_cannot_render() {
    let tmp = tempfile::tempdir().unwrap();
    let (png, json) = (tmp.path().join("r.png"), tmp.path().join("r.json"));
    let (png, json) = (png.to_str().unwrap(), json.to_str().unwrap());
    let base = ["render", "--scene", "builtin:field", "--instances", "200", "--out", png, "--stats", json];
    let (code, stdout, err) =
        run(&[&base[..], &["--size", "64x36", "--graph", "builtin:fxaa", "--reference", "2"]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("reference (4 samples per pixel): mean FLIP"), "{stdout}");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let reference = &stats["reference"];
    assert_eq!(reference["samples_per_pixel"], 4, "{stats}");
    let flip = reference["mean_flip"].as_f64().unwrap();
    assert!((0.0..1.0).contains(&flip), "{reference}");
    assert!(reference["psnr_db"].as_f64().unwrap() > 10.0, "{reference}");

    // 16384 x 4 is over every device's maxImageDimension2D we run on: refused before rendering.
    std::fs::remove_file(png).unwrap();
    let (code, _, err) = run(&[&base[..], &["--size", "16384x4", "--reference"]].concat());
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("maxImageDimension2D"), "{err}");
    assert!(!std::path::Path::new(png).exists());
    let (code, _, err) = run(&[&base[..], &["--reference", "0"]].concat());
    assert_eq!(code, 2, "{err}");
}

/// `--animate`: traffic through the city, every frame verified against exact visibility, and
/// each frame's stats report the world changes it applied.
#[test]
fn animate_drives_traffic_and_culling_stays_exact() {
    let tmp = tempfile::tempdir().unwrap();
    let (png, json) = (tmp.path().join("f.png"), tmp.path().join("f.json"));
    #[rustfmt::skip]
    let (code, stdout, err) = run(&[
        "render", "--animate", "--instances", "2000", "--size", "64x48", "--frames", "6", "--verify",
        "--out", png.to_str().unwrap(), "--stats", json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}{err}");
    assert!(stdout.contains("0 false negatives"), "{stdout}");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for frame in stats["frames"].as_array().unwrap() {
        let update = &frame["update"];
        assert!(update["instances_changed"].as_u64().unwrap() >= 40, "every vehicle moves: {update}");
        assert!(update["bytes_uploaded"].as_u64().unwrap() > 0, "{update}");
    }
    let (code, _, err) = run(&["render", "--animate", "--scene", "builtin:field", "--out", png.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(err.contains("--animate plays a scene's glTF animations or drives traffic through builtin:city; builtin:field has no animation"), "{err}");
}

/// `--stream N`: the scene arrives in a live world in N pieces, one a frame, each verified
/// against exact visibility; once all are in, the frame is the plain render's.
#[test]
fn stream_adds_the_scene_in_pieces_and_ends_on_the_plain_image() {
    let tmp = tempfile::tempdir().unwrap();
    let (streamed, plain) = (tmp.path().join("s.png"), tmp.path().join("p.png"));
    let base = ["render", "--instances", "1500", "--size", "64x48", "--frames", "5"];
    let (code, stdout, err) =
        run(&[&base[..], &["--stream", "3", "--verify", "--out", streamed.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{stdout}{err}");
    for piece in ["piece 1/3: 500 instances", "piece 2/3: 500 instances", "piece 3/3: 500 instances"] {
        assert!(stdout.contains(piece), "{stdout}");
    }
    assert!(stdout.contains("0 false negatives"), "{stdout}");
    let probe = stdout.lines().find(|l| l.starts_with("registration into 1500 instances: 1 mesh")).unwrap_or_default();
    assert!(probe.contains("MB uploaded") && !probe.contains("laid out anew"), "{stdout}");
    let (code, stdout, err) = run(&[&base[..], &["--out", plain.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{stdout}{err}");
    assert!(std::fs::read(&streamed).unwrap() == std::fs::read(&plain).unwrap(), "the streamed frame differs");
    let (code, _, err) = run(&["render", "--stream", "2", "--animate", "--out", plain.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
}

/// `--animate` plays a scene's animation: the skinned crowd and a glTF file with morph targets
/// (assimp's AnimatedMorphCube), culled exactly on every frame, and the pose shows (the last
/// frame differs from the rest pose).
#[test]
fn animate_plays_skinned_and_morphed_scenes() {
    let tmp = tempfile::tempdir().unwrap();
    let morph_cube = "/usr/share/assimp/models/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf";
    for scene in ["builtin:crowd", morph_cube] {
        let (rest, posed) = (tmp.path().join("rest.png"), tmp.path().join("posed.png"));
        let base = ["render", "--scene", scene, "--instances", "40", "--size", "64x48"];
        let (code, stdout, err) = run(&[&base[..], &["--frames", "1", "--out", rest.to_str().unwrap()]].concat());
        assert_eq!(code, 0, "{scene}: {stdout}{err}");
        let animate = ["--animate", "--frames", "20", "--verify", "--out", posed.to_str().unwrap()];
        let (code, stdout, err) = run(&[&base[..], &animate[..]].concat());
        assert_eq!(code, 0, "{scene}: {stdout}{err}");
        assert!(stdout.contains("0 false negatives"), "{scene}: {stdout}");
        assert!(std::fs::read(&rest).unwrap() != std::fs::read(&posed).unwrap(), "{scene}: the animation shows");
    }
}

/// `--sun X,Y,Z` lights the scene from that direction; no direction is an error naming the flag.
#[test]
fn sun_flag_moves_the_light_and_refuses_no_direction() {
    let tmp = tempfile::tempdir().unwrap();
    let (plain, lit) = (tmp.path().join("p.png"), tmp.path().join("s.png"));
    let base = ["render", "--instances", "1000", "--size", "64x48", "--frames", "1"];
    let (code, stdout, err) = run(&[&base[..], &["--out", plain.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{stdout}{err}");
    let (code, stdout, err) = run(&[&base[..], &["--sun", "1,0.2,-1", "--out", lit.to_str().unwrap()]].concat());
    assert_eq!(code, 0, "{stdout}{err}");
    assert!(std::fs::read(&plain).unwrap() != std::fs::read(&lit).unwrap(), "the sun moved");
    let (code, _, err) = run(&[&base[..], &["--sun", "0,0,0"]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--sun") && err.contains("finite and not zero"), "{err}");
}

/// `--stream` on a real level, frames submitted without waiting: the pieces grow the world in
/// place while earlier frames still execute, and nothing they use is destroyed under them (the
/// culling passes' scratch memory, sized for the slots, is replaced as the level grows; a
/// validation message fails the command).
#[test]
fn streaming_a_level_while_frames_are_in_flight_is_clean() {
    let level = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/nexuiz_ons-reborn.glb");
    let level =
        if level.exists() { level } else { std::path::Path::new("/work/shared/assets/nexuiz_ons-reborn.glb").into() };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("s.png");
    let (code, stdout, err) = run(&[
        "render",
        "--scene",
        level.to_str().unwrap(),
        "--stream",
        "4",
        "--frames",
        "7",
        "--size",
        "64x36",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}{err}");
    assert!(stdout.contains("piece 4/4") && stdout.contains("registration into"), "{stdout}");
}

/// `--shadows on` on a real level, at a player spawn among alpha-masked trees: the foliage's
/// holed shadows and everything else come out the same with caster culling as with every
/// caster drawn (`--no-caster-cull`), and differ from the image without shadows.
#[test]
fn shadows_on_a_level_are_the_same_with_and_without_caster_culling() {
    let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets");
    let assets = if assets.exists() { assets } else { std::path::Path::new("/work/shared/assets").into() };
    let spawns = std::fs::read_to_string(assets.join("nexuiz_spawns.txt")).unwrap();
    let spawn: Vec<&str> = spawns.lines().filter(|l| l.starts_with("ons-reborn ")).nth(8).unwrap().split(' ').collect();
    let level = assets.join("nexuiz_ons-reborn.glb");
    let tmp = tempfile::tempdir().unwrap();
    let image = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let eye = format!("--eye={}", spawn[1]);
        let target = format!("--target={}", spawn[2]);
        let base = [
            "render",
            "--scene",
            level.to_str().unwrap(),
            &eye,
            &target,
            "--size",
            "160x90",
            "--frames",
            "2",
            "--validation",
        ];
        let (code, stdout, err) = run(&[&base[..], extra, &["--out", out.to_str().unwrap()]].concat());
        assert_eq!(code, 0, "{stdout}{err}");
        std::fs::read(out).unwrap()
    };
    let culled = image("culled.png", &["--shadows", "on"]);
    assert!(
        culled == image("unculled.png", &["--shadows", "on", "--no-caster-cull"]),
        "caster culling changed the image"
    );
    assert!(culled != image("unshadowed.png", &["--shadows", "off"]), "the level casts shadows");
}
