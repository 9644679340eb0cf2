//! Graphs that build on others: `extends: "two_phase"` (a graph of the library the registry
//! holds, [`crate::graph::KindRegistry::register_graph`]) or `extends: "base.ron"` (a file,
//! relative to the one that names it) takes that graph whole, and the file then adds or
//! overrides params and resources by name, appends passes, edits the base's passes by name
//! (`Insert`, `Replace`, `Remove`, `Set`) and may give other outputs.
//!
//! Composition works on the parsed files, before validation: the result is one
//! [`GraphFile`] that validation checks like any other. Every part of it remembers the file
//! and place it came from ([`Sources`]), so that an error in a composed graph is reported at
//! the text at fault, in whichever file holds it.

use super::error::{GraphError, GraphErrors, Pos};
use super::kinds::KindRegistry;
use super::locate::{Locator, Seg};
use super::schema::{self, EditDecl, Entries, GraphFile, Literal, PassDecl, ResourceDecl};
use std::path::{Path, PathBuf};

/// How deep `extends` may chain.
pub const MAX_EXTENDS_DEPTH: usize = 8;

/// One file of a composed graph.
#[derive(Clone, Debug)]
pub struct Source {
    /// Its name in messages.
    pub name: String,
    /// Where its own relative paths (shaders, bases) resolve.
    pub dir: Option<PathBuf>,
    locator: Locator,
}

/// A path into a file (segments whose names are the schema's field names).
type Path_ = Vec<Seg<'static>>;

/// Where an entry of a map of the composed graph (`params`, `resources`, a pass's `reads`,
/// `writes`, `settings`) was written: the file, the map's path there and the entry's index.
#[derive(Clone, Debug)]
struct Origin {
    source: usize,
    map: Path_,
    index: usize,
}

/// A rule of [`Sources`]: paths of the composed graph that start with `from` are written at
/// `to`, with the rest of the path appended.
#[derive(Clone, Debug)]
struct Rule {
    from: Path_,
    source: usize,
    to: Path_,
}

/// The files of a composed graph and where each part of it was written.
#[derive(Clone, Debug)]
pub struct Sources {
    /// The files; the first is the one that was loaded.
    pub files: Vec<Source>,
    rules: Vec<Rule>,
}

impl Sources {
    /// The files' names, in [`Pos::file`] order.
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|f| f.name.clone()).collect()
    }

    /// The file and path in it where the part at `path` of the composed graph was written.
    fn locate(&self, path: &[Seg<'_>]) -> (usize, Vec<Seg<'static>>) {
        let best = self
            .rules
            .iter()
            .filter(|r| r.from.len() <= path.len() && r.from.iter().zip(path).all(|(a, b)| same(*a, *b)))
            .max_by_key(|r| r.from.len());
        match best {
            Some(rule) => {
                let mut to = rule.to.clone();
                to.extend(path[rule.from.len()..].iter().map(|s| owned(*s)));
                (rule.source, to)
            }
            None => (0, path.iter().map(|s| owned(*s)).collect()),
        }
    }

    /// The position of `path` of the composed graph.
    pub fn pos(&self, path: &[Seg<'_>]) -> Pos {
        let (source, path) = self.locate(path);
        self.files[source].locator.pos(&path).in_file(source)
    }

    /// The position of character `offset` of the string at `path`.
    pub fn pos_in_string(&self, path: &[Seg<'_>], offset: usize) -> Pos {
        let (source, path) = self.locate(path);
        self.files[source].locator.pos_in_string(&path, offset).in_file(source)
    }

    /// The identifier written at `path`.
    pub fn ident(&self, path: &[Seg<'_>]) -> Option<&str> {
        let (source, path) = self.locate(path);
        self.files[source].locator.ident(&path)
    }

    /// The folder that the relative paths written at `path` resolve against.
    pub fn dir_of(&self, path: &[Seg<'_>]) -> Option<&Path> {
        self.files[self.locate(path).0].dir.as_deref()
    }
}

fn same(a: Seg<'_>, b: Seg<'_>) -> bool {
    match (a, b) {
        (Seg::Field(x), Seg::Field(y)) | (Seg::FieldName(x), Seg::FieldName(y)) => x == y,
        (Seg::Index(x), Seg::Index(y)) | (Seg::Key(x), Seg::Key(y)) | (Seg::Value(x), Seg::Value(y)) => x == y,
        _ => false,
    }
}

/// The schema's field names, which paths use.
fn field(name: &str) -> &'static str {
    const FIELDS: &[&str] = &[
        "name",
        "extends",
        "params",
        "resources",
        "passes",
        "edits",
        "outputs",
        "reads",
        "writes",
        "settings",
        "shader",
        "dispatch",
        "kind",
        "before",
        "after",
        "pass",
        "with",
        "unbind",
        "size",
        "format",
        "mips",
        "samples",
        "history",
    ];
    FIELDS.iter().copied().find(|f| *f == name).unwrap_or("?")
}

fn owned(seg: Seg<'_>) -> Seg<'static> {
    match seg {
        Seg::Field(f) => Seg::Field(field(f)),
        Seg::FieldName(f) => Seg::FieldName(field(f)),
        Seg::Index(i) => Seg::Index(i),
        Seg::Key(i) => Seg::Key(i),
        Seg::Value(i) => Seg::Value(i),
    }
}

/// A map of the composed graph, each entry with where it was written.
struct Map<V> {
    entries: Vec<(String, V, Origin)>,
}

impl<V: Clone> Map<V> {
    fn of(entries: &Entries<V>, source: usize, map: Path_) -> Self {
        let entries = entries
            .0
            .iter()
            .enumerate()
            .map(|(index, (k, v))| (k.clone(), v.clone(), Origin { source, map: map.clone(), index }))
            .collect();
        Self { entries }
    }

    /// Entries of `other` replace the entries of the same name in place (the first of them:
    /// a duplicate in one file stays a duplicate, and an error) or are added at the end.
    fn overlay(&mut self, other: Map<V>) {
        for (k, v, origin) in other.entries {
            let mine = self.entries.iter().position(|(name, _, o)| name == &k && !from_same_map(o, &origin));
            match mine {
                Some(i) => self.entries[i] = (k, v, origin),
                None => self.entries.push((k, v, origin)),
            }
        }
    }

    fn entries(&self) -> Entries<V> {
        Entries(self.entries.iter().map(|(k, v, _)| (k.clone(), v.clone())).collect())
    }

    /// The rules that map this map's entries at `at` to where they were written.
    fn rules(&self, at: &[Seg<'static>], out: &mut Vec<Rule>) {
        for (i, (_, _, origin)) in self.entries.iter().enumerate() {
            for (from, to) in [(Seg::Key(i), Seg::Key(origin.index)), (Seg::Value(i), Seg::Value(origin.index))] {
                let mut path = at.to_vec();
                path.push(from);
                let mut target = origin.map.clone();
                target.push(to);
                out.push(Rule { from: path, source: origin.source, to: target });
            }
        }
    }
}

/// Whether two entries come from the same map of the same file.
fn from_same_map(a: &Origin, b: &Origin) -> bool {
    a.source == b.source && a.map.len() == b.map.len() && a.map.iter().zip(&b.map).all(|(x, y)| same(*x, *y))
}

/// A pass of the composed graph with where it and each of its entries were written.
struct ComposedPass {
    decl: PassDecl,
    source: usize,
    path: Path_,
    reads: Map<String>,
    writes: Map<String>,
    settings: Map<Literal>,
}

impl ComposedPass {
    fn new(decl: &PassDecl, source: usize, path: Path_) -> Self {
        let at = |f: &'static str| [path.clone(), vec![Seg::Field(f)]].concat();
        Self {
            reads: Map::of(&decl.reads, source, at("reads")),
            writes: Map::of(&decl.writes, source, at("writes")),
            settings: Map::of(&decl.settings, source, at("settings")),
            decl: decl.clone(),
            source,
            path,
        }
    }

    fn decl(&self) -> PassDecl {
        PassDecl {
            reads: self.reads.entries(),
            writes: self.writes.entries(),
            settings: self.settings.entries(),
            ..self.decl.clone()
        }
    }
}

/// A graph being composed.
struct Graph {
    name: String,
    params: Map<Literal>,
    resources: Map<ResourceDecl>,
    passes: Vec<ComposedPass>,
    outputs: Option<(Vec<String>, usize)>,
    name_source: usize,
}

/// Reads a graph's text and file name, and from them the base graphs it extends.
pub struct Composer<'a> {
    kinds: &'a KindRegistry,
    sources: Vec<Source>,
    errors: Vec<GraphError>,
}

impl<'a> Composer<'a> {
    /// A composer that finds named bases in `kinds`' library of graphs.
    pub fn new(kinds: &'a KindRegistry) -> Self {
        Self { kinds, sources: Vec::new(), errors: Vec::new() }
    }

    /// Parses `text` (file `file`, relative paths against `dir`) and the graphs it extends, and
    /// composes them into one file, with the errors of edits that could not apply (the rest of
    /// the graph can still be checked). A file that does not parse, or a base that cannot be
    /// read, is an error that ends it.
    pub fn compose(
        mut self,
        text: &str,
        file: &str,
        dir: Option<&Path>,
    ) -> Result<(GraphFile, Sources, Vec<GraphError>), GraphErrors> {
        let Some(graph) = self.load(text, file, dir, &mut Vec::new()) else {
            return Err(GraphErrors::sorted(self.errors));
        };
        let mut rules = Vec::new();
        graph.params.rules(&[Seg::Field("params")], &mut rules);
        graph.resources.rules(&[Seg::Field("resources")], &mut rules);
        for (i, p) in graph.passes.iter().enumerate() {
            let at = vec![Seg::Field("passes"), Seg::Index(i)];
            rules.push(Rule { from: at.clone(), source: p.source, to: p.path.clone() });
            for (f, map) in [("reads", &p.reads), ("writes", &p.writes)] {
                map.rules(&[at.clone(), vec![Seg::Field(f)]].concat(), &mut rules);
            }
            p.settings.rules(&[at.clone(), vec![Seg::Field("settings")]].concat(), &mut rules);
        }
        if let Some((_, source)) = &graph.outputs {
            rules.push(Rule { from: vec![Seg::Field("outputs")], source: *source, to: vec![Seg::Field("outputs")] });
        }
        rules.push(Rule { from: vec![Seg::Field("name")], source: graph.name_source, to: vec![Seg::Field("name")] });
        let composed = GraphFile {
            name: graph.name.clone(),
            extends: None,
            params: graph.params.entries(),
            resources: graph.resources.entries(),
            passes: graph.passes.iter().map(ComposedPass::decl).collect(),
            edits: Vec::new(),
            outputs: graph.outputs.map(|(o, _)| o),
        };
        Ok((composed, Sources { files: self.sources, rules }, self.errors))
    }

    /// Parses one file and composes it onto its base; `chain` holds the files that extend it
    /// (a cycle is an error).
    fn load(&mut self, text: &str, file: &str, dir: Option<&Path>, chain: &mut Vec<String>) -> Option<Graph> {
        let source = self.sources.len();
        self.sources.push(Source {
            name: file.to_string(),
            dir: dir.map(Path::to_path_buf),
            locator: Locator::new(text),
        });
        let parsed = match schema::parse(text) {
            Ok(g) => g,
            Err(e) => {
                let pos = Pos::at(e.span.start.line, e.span.start.col);
                self.errors.push(GraphError::new(file, pos, e.code.to_string()));
                return None;
            }
        };
        let locator = self.sources[source].locator.clone();
        let at = |path: &[Seg<'_>]| locator.pos(path);
        let mut graph = match &parsed.extends {
            None => Graph {
                name: String::new(),
                params: Map { entries: Vec::new() },
                resources: Map { entries: Vec::new() },
                passes: Vec::new(),
                outputs: None,
                name_source: source,
            },
            Some(base) => {
                let pos = at(&[Seg::Field("extends")]);
                chain.push(file.to_string());
                let base = self.base(base, dir, pos, source, chain);
                chain.pop();
                base?
            }
        };
        graph.name = parsed.name.clone();
        graph.name_source = source;
        graph.params.overlay(Map::of(&parsed.params, source, vec![Seg::Field("params")]));
        graph.resources.overlay(Map::of(&parsed.resources, source, vec![Seg::Field("resources")]));
        for (i, p) in parsed.passes.iter().enumerate() {
            graph.passes.push(ComposedPass::new(p, source, vec![Seg::Field("passes"), Seg::Index(i)]));
        }
        for (k, edit) in parsed.edits.iter().enumerate() {
            self.edit(&mut graph, edit, source, k);
        }
        if let Some(outputs) = &parsed.outputs {
            graph.outputs = Some((outputs.clone(), source));
        }
        Some(graph)
    }

    /// The graph `name` extends: one of the registry's library, or a file relative to `dir`.
    fn base(
        &mut self,
        name: &str,
        dir: Option<&Path>,
        pos: Pos,
        source: usize,
        chain: &mut Vec<String>,
    ) -> Option<Graph> {
        let file_name = &self.sources[source].name.clone();
        let mut fail = |message: String| {
            self.errors.push(GraphError::new(file_name, pos, message));
            None
        };
        if chain.len() >= MAX_EXTENDS_DEPTH {
            return fail(format!("extends \"{name}\": graphs extend each other more than {MAX_EXTENDS_DEPTH} deep"));
        }
        let library = name.strip_prefix("builtin:").unwrap_or(name);
        let (text, file, base_dir) = if let Some(g) = self.kinds.graph(library) {
            (g.text.to_string(), g.file.to_string(), None)
        } else if name.ends_with(".ron") {
            let path = dir.map_or_else(|| PathBuf::from(name), |d| d.join(name));
            match crate::files::read_limited_text(&path, crate::files::GRAPH_LIMIT, "graph file") {
                Ok(text) => (text, path.display().to_string(), path.parent().map(Path::to_path_buf)),
                Err(e) => return fail(format!("extends \"{name}\": {e}")),
            }
        } else {
            let names: Vec<&str> = self.kinds.graphs().map(|g| g.name).collect();
            return fail(format!(
                "extends \"{name}\": no such graph (graphs: {}; or a path ending in .ron)",
                names.join(", ")
            ));
        };
        if chain.contains(&file) {
            return fail(format!("extends \"{name}\": {file} extends itself through {}", chain.join(" -> ")));
        }
        self.load(&text, &file, base_dir.as_deref(), chain)
    }

    /// Applies edit `k` of file `source`.
    fn edit(&mut self, graph: &mut Graph, edit: &EditDecl, source: usize, k: usize) {
        let path = vec![Seg::Field("edits"), Seg::Index(k)];
        let at = |segs: &[Seg<'static>]| [path.clone(), segs.to_vec()].concat();
        let pos = |me: &Self, p: &[Seg<'static>]| me.sources[source].locator.pos(&at(p));
        let find = |graph: &Graph, name: &str| graph.passes.iter().position(|p| p.decl.name == name);
        let missing = |me: &mut Self, name: &str, field: &'static str, graph: &Graph| {
            let names: Vec<&str> = graph.passes.iter().map(|p| p.decl.name.as_str()).collect();
            let message = format!("no pass '{name}' to edit (passes: {})", names.join(", "));
            let pos = pos(me, &[Seg::Field(field)]);
            me.errors.push(GraphError::new(&me.sources[source].name, pos, message));
        };
        match edit {
            EditDecl::Insert { before, after, passes } => {
                let (anchor, field, offset) = match (before, after) {
                    (Some(b), None) => (b, "before", 0),
                    (None, Some(a)) => (a, "after", 1),
                    _ => {
                        let message = "Insert takes one of before: \"pass\" or after: \"pass\"".to_string();
                        let pos = pos(self, &[]);
                        self.errors.push(GraphError::new(&self.sources[source].name, pos, message));
                        return;
                    }
                };
                let Some(i) = find(graph, anchor) else { return missing(self, anchor, field, graph) };
                for (j, p) in passes.iter().enumerate() {
                    let pass = ComposedPass::new(p, source, at(&[Seg::Field("passes"), Seg::Index(j)]));
                    graph.passes.insert(i + offset + j, pass);
                }
            }
            EditDecl::Replace { pass, with } => {
                let Some(i) = find(graph, pass) else { return missing(self, pass, "pass", graph) };
                graph.passes[i] = ComposedPass::new(with, source, at(&[Seg::Field("with")]));
            }
            EditDecl::Remove { pass } => {
                let Some(i) = find(graph, pass) else { return missing(self, pass, "pass", graph) };
                graph.passes.remove(i);
            }
            EditDecl::Set { pass, reads, writes, settings, unbind } => {
                let Some(i) = find(graph, pass) else { return missing(self, pass, "pass", graph) };
                let p = &mut graph.passes[i];
                for (j, slot) in unbind.iter().enumerate() {
                    let before = p.reads.entries.len() + p.writes.entries.len();
                    p.reads.entries.retain(|(s, _, _)| s != slot);
                    p.writes.entries.retain(|(s, _, _)| s != slot);
                    if before == p.reads.entries.len() + p.writes.entries.len() {
                        let message = format!("pass '{pass}' binds no slot \"{slot}\" to unbind");
                        let pos = pos(self, &[Seg::Field("unbind"), Seg::Index(j)]);
                        self.errors.push(GraphError::new(&self.sources[source].name, pos, message));
                    }
                }
                let p = &mut graph.passes[i];
                p.reads.overlay(Map::of(reads, source, at(&[Seg::Field("reads")])));
                p.writes.overlay(Map::of(writes, source, at(&[Seg::Field("writes")])));
                p.settings.overlay(Map::of(settings, source, at(&[Seg::Field("settings")])));
            }
        }
    }
}

/// A graph of a registry's library: a name (`extends: "two_phase"`, `builtin:two_phase` on the
/// command line), the name its positions are reported under, and its RON text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LibraryGraph {
    /// Its name.
    pub name: &'static str,
    /// The file name errors name (`graph/two_phase.ron`).
    pub file: &'static str,
    /// The RON text.
    pub text: &'static str,
}
