//! Fuzzing in the test suite: every input the fuzzers ever found breaking a promise
//! (`tests/fuzz/graph/*.ron`, `tests/fuzz/gltf/*.glb`) now gives a positioned error or renders
//! without a validation message, and a short run of each target (`cullgraph fuzz`, 20 seconds)
//! finds nothing new: no panic, crash, hang, unpositioned error, validation message, or graph
//! that passes the check and fails to render.
//!
//! Longer runs: `make fuzz MINUTES=10` (see docs/fuzzing.md).

mod common;

use common::cli::run;
use std::path::{Path, PathBuf};

fn regressions(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz").join(target);
    // git keeps no empty folder, so a target with no regression yet has none.
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    files.sort();
    files
}

#[test]
fn every_input_the_fuzzers_found_is_handled() {
    let mut checked = 0;
    for target in ["graph", "gltf"] {
        for file in regressions(target) {
            let (code, out, err) = run(&["fuzz", target, "--replay", file.to_str().unwrap()]);
            assert_eq!(code, 0, "{}: {out}{err}", file.display());
            assert!(out.contains(": ok") || out.contains(": positioned error"), "{}: {out}", file.display());
            checked += 1;
        }
    }
    assert!(checked >= 2, "the regression inputs are there");
}

/// A 20-second run of `target` finds no input that breaks a promise; the report counts the
/// inputs by outcome.
fn smoke(target: &str, seeds: &[&str]) {
    let out = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut args = vec!["fuzz", target, "--seconds", "20", "--out", out.path().to_str().unwrap()];
    let seeds: Vec<String> = seeds.iter().map(|s| root.join(s).display().to_string()).collect();
    for s in &seeds {
        args.extend(["--seeds", s]);
    }
    let (code, report, err) = run(&args);
    assert_eq!(code, 0, "{report}{err}");
    let count = |class: &str| -> u64 {
        let line = report.lines().find(|l| l.starts_with(&format!("| {class} |"))).expect(class);
        line.trim_end_matches(" |").rsplit("| ").next().unwrap().trim().parse().unwrap()
    };
    assert!(count("ok") > 0 && count("positioned error") > 0, "{report}");
    let mut failures = vec!["unpositioned error", "validation message", "panic", "crash", "hang"];
    if target == "graph" {
        failures.push("check lied");
    }
    for class in failures {
        assert_eq!(count(class), 0, "{class}: {report}");
    }
    // Most inputs are edited in their structure, and all of those are still well-formed.
    let row = report.lines().find(|l| l.starts_with("| structure |")).expect("the structure row");
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    let inputs: u64 = cells[2].parse().unwrap();
    assert!(inputs * 10 > count_all(&report) * 6, "{report}");
    assert!(cells[3].starts_with(&format!("{inputs} (100.0 %)")), "{report}");
}

/// The inputs of a report.
fn count_all(report: &str) -> u64 {
    let title = report.lines().next().unwrap();
    title.split("): ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn a_short_graph_fuzz_finds_nothing() {
    smoke("graph", &["graph/examples", "tests/graphs/bad", "tests/graphs/gpu"]);
}

#[test]
fn a_short_gltf_fuzz_finds_nothing() {
    smoke("gltf", &[]);
}
