//! `cullgraph render --projection` and `--jitter` as a user runs them: each projection renders
//! its own image, culls, and loses no visible instance (`--verify`), validation clean; bad values
//! are refused naming the flag.

mod common;

use common::cli::run;

/// Renders the default scene at 48x32 for 3 frames with `extra` flags: the PNG's bytes and the
/// stats of each frame.
fn render(tmp: &std::path::Path, name: &str, extra: &[&str]) -> (Vec<u8>, Vec<serde_json::Value>) {
    let (png, json) = (tmp.join(format!("{name}.png")), tmp.join(format!("{name}.json")));
    let mut args =
        vec!["render", "--instances", "1500", "--size", "48x32", "--frames", "3", "--verify", "--validation"];
    args.extend(["--out", png.to_str().unwrap(), "--stats", json.to_str().unwrap()]);
    args.extend(extra);
    let (code, stdout, err) = run(&args);
    assert_eq!(code, 0, "{args:?}: {stdout}{err}");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    (std::fs::read(&png).unwrap(), stats["frames"].as_array().unwrap().clone())
}

#[test]
fn every_projection_and_jitter_renders_its_own_image_and_culls_without_loss() {
    let tmp = tempfile::tempdir().unwrap();
    let (default, _) = render(tmp.path(), "default", &[]);
    let cases: [(&str, &[&str]); 6] = [
        ("far", &["--projection", "far:60"]),
        ("ortho", &["--projection", "ortho:40"]),
        ("offcenter", &["--projection", "offcenter:-40,25,30,-20"]),
        ("halton", &["--jitter", "halton"]),
        ("fixed", &["--jitter", "0.5,-0.25"]),
        ("offcenter_halton", &["--projection", "offcenter:-30,35,25,-30", "--jitter", "halton"]),
    ];
    let (infinite, _) = render(tmp.path(), "infinite", &["--projection", "infinite"]);
    assert!(infinite == default, "--projection infinite is the default projection");
    for (name, flags) in cases {
        let (image, frames) = render(tmp.path(), name, flags);
        assert!(image != default, "{name}: the image equals the default projection's");
        for (f, frame) in frames.iter().enumerate() {
            assert_eq!(frame["verify"]["false_negatives"], 0, "{name} frame {f}: {}", frame["verify"]);
            let culled = frame["frustum_culled"].as_u64().unwrap() + frame["occlusion_culled"].as_u64().unwrap();
            assert!(culled > 0, "{name} frame {f} culls nothing: {frame}");
        }
    }
    // A far plane close to the eye culls more by frustum than no far plane.
    let frustum = |frames: &[serde_json::Value]| frames[0]["frustum_culled"].as_u64().unwrap();
    let (_, near_far) = render(tmp.path(), "near_far", &["--projection", "far:15"]);
    let (_, no_far) = render(tmp.path(), "no_far", &["--projection", "infinite"]);
    assert!(frustum(&near_far) > frustum(&no_far), "{} vs {}", frustum(&near_far), frustum(&no_far));
}

#[test]
fn bad_projections_and_jitters_are_refused_naming_the_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("x.png");
    let out = out.to_str().unwrap();
    for (flag, value, words) in [
        ("--projection", "far:-1", "must be positive"),
        ("--projection", "ortho:0", "must be positive"),
        ("--projection", "offcenter:-40,25,30", "four angles"),
        ("--projection", "offcenter:-40,25,95,-20", "(-90, 90)"),
        ("--projection", "offcenter:25,-40,30,-20", "left < right"),
        ("--projection", "fisheye", "is not infinite, far:D, ortho:H or offcenter:L,R,U,D"),
        ("--jitter", "2,0", "at most 1 pixel"),
        ("--jitter", "sobol", "is not halton or X,Y"),
    ] {
        let (code, _, err) = run(&["render", "--size", "16x16", flag, value, "--out", out]);
        assert_eq!(code, 2, "{flag} {value}: {err}");
        assert!(err.contains(flag) && err.contains(words), "{flag} {value}: {err}");
    }
    // A far plane before the near plane is refused once the camera is known, naming the flag.
    let (code, _, err) = run(&["render", "--size", "16x16", "--near", "2", "--projection", "far:1", "--out", out]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--projection far:1") && err.contains("beyond the near plane"), "{err}");
    assert!(!std::path::Path::new(out).exists());
}
