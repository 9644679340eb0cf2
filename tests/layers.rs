//! The library's layers, and the documentation of its pass kinds, checked against the code.
//!
//! Layers, each using only those below it: `gpu` <- `graph` <- (`cull`, `scene`, `stats`: plain
//! data and math) <- `passes` <- `render` <- (`oracle`: verification) <- (`cli`, `bench`). The
//! graph knows no pass kind; every kind, built-in or an engine's, reaches it through the
//! registry.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The modules each module must not use.
const FORBIDDEN: &[(&str, &[&str])] = &[
    ("files.rs", &["gpu", "graph", "cull", "scene", "stats", "passes", "render", "oracle", "bench", "cli"]),
    ("gpu", &["graph", "cull", "scene", "stats", "passes", "render", "oracle", "bench", "cli"]),
    ("graph", &["cull", "scene", "stats", "passes", "render", "oracle", "bench", "cli"]),
    ("cull", &["graph", "stats", "passes", "render", "oracle", "bench", "cli"]),
    ("scene", &["graph", "cull", "stats", "passes", "render", "oracle", "bench", "cli"]),
    ("stats", &["cull", "scene", "passes", "render", "oracle", "bench", "cli"]),
    ("passes", &["render", "oracle", "bench", "cli"]),
    ("render", &["bench", "cli"]),
    ("oracle", &["bench", "cli"]),
];

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
    for (module, forbidden) in FORBIDDEN {
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
                for other in *forbidden {
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
