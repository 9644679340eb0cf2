//! Which render graph a renderer runs: RON text with its file name (for error positions), the
//! folder its user shaders resolve against, and parameter overrides.

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::graph::{compile, load_in, CompiledGraph, DeviceEnv, KindRegistry};
use crate::passes::builtin_kinds;
use crate::passes::shared::frame_inputs;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The default graph shipped with the crate (`graph/default.ron`), embedded at build time.
pub const DEFAULT_GRAPH: &str = include_str!("../../graph/default.ron");

/// The graphs shipped in `graph/`, embedded so that a binary carried elsewhere has them:
/// `builtin:NAME` on the command line.
pub const BUILTIN_GRAPHS: &[(&str, &str)] = &[
    ("default", DEFAULT_GRAPH),
    ("no_cull", include_str!("../../graph/no_cull.ron")),
    ("frustum", include_str!("../../graph/frustum.ron")),
    ("two_phase", include_str!("../../graph/two_phase.ron")),
    ("one_phase", include_str!("../../graph/one_phase.ron")),
    ("occluder_prepass", include_str!("../../graph/occluder_prepass.ron")),
    ("overlay", include_str!("../../graph/overlay.ron")),
    ("msaa_compressed", include_str!("../../graph/msaa_compressed.ron")),
    ("msaa_compressed_edges", include_str!("../../graph/msaa_compressed_edges.ron")),
    ("msaa_compressed_claim", include_str!("../../graph/msaa_compressed_claim.ron")),
    ("msaa_per_sample", include_str!("../../graph/msaa_per_sample.ron")),
    ("msaa_zprepass", include_str!("../../graph/msaa_zprepass.ron")),
    ("visibility_buffer", include_str!("../../graph/visibility_buffer.ron")),
    ("fxaa", include_str!("../../graph/fxaa.ron")),
];

/// A render graph to load.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GraphSpec {
    /// RON source.
    pub text: String,
    /// Name used in `file:line:col` messages.
    pub file: String,
    /// Folder that relative shader paths of compute passes resolve against.
    pub dir: Option<PathBuf>,
    /// `name=value` parameter overrides (CLI `--param`, API).
    pub overrides: Vec<(String, String)>,
    /// The pass kinds its passes may use (the built-in ones unless an engine registered more).
    pub kinds: KindRegistry,
}

impl GraphSpec {
    /// The embedded default graph.
    pub fn default_graph() -> Self {
        Self {
            text: DEFAULT_GRAPH.into(),
            file: "graph/default.ron".into(),
            dir: None,
            overrides: Vec::new(),
            kinds: builtin_kinds(),
        }
    }

    /// A graph shipped in `graph/` by name (`default`, `no_cull`, `frustum`, ...).
    pub fn builtin(name: &str) -> Result<Self> {
        let (_, text) = BUILTIN_GRAPHS.iter().find(|(n, _)| *n == name).ok_or_else(|| {
            let names: Vec<&str> = BUILTIN_GRAPHS.iter().map(|(n, _)| *n).collect();
            Error::Invalid(format!("unknown built-in graph '{name}' (built-in graphs: {})", names.join(", ")))
        })?;
        Ok(Self {
            text: text.to_string(),
            file: format!("graph/{name}.ron"),
            dir: None,
            overrides: Vec::new(),
            kinds: builtin_kinds(),
        })
    }

    /// `builtin:NAME` or a path.
    pub fn from_arg(arg: &str) -> Result<Self> {
        match arg.strip_prefix("builtin:") {
            Some(name) => Self::builtin(name),
            None => Self::from_file(Path::new(arg)),
        }
    }

    /// A graph file on disk.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = crate::files::read_limited_text(path, crate::files::GRAPH_LIMIT, "graph file")
            .map_err(|e| Error::Io { path: path.display().to_string(), source: std::io::Error::other(e) })?;
        Ok(Self {
            text,
            file: path.display().to_string(),
            dir: path.parent().map(Path::to_path_buf),
            overrides: Vec::new(),
            kinds: builtin_kinds(),
        })
    }

    /// The same graph with `overrides` added (later ones win).
    pub fn with_overrides(mut self, overrides: impl IntoIterator<Item = (String, String)>) -> Self {
        self.overrides.extend(overrides);
        self
    }

    /// The same graph, loaded with `kinds` (for example the built-in kinds and an engine's own).
    pub fn with_kinds(mut self, kinds: KindRegistry) -> Self {
        self.kinds = kinds;
        self
    }
}

impl GraphSpec {
    /// Loads, validates (against `ctx`'s device) and compiles the graph for `scene` at
    /// `width` x `height`.
    pub fn compile(
        &self,
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        scene: &Scene,
        width: u32,
        height: u32,
    ) -> Result<CompiledGraph> {
        self.compile_for(ctx, shaders, &frame_inputs(scene, width, height))
    }

    /// Loads, validates (against `ctx`'s device) and compiles the graph for `inputs`.
    pub fn compile_for(
        &self,
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        inputs: &crate::graph::FrameInputs,
    ) -> Result<CompiledGraph> {
        let env = DeviceEnv::new(ctx, shaders);
        let graph = load_in(&self.text, &self.file, self.dir.as_deref(), &self.overrides, &env, &self.kinds)?;
        Ok(compile(&graph, inputs)?)
    }
}
