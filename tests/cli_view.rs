//! `cullgraph view` in a window on a virtual X server (Xvfb, which `scripts/install-deps`
//! installs): frames presented, a scripted resize, scripted input that moves the camera, the
//! screenshot against the headless render of the same camera, hot reload of a broken graph,
//! the keys, and a machine without a display. Validation is on for every run.

mod common;

use common::cli::{cullgraph, run, run_command_within};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A virtual X server of its own for one test, stopped when dropped.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Self {
        // -displayfd: the server picks a free display and writes its number once it accepts
        // clients.
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb (a virtual X server) is missing: run scripts/install-deps");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let number = line.trim();
        assert!(!number.is_empty(), "Xvfb did not start");
        Self { child, display: format!(":{number}") }
    }

    /// `cullgraph view ARGS` on this display, within `seconds`.
    fn view(&self, args: &[&str], seconds: u64) -> (i32, String, String) {
        let mut command = cullgraph();
        command.env("DISPLAY", &self.display).arg("view").args(args);
        run_command_within(command, Duration::from_secs(seconds))
    }
}

impl Xvfb {
    /// `view` of the 2,000-instance city at `size` for `frames` frames, playing `script` (when
    /// not empty) and writing the last frame to `shot`; `extra` flags after those.
    fn run_city(&self, size: &str, frames: u32, script: &str, shot: &Path, extra: &[&str]) -> (i32, String, String) {
        let script_file = shot.with_extension("script.txt");
        std::fs::write(&script_file, script).unwrap();
        let frames = frames.to_string();
        let mut args = vec!["--instances", "2000", "--size", size, "--frames", &frames];
        args.extend(["--screenshot", shot.to_str().unwrap()]);
        if !script.is_empty() {
            args.extend(["--script", script_file.to_str().unwrap()]);
        }
        args.extend_from_slice(extra);
        self.view(&args, 180)
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn rgba(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8()
}

/// The largest channel difference between two images of one size, and the share of pixels
/// that differ at all.
fn difference(a: &image::RgbaImage, b: &image::RgbaImage) -> (u8, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let mut max = 0;
    let mut differing = 0;
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap();
        max = max.max(d);
        differing += (d > 0) as usize;
    }
    (max, differing as f64 / (a.width() * a.height()) as f64)
}

/// `render` of the same scene and camera, headless.
fn headless(out: &Path, extra: &[&str]) {
    let mut args = vec!["render", "--scene", "builtin:city", "--instances", "2000", "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
}

/// `view: camera eye=X,Y,Z target=X,Y,Z, flying at S units/s` of a run's output.
fn final_camera(stdout: &str) -> ([f64; 3], [f64; 3], f64) {
    let line = stdout.lines().find(|l| l.starts_with("view: camera ")).unwrap_or_else(|| panic!("{stdout}"));
    let field = |key: &str| -> [f64; 3] {
        let rest = &line[line.find(key).unwrap() + key.len()..];
        let v: Vec<f64> =
            rest.split([' ', ',']).filter(|s| !s.is_empty()).take(3).map(|s| s.parse().unwrap()).collect();
        [v[0], v[1], v[2]]
    };
    let speed: f64 = line.split("flying at ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    (field("eye="), field("target="), speed)
}

#[test]
fn frames_are_presented_and_the_last_equals_the_headless_render() {
    let x = Xvfb::start();
    let tmp = tempfile::tempdir().unwrap();
    let shot = tmp.path().join("shot.png");
    let (code, out, err) = x.run_city("160x96", 6, "", &shot, &[]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(out.contains("view: 6 frames presented at 160x96"), "{out}");
    let reference = tmp.path().join("render.png");
    headless(&reference, &["--size", "160x96"]);
    let (max, share) = difference(&rgba(&shot), &rgba(&reference));
    assert!(max <= 2 && share < 0.001, "the window's frame differs from render's: max {max}, {share} of pixels");
}

#[test]
fn a_scripted_resize_changes_the_window_and_the_frame_follows() {
    let x = Xvfb::start();
    let tmp = tempfile::tempdir().unwrap();
    let shot = tmp.path().join("shot.png");
    let (code, out, err) = x.run_city("160x96", 8, "2 resize 120x72\n", &shot, &[]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(out.contains("presented at 120x72"), "{out}");
    let reference = tmp.path().join("render.png");
    headless(&reference, &["--size", "120x72"]);
    let (max, share) = difference(&rgba(&shot), &rgba(&reference));
    assert!(max <= 2 && share < 0.001, "after the resize: max {max}, {share} of pixels");
}

#[test]
fn scripted_keys_and_mouse_move_the_camera_where_expected() {
    let x = Xvfb::start();
    let tmp = tempfile::tempdir().unwrap();
    let shot = tmp.path().join("shot.png");
    // Forward for 30 frames (half a second), then a quarter turn to the right by the mouse.
    let turn = std::f64::consts::FRAC_PI_2 / 0.003;
    let script = format!("# fly\n0 key W down\n30 key W up\n31 look {turn} 0\n");
    let (code, out, err) = x.run_city("128x80", 34, &script, &shot, &["--eye", "0,20,120", "--target", "0,20,0"]);
    assert_eq!(code, 0, "{out}\n{err}");
    let (eye, target, speed) = final_camera(&out);
    let moved = speed * 30.0 / 60.0;
    assert!((eye[0]).abs() < 1e-3 && (eye[1] - 20.0).abs() < 1e-3, "{eye:?}");
    assert!((eye[2] - (120.0 - moved)).abs() < 1e-2, "{eye:?}, moved {moved}");
    // Looking along +X now.
    let look = [target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]];
    assert!(look[0] > 0.999 && look[2].abs() < 1e-3, "{look:?}");
    let reference = tmp.path().join("render.png");
    let (eye_arg, target_arg) =
        (format!("{},{},{}", eye[0], eye[1], eye[2]), format!("{},{},{}", target[0], target[1], target[2]));
    headless(&reference, &["--size", "128x80", "--eye", &eye_arg, "--target", &target_arg]);
    let (max, share) = difference(&rgba(&shot), &rgba(&reference));
    // The printed camera is rounded to 1e-4: a few edge pixels may fall the other way.
    assert!(share < 0.01, "the scripted camera's frame differs from render's there: max {max}, {share} of pixels");
}

#[test]
fn the_keys_switch_overlay_graphs_shadows_traffic_and_frozen_culling_without_a_validation_message() {
    let x = Xvfb::start();
    let tmp = tempfile::tempdir().unwrap();
    let shot = tmp.path().join("shot.png");
    let script = "1 press H\n2 press O\n3 press V\n4 press V\n5 press L\n6 press G\n7 key Shift down\n7 press G\n7 key Shift up\n\
         8 press O\n9 press F\n10 key S down\n13 key S up\n14 press F\n15 press T\n17 press C\n18 wheel 2\n19 press P\n20 press H\n";
    let (code, out, err) = x.run_city("128x80", 22, script, &shot, &[]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(!err.contains("error:"), "{err}");
    let frozen = out.lines().find(|l| l.starts_with("culling frozen: the ")).unwrap_or_else(|| panic!("{out}"));
    let numbers: Vec<usize> = frozen.split(' ').filter_map(|w| w.parse().ok()).collect();
    assert!(numbers[0] > 0 && numbers[1] > 0, "{frozen}");
    assert!(out.contains(&format!("culling follows the camera again ({} instances back)", numbers[1])), "{out}");
    // P wrote a numbered screenshot beside --screenshot, and --frames the last one.
    assert!(tmp.path().join("shot.1.png").is_file() && shot.is_file(), "{out}");
}

#[test]
fn a_graph_that_breaks_while_running_keeps_the_last_good_one_and_says_why() {
    let x = Xvfb::start();
    let tmp = tempfile::tempdir().unwrap();
    let graph = tmp.path().join("g.ron");
    std::fs::write(&graph, "Graph(name: \"mine\", extends: \"frustum\")\n").unwrap();
    let shot = tmp.path().join("shot.png");
    let mut command = cullgraph();
    command.env("DISPLAY", &x.display).args([
        "view",
        "--instances",
        "2000",
        "--size",
        "96x64",
        "--graph",
        graph.to_str().unwrap(),
        "--frames",
        "100000",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    let mut child = command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    stdout.read_line(&mut line).unwrap();
    assert!(line.starts_with("view: ") && line.contains("through 'mine'"), "{line}");
    // Broken on line 2; then, once the error was reported, fixed again.
    std::fs::write(&graph, "Graph(name: \"mine\",\n  extends: 7)\n").unwrap();
    let stderr = child.stderr.take().unwrap();
    let mut errors = BufReader::new(stderr).lines();
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    let mut said = String::new();
    while !said.contains("still running the last good graph") {
        assert!(std::time::Instant::now() < deadline, "no reload error within a minute: {said}");
        said.push_str(&errors.next().unwrap().unwrap());
        said.push('\n');
    }
    assert!(said.contains("g.ron:2:"), "the error names the file and line: {said}");
    std::fs::write(&graph, "Graph(name: \"mine again\", extends: \"frustum\")\n").unwrap();
    let mut reloaded = String::new();
    while !reloaded.contains("reloaded 'mine again'") {
        reloaded.clear();
        assert!(stdout.read_line(&mut reloaded).unwrap() > 0, "ended before reloading");
    }
    let _ = child.kill();
    let _ = child.wait();
}

#[test]
fn without_a_display_or_with_bad_input_it_says_so_and_exits_1() {
    let tmp = tempfile::tempdir().unwrap();
    let mut command = cullgraph();
    command.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").args(["view", "--frames", "1"]);
    let (code, _, err) = run_command_within(command, Duration::from_secs(60));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no display"), "{err}");
    let x = Xvfb::start();
    let script = tmp.path().join("bad.txt");
    std::fs::write(&script, "3 key W down\n4 key Y down\n").unwrap();
    for (args, want) in [
        (vec!["--scene", "builtin:nope"], "nope"),
        (vec!["--graph", "missing.ron"], "missing.ron"),
        (vec!["--graph", "builtin:nope"], "unknown built-in graph 'nope'"),
        (vec!["--script", script.to_str().unwrap()], "bad.txt:2: unknown key 'Y'"),
    ] {
        let mut all = args.clone();
        all.extend(["--frames", "1"]);
        let (code, _, err) = x.view(&all, 60);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}
