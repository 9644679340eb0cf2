//! The seeds of each target and the inputs mutated from them: most by editing the parsed
//! structure ([`super::mutate_graph`], [`super::mutate_gltf`]), a share by editing bytes
//! ([`super::mutate_bytes`]), which is what reaches the parsers' own corners.

use super::ron_tree::{self, Document};
use super::{mutate_bytes, mutate_gltf, mutate_graph, targets};
use cullgraph::files;
use rand::rngs::SmallRng;
use rand::Rng;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The share of inputs mutated byte by byte.
const BYTE_SHARE: f64 = 0.2;
/// The share of graph inputs mutated from a seed that passes the check (most seeds are the
/// test suite's bad graphs: good as donors of odd parts, but their mutants rarely get further
/// than their own mistake).
const GOOD_SEED_SHARE: f64 = 0.75;

/// How an input was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Mutator {
    /// Edits of the parsed tree, printed back.
    Structure,
    /// Edits of the bytes.
    Bytes,
}

impl Mutator {
    /// Both, in report order.
    pub const ALL: [Mutator; 2] = [Mutator::Structure, Mutator::Bytes];

    /// The name in the worker's lines and the report.
    pub fn name(self) -> &'static str {
        match self {
            Mutator::Structure => "structure",
            Mutator::Bytes => "bytes",
        }
    }

    /// The mutator called `name`.
    pub fn from_name(name: &str) -> Option<Mutator> {
        Mutator::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// One input.
pub struct Input {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// The folder of the seed's file (where a graph's shaders resolve).
    pub dir: Option<PathBuf>,
    /// How it was made.
    pub mutator: Mutator,
    /// Whether it is still well-formed RON or JSON (by the fuzzer's own parsers).
    pub well_formed: bool,
}

/// A graph seed.
struct GraphSeed {
    text: String,
    tree: Option<Document>,
    dir: Option<PathBuf>,
    passes: bool,
}

/// The seeds of the graph target: the shipped graphs and the `.ron` files of the seed folders.
pub struct GraphCorpus {
    seeds: Vec<GraphSeed>,
    pools: mutate_graph::Pools,
}

/// The `.EXT` files directly in `dir`, sorted; a folder that cannot be listed is an error
/// naming `--seeds`.
fn seed_files(dir: &Path, ext: &str) -> cullgraph::Result<Vec<PathBuf>> {
    super::super::paths::input_dir("--seeds", dir)?;
    let entries =
        std::fs::read_dir(dir).map_err(|e| cullgraph::Error::Invalid(format!("--seeds {}: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> =
        entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == ext)).collect();
    files.sort();
    Ok(files)
}

impl GraphCorpus {
    /// The shipped graphs and those in `dirs`, each marked by `passes` (whether it passes the
    /// check). A file that cannot be read as a graph (a FIFO named `x.ron`, a huge one) is
    /// skipped with a note, not waited on.
    pub fn new(dirs: &[PathBuf], passes: &dyn Fn(&str, Option<&Path>) -> bool) -> cullgraph::Result<Self> {
        let seed = |text: String, dir: Option<PathBuf>| GraphSeed {
            tree: ron_tree::parse(&text),
            passes: passes(&text, dir.as_deref()),
            text,
            dir,
        };
        let mut seeds: Vec<GraphSeed> =
            cullgraph::passes::SHIPPED_GRAPHS.iter().map(|g| seed(g.text.to_string(), None)).collect();
        for dir in dirs {
            for file in seed_files(dir, "ron")? {
                match files::read_limited_text(&file, files::GRAPH_LIMIT, "graph file") {
                    Ok(text) => seeds.push(seed(text, Some(dir.clone()))),
                    Err(e) => eprintln!("note: seed {} skipped: {e}", file.display()),
                }
            }
        }
        let pools = mutate_graph::Pools::of(seeds.iter().filter_map(|s| s.tree.as_ref()));
        Ok(Self { seeds, pools })
    }

    /// A mutated graph.
    pub fn input(&self, rng: &mut SmallRng) -> Input {
        let good: Vec<&GraphSeed> = self.seeds.iter().filter(|s| s.passes).collect();
        let seed = match good.is_empty() || !rng.random_bool(GOOD_SEED_SHARE) {
            true => &self.seeds[rng.random_range(0..self.seeds.len())],
            false => good[rng.random_range(0..good.len())],
        };
        let (text, mutator) = match &seed.tree {
            Some(tree) if !rng.random_bool(BYTE_SHARE) => {
                (mutate_graph::graph(rng, tree, &self.pools), Mutator::Structure)
            }
            _ => {
                let others: Vec<&str> = self.seeds.iter().map(|s| s.text.as_str()).collect();
                (mutate_bytes::graph_text(rng, &seed.text, &others), Mutator::Bytes)
            }
        };
        let well_formed = ron_tree::parse(&text).is_some();
        let mut text = text;
        if let Some(dir) = &seed.dir {
            text.push_str(&format!("\n{}{}", super::SEED_DIR_MARK, dir.display()));
        }
        Input { bytes: text.into_bytes(), dir: seed.dir.clone(), mutator, well_formed }
    }
}

/// The seeds of the glTF target: the built-in document and the `.glb` files of the seed
/// folders, each as its JSON and binary chunk.
pub struct GltfCorpus {
    seeds: Vec<(Value, Vec<u8>)>,
    pools: mutate_gltf::Pools,
}

impl GltfCorpus {
    /// The built-in document and the `.glb` files in `dirs`.
    pub fn new(dirs: &[PathBuf]) -> cullgraph::Result<Self> {
        let mut seeds = vec![targets::gltf_seed()];
        for dir in dirs {
            for file in seed_files(dir, "glb")? {
                let parsed = files::read_limited(&file, files::SCENE_LIMIT, "scene file").and_then(|bytes| {
                    let glb = gltf::Glb::from_slice(&bytes).map_err(|e| e.to_string())?;
                    let doc = serde_json::from_slice(&glb.json).map_err(|e| e.to_string())?;
                    Ok((doc, glb.bin.map(|b| b.into_owned()).unwrap_or_default()))
                });
                match parsed {
                    Ok(seed) => seeds.push(seed),
                    Err(e) => eprintln!("note: seed {} skipped: {e}", file.display()),
                }
            }
        }
        let pools = mutate_gltf::Pools::of(seeds.iter().map(|(doc, _)| doc));
        Ok(Self { seeds, pools })
    }

    /// A mutated GLB file.
    pub fn input(&self, rng: &mut SmallRng) -> Input {
        let (doc, bin) = &self.seeds[rng.random_range(0..self.seeds.len())];
        let mut bin = bin.clone();
        if !rng.random_bool(BYTE_SHARE) {
            let mut doc = doc.clone();
            mutate_gltf::document(rng, &mut doc, &self.pools);
            if rng.random_range(0..8) == 0 {
                mutate_bytes::binary(rng, &mut bin);
            }
            let json = serde_json::to_vec(&doc).unwrap_or_default();
            return Input {
                bytes: targets::glb(&json, &bin),
                dir: None,
                mutator: Mutator::Structure,
                well_formed: true,
            };
        }
        let mut json = serde_json::to_vec(doc).unwrap_or_default();
        let file = match rng.random_range(0..3) {
            0 => {
                mutate_bytes::binary(rng, &mut json);
                targets::glb(&json, &bin)
            }
            1 => {
                mutate_bytes::binary(rng, &mut bin);
                targets::glb(&json, &bin)
            }
            _ => {
                let mut file = targets::glb(&json, &bin);
                mutate_bytes::binary(rng, &mut file); // the container itself
                file
            }
        };
        let well_formed =
            gltf::Glb::from_slice(&file).ok().is_some_and(|glb| serde_json::from_slice::<Value>(&glb.json).is_ok());
        Input { bytes: file, dir: None, mutator: Mutator::Bytes, well_formed }
    }
}
