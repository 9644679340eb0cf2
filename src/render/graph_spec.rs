//! Which render graph a renderer runs: RON text with its file name (for error positions), the
//! folder its user shaders resolve against, and parameter overrides.

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::graph::{
    compile, load_in, CompiledGraph, DeviceEnv, GraphError, GraphErrors, KindRegistry, ResolvedKind, SettingOverride,
};
use crate::passes::builtin_kinds;
use crate::passes::shared::frame_inputs;
use crate::scene::Scene;
use ash::vk;
use std::path::{Path, PathBuf};

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
    /// Settings of passes to change when compiling (after the params): what a kind's
    /// adaptation asked for ([`crate::graph::Adaptation`]).
    pub settings: Vec<SettingOverride>,
}

impl GraphSpec {
    /// The embedded default graph.
    pub fn default_graph() -> Self {
        Self::builtin("default").expect("the built-in kinds' library holds the default graph")
    }

    /// A graph shipped in `graph/` by name (`default`, `no_cull`, `frustum`, ...).
    pub fn builtin(name: &str) -> Result<Self> {
        Self::from_library(builtin_kinds(), name)
    }

    /// The graph called `name` of `kinds`' library, loaded with `kinds`.
    pub fn from_library(kinds: KindRegistry, name: &str) -> Result<Self> {
        let graph = *kinds.graph(name).ok_or_else(|| {
            let names: Vec<&str> = kinds.graphs().map(|g| g.name).collect();
            Error::Invalid(format!("unknown built-in graph '{name}' (built-in graphs: {})", names.join(", ")))
        })?;
        Ok(Self {
            text: graph.text.to_string(),
            file: graph.file.to_string(),
            dir: None,
            overrides: Vec::new(),
            kinds,
            settings: Vec::new(),
        })
    }

    /// `builtin:NAME` or a path.
    pub fn from_arg(arg: &str) -> Result<Self> {
        match arg.strip_prefix("builtin:") {
            Some(name) => Self::builtin(name),
            None => Self::from_file(Path::new(arg)),
        }
    }

    /// A graph from RON text held by the host (a variant written at run time, say), named
    /// `name` in its errors (`name:line:col`); `extends` reaches the shipped graphs, and files
    /// relative to the working directory.
    pub fn from_text(name: &str, text: impl Into<String>) -> Self {
        Self {
            text: text.into(),
            file: name.to_string(),
            dir: None,
            overrides: Vec::new(),
            kinds: builtin_kinds(),
            settings: Vec::new(),
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
            settings: Vec::new(),
        })
    }

    /// The same graph with `overrides` added (later ones win).
    pub fn with_overrides(mut self, overrides: impl IntoIterator<Item = (String, String)>) -> Self {
        self.overrides.extend(overrides);
        self
    }

    /// The same graph with `settings` changed (later ones win).
    pub fn with_settings(mut self, settings: impl IntoIterator<Item = SettingOverride>) -> Self {
        self.settings.extend(settings);
        self
    }

    /// The same graph, loaded with `kinds` (for example the built-in kinds and an engine's own).
    pub fn with_kinds(mut self, kinds: KindRegistry) -> Self {
        self.kinds = kinds;
        self
    }
}

/// The rule for a graph whose first output is read back or shown: that output is an image of
/// the output size (`width` x `height`) with one sample a pixel. An error at the output's
/// declaration otherwise. [`Renderer::render_to_rgba8`](crate::render::Renderer::render_to_rgba8)
/// applies it, and so does `graph check --size`, for the frame `cullgraph render` reads back.
pub fn shown_image_error(plan: &CompiledGraph, width: u32, height: u32) -> std::result::Result<(), GraphErrors> {
    let Some(&first) = plan.outputs.first() else { return Ok(()) };
    let r = &plan.resources[first];
    // At the resource's description when it has the wrong size, at the outputs otherwise.
    let mut at = r.pos;
    let message = match r.kind {
        ResolvedKind::Image { extent, samples, .. }
            if (extent.width, extent.height) == (width, height) && samples == vk::SampleCountFlags::TYPE_1 =>
        {
            return Ok(())
        }
        ResolvedKind::Image { extent, samples, .. } => format!(
            "the first output '{}' is the image the host shows: it must be the output size, {width}x{height}, with \
             one sample a pixel; it is {}x{} with {}",
            r.name,
            extent.width,
            extent.height,
            samples.as_raw()
        ),
        ResolvedKind::Buffer { .. } => {
            at = plan.output_pos.first().copied().unwrap_or(r.pos);
            format!("the first output '{}' is a buffer; it must be the image the host shows", r.name)
        }
    };
    Err(GraphErrors(vec![GraphError::new(plan.file_at(at), at, message)]))
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
        self.compile_for(ctx, shaders, &frame_inputs(&self.kinds, scene, width, height)?)
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
        let mut inputs = inputs.clone();
        inputs.settings.extend(self.settings.iter().cloned());
        let plan = compile(&graph, &inputs)?;
        Ok(plan)
    }
}
