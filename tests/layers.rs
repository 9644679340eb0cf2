//! The library's layers, and the documentation of its pass kinds, checked against the code.
//!
//! Layers, each using only those below it: `gpu` <- `graph` <- (`cull`, `scene`, `stats`: plain
//! data and math) <- `passes` <- `render` <- `oracle` (verification, which attaches to a
//! renderer from outside) <- `bench` <- `cli`. The graph knows no pass kind; every kind,
//! built-in or an engine's, reaches it through the registry. Every pair of layers is checked:
//! a module may use exactly the ones [`MAY_USE`] lists for it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The library's modules (a file or a folder of `src/`), each with every module it may use.
const MAY_USE: &[(&str, &[&str])] = &[
    ("files.rs", &[]),
    ("parallel.rs", &[]),
    ("gpu", &["files.rs", "parallel.rs"]),
    ("graph", &["files.rs", "parallel.rs", "gpu"]),
    ("scene", &["files.rs", "parallel.rs", "gpu"]),
    ("cull", &["files.rs", "parallel.rs", "gpu", "scene"]),
    ("stats", &["files.rs", "parallel.rs", "gpu", "graph"]),
    ("passes", &["files.rs", "parallel.rs", "gpu", "graph", "cull", "scene", "stats"]),
    ("render", &["files.rs", "parallel.rs", "gpu", "graph", "cull", "scene", "stats", "passes"]),
    ("oracle", &["files.rs", "parallel.rs", "gpu", "graph", "cull", "scene", "stats", "passes", "render"]),
    ("bench", &["files.rs", "parallel.rs", "gpu", "graph", "cull", "scene", "stats", "passes", "render", "oracle"]),
    (
        "cli",
        &["files.rs", "parallel.rs", "gpu", "graph", "cull", "scene", "stats", "passes", "render", "oracle", "bench"],
    ),
];

/// The modules `module` must not use: every other one.
fn forbidden(module: &str) -> Vec<&'static str> {
    let allowed = MAY_USE.iter().find(|(m, _)| *m == module).map_or(&[][..], |(_, a)| *a);
    MAY_USE
        .iter()
        .map(|(m, _)| m.trim_end_matches(".rs"))
        .filter(|m| *m != module.trim_end_matches(".rs"))
        .filter(|m| !allowed.iter().any(|a| a.trim_end_matches(".rs") == *m))
        .collect()
}

#[test]
fn every_module_of_src_has_its_place_in_the_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let known: BTreeSet<&str> = MAY_USE.iter().map(|(m, _)| *m).collect();
    let roots = ["lib.rs", "main.rs", "prelude.rs", "error.rs"];
    for entry in std::fs::read_dir(&src).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().to_string();
        assert!(known.contains(name.as_str()) || roots.contains(&name.as_str()), "src/{name} has no layer in MAY_USE");
    }
    // What a layer may use includes what the layers it uses may: the table is closed.
    for (module, allowed) in MAY_USE {
        for used in *allowed {
            let theirs = MAY_USE.iter().find(|(m, _)| m == used).unwrap().1;
            for t in theirs {
                assert!(allowed.contains(t), "{module} may use {used}, which uses {t}: list it for {module} too");
            }
        }
    }
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn each_layer_uses_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut violations = Vec::new();
    for (module, _) in MAY_USE {
        let forbidden = forbidden(module);
        let mut files = Vec::new();
        let path = src.join(module);
        if path.is_file() {
            files.push(path);
        } else {
            rust_files(&path, &mut files);
        }
        assert!(!files.is_empty(), "src/{module} has no Rust files");
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            for (n, line) in text.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                for other in &forbidden {
                    if code.contains(&format!("crate::{other}::"))
                        || code.contains(&format!("crate::{other}}}"))
                        || code.contains(&format!("crate::{other};"))
                        || code.contains(&format!("crate::{other},"))
                    {
                        violations.push(format!("{}:{}: uses crate::{other}", file.display(), n + 1));
                    }
                }
            }
        }
    }
    assert!(violations.is_empty(), "layer violations:\n{}", violations.join("\n"));
}

/// The rows of the table of built-in kinds in `graph/README.md`: kind name -> row text.
fn readme_rows() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("graph/README.md")).unwrap();
    let table = text.split("## Built-in pass kinds").nth(1).expect("a table of built-in pass kinds");
    table
        .lines()
        .skip_while(|l| !l.starts_with("| kind"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let name = l.split('|').nth(1).unwrap().trim().trim_matches('`').to_string();
            (name, l.to_string())
        })
        .collect()
}

/// A row with the rows it refers to ("as `gbuffer`"), transitively.
fn row_with_references(rows: &BTreeMap<String, String>, kind: &str) -> String {
    let mut seen = BTreeSet::new();
    let mut pending = vec![kind.to_string()];
    let mut text = String::new();
    while let Some(k) = pending.pop() {
        if !seen.insert(k.clone()) {
            continue;
        }
        let Some(row) = rows.get(&k) else { continue };
        text.push_str(row);
        for (i, _) in row.match_indices("as `") {
            let rest = &row[i + 4..];
            pending.push(rest[..rest.find('`').unwrap_or(0)].to_string());
        }
    }
    text
}

#[test]
fn the_readme_table_of_kinds_matches_the_registry() {
    let kinds = cullgraph::passes::builtin_kinds();
    let rows = readme_rows();
    let registered: BTreeSet<String> = kinds.infos().map(|k| k.name.to_string()).collect();
    let documented: BTreeSet<String> = rows.keys().cloned().collect();
    assert_eq!(documented, registered, "graph/README.md's kinds and the registry's");
    let mut missing = Vec::new();
    for info in kinds.infos() {
        let text = row_with_references(&rows, info.name);
        let names = info.reads.iter().chain(&info.writes).map(|s| s.name).chain(info.settings.iter().map(|s| s.name));
        for name in names {
            if !text.contains(&format!("`{name}`")) {
                missing.push(format!("{}: `{name}`", info.name));
            }
        }
    }
    assert!(missing.is_empty(), "slots and settings missing from graph/README.md:\n{}", missing.join("\n"));
}
