//! The graph a renderer runs, and the ones reloads replaced: a replaced runtime keeps its
//! resources, timestamps and counters until its last frame can no longer be executing, and the
//! last reload can be reverted while the new graph has recorded nothing.

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::graph::{FrameInputs, GraphRuntime, FRAMES_IN_FLIGHT};
use crate::render::GraphSpec;

/// The running graph and the replaced ones.
pub(super) struct Graphs {
    /// What the running graph was built from.
    pub spec: GraphSpec,
    /// The running graph.
    pub runtime: GraphRuntime,
    /// Renderer frame at which `runtime` recorded its first frame.
    start: u64,
    /// Runtimes replaced by a reload: (first frame, first frame of the next runtime, runtime).
    retired: Vec<(u64, u64, GraphRuntime)>,
    /// The spec the last reload replaced (for [`Graphs::revert`]).
    replaced_spec: Option<GraphSpec>,
}

impl Graphs {
    /// `runtime`, built from `spec`, recording from the first frame on.
    pub fn new(spec: &GraphSpec, runtime: GraphRuntime) -> Self {
        Self { spec: spec.clone(), runtime, start: 0, retired: Vec::new(), replaced_spec: None }
    }

    /// Makes `runtime` the one that records from frame `frame` on, with what the current one was
    /// asked for (step timing, captured draw lists); the current one is kept until its frames
    /// can no longer be executing.
    pub fn install(&mut self, mut runtime: GraphRuntime, frame: u64) -> Result<()> {
        runtime.set_step_timing(self.runtime.step_timing());
        runtime.capture_draw_lists(self.runtime.captures_draw_lists())?;
        let old = std::mem::replace(&mut self.runtime, runtime);
        self.retired.push((self.start, frame, old));
        self.start = frame;
        Ok(())
    }

    /// Installs `runtime`, built from `spec`, as a reload that [`Graphs::revert`] can undo.
    pub fn reload(&mut self, spec: &GraphSpec, runtime: GraphRuntime, frame: u64) -> Result<()> {
        self.install(runtime, frame)?;
        self.replaced_spec = Some(std::mem::replace(&mut self.spec, spec.clone()));
        Ok(())
    }

    /// Puts back the graph the last reload replaced, when the new one has recorded nothing
    /// (`frame` is the next frame to record).
    pub fn revert(&mut self, frame: u64) -> Result<()> {
        let recorded_none = self.start == frame;
        match (self.retired.pop(), self.replaced_spec.take()) {
            (Some((start, end, old)), Some(spec)) if recorded_none && end == frame => {
                self.runtime = old;
                self.start = start;
                self.spec = spec;
                Ok(())
            }
            (retired, spec) => {
                self.retired.extend(retired);
                self.replaced_spec = spec;
                Err(Error::Invalid(
                    "no reload to revert: nothing was reloaded, or the new graph has recorded frames".into(),
                ))
            }
        }
    }

    /// The runtime that recorded renderer frame `frame` and the frame's index within it: the
    /// current one, or one a reload retired (it keeps its frames' timestamps and counters until
    /// they can no longer be executing). `None` once that runtime is gone.
    pub fn runtime_of(&self, frame: u64) -> Option<(&GraphRuntime, u64)> {
        if frame >= self.start {
            return Some((&self.runtime, frame - self.start));
        }
        self.retired
            .iter()
            .find(|(start, end, _)| (*start..*end).contains(&frame))
            .map(|(start, _, old)| (old, frame - start))
    }

    /// Drops the replaced runtimes whose frames have executed, once frame `frame` is recorded.
    pub fn recorded(&mut self, frame: u64) {
        self.retired.retain(|(_, end, _)| frame < end + FRAMES_IN_FLIGHT as u64);
    }
}

/// Loads, validates and compiles `spec` for `inputs`, and instantiates it.
pub(super) fn build_runtime(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    inputs: &FrameInputs,
    spec: &GraphSpec,
) -> Result<GraphRuntime> {
    profiling::scope!("cullgraph::build_graph");
    let plan = spec.compile_for(ctx, shaders, inputs)?;
    GraphRuntime::new(ctx, shaders, plan, spec.dir.as_deref())
}
