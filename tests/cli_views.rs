//! `cullgraph render --view ... --resize ...` as a user runs it: several views of one world
//! per frame, each with its own image and figures, and outputs that change size mid-run.

mod common;

use common::cli::run;

fn png_size(path: &std::path::Path) -> (u32, u32) {
    let image = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (image.width(), image.height())
}

#[test]
fn several_views_write_their_images_and_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("f.png");
    let stats = tmp.path().join("s.json");
    let (code, stdout, err) = run(&[
        "render",
        "--scene",
        "builtin:city",
        "--instances",
        "1500",
        "--size",
        "48x32",
        "--view",
        "eye=0,60,150;target=0,0,0",
        "--view",
        "eye=-60,3,-60;target=60,1,60;fov=70;size=40x20",
        "--frames",
        "3",
        "--resize",
        "36x24@2",
        "--verify",
        "--validation",
        "--out",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("0 false negatives"), "{stdout}");
    // Resized from frame 2 on: the last images have the new size.
    for n in 0..2 {
        assert_eq!(png_size(&tmp.path().join(format!("f.view{n}.png"))), (36, 24));
    }
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let views = json["views"].as_array().expect("a views array");
    assert_eq!(views.len(), 2);
    for (n, view) in views.iter().enumerate() {
        assert_eq!(view["view"], n);
        assert_eq!(view["frames"].as_array().unwrap().len(), 3);
        assert!(view["view_bytes"].as_u64().unwrap() > 0);
        let last = &view["frames"][2];
        assert!(last["drawn"].as_u64().unwrap() > 0 && last["drawn"].as_u64() < last["instances"].as_u64());
    }
    // The two cameras see different things.
    assert_ne!(views[0]["frames"][2]["drawn"], views[1]["frames"][2]["drawn"]);
}

#[test]
fn a_resize_without_views_changes_the_image_size() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("f.png");
    let (code, _, err) = run(&[
        "render",
        "--size",
        "32x32",
        "--frames",
        "3",
        "--resize",
        "17x9@1",
        "--resize",
        "20x12@2",
        "--validation",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(png_size(&out), (20, 12));
}

#[test]
fn bad_views_and_resizes_name_the_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("f.png");
    let out = out.to_str().unwrap();
    for (args, says) in [
        (vec!["--view", "eye=1,2,3"], "target"),
        (vec!["--view", "eye=1,2,3;target=0,0,0;size=0x3"], "0x3"),
        (vec!["--view", "eye=1,2,3;target=0,0,0;zoom=2"], "zoom"),
        (vec!["--resize", "10x10"], "WxH@FRAME"),
        (vec!["--resize", "0x10@1"], "between 1 and 16384"),
        (vec!["--view", "eye=1,2,3;target=0,0,0", "--eye", "1,1,1"], "--eye"),
    ] {
        let mut all = vec!["render", "--out", out];
        all.extend(args.iter().copied());
        let (code, _, err) = run(&all);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        let flag = args[0];
        assert!(err.contains(flag), "{args:?}: the error names {flag}: {err}");
    }
}
