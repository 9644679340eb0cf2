//! The graph a renderer runs, and the ones reloads replaced: a replaced runtime keeps its
//! resources, timestamps and counters until its last frame can no longer be executing, and the
//! last reload can be reverted while the new graph has recorded nothing.

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::graph::{FrameInputs, GraphRuntime, FRAMES_IN_FLIGHT};
use crate::render::GraphSpec;
use std::collections::VecDeque;

/// How many of a runtime's recent frames are remembered: enough to find any frame whose
/// timestamps and counters it still holds.
const REMEMBERED_FRAMES: usize = 2 * FRAMES_IN_FLIGHT;

/// A runtime's recent frames: (renderer frame, the runtime's own number of it). A view need
/// not record every frame of its renderer, so the two differ by more than an offset.
type FrameMap = VecDeque<(u64, u64)>;

/// A runtime a reload or resize replaced, kept until its frames can no longer be executing.
struct Retired {
    frames: FrameMap,
    compiled: FrameInputs,
    /// The renderer frame from which its successor records.
    end: u64,
    runtime: GraphRuntime,
}

/// The running graph and the replaced ones.
pub(super) struct Graphs {
    /// What the running graph was built from.
    pub spec: GraphSpec,
    /// The running graph.
    pub runtime: GraphRuntime,
    /// What the running graph is compiled for (the output size, and the scene's quantities
    /// with the room a world keeps to grow).
    pub compiled: FrameInputs,
    /// The running graph's recent frames.
    frames: FrameMap,
    /// Runtimes replaced by a reload or a resize.
    retired: Vec<Retired>,
    /// The spec the last reload replaced (for [`Graphs::revert`]).
    replaced_spec: Option<GraphSpec>,
}

impl Graphs {
    /// `runtime`, built from `spec`, recording from the first frame on.
    pub fn new(spec: &GraphSpec, runtime: GraphRuntime, compiled: FrameInputs) -> Self {
        Self {
            spec: spec.clone(),
            runtime,
            compiled,
            frames: FrameMap::new(),
            retired: Vec::new(),
            replaced_spec: None,
        }
    }

    /// Makes `runtime` the one that records from renderer frame `frame` on, with what the
    /// current one was asked for (step timing, captured draw lists); the current one is kept
    /// until its frames can no longer be executing.
    pub fn install(&mut self, mut runtime: GraphRuntime, compiled: FrameInputs, frame: u64) -> Result<()> {
        runtime.set_step_timing(self.runtime.step_timing());
        runtime.set_replay(self.runtime.replays());
        runtime.capture_draw_lists(self.runtime.captures_draw_lists())?;
        let old = std::mem::replace(&mut self.runtime, runtime);
        let frames = std::mem::take(&mut self.frames);
        let old_compiled = std::mem::replace(&mut self.compiled, compiled);
        self.retired.push(Retired { frames, compiled: old_compiled, end: frame, runtime: old });
        self.replaced_spec = None;
        Ok(())
    }

    /// Installs `runtime`, built from `spec`, as a reload that [`Graphs::revert`] can undo.
    pub fn reload(&mut self, spec: &GraphSpec, runtime: GraphRuntime, compiled: FrameInputs, frame: u64) -> Result<()> {
        self.install(runtime, compiled, frame)?;
        self.replaced_spec = Some(std::mem::replace(&mut self.spec, spec.clone()));
        Ok(())
    }

    /// Puts back the graph the last reload replaced, when the new one has recorded nothing.
    pub fn revert(&mut self) -> Result<()> {
        match (self.frames.is_empty(), self.replaced_spec.take()) {
            (true, Some(spec)) if !self.retired.is_empty() => {
                let old = self.retired.pop().expect("checked: not empty");
                self.runtime = old.runtime;
                self.frames = old.frames;
                self.compiled = old.compiled;
                self.spec = spec;
                Ok(())
            }
            (_, spec) => {
                self.replaced_spec = spec;
                Err(Error::Invalid(
                    "no reload to revert: nothing was reloaded, or the new graph has recorded frames".into(),
                ))
            }
        }
    }

    /// Notes that the running graph recorded renderer frame `frame` as its own frame `local`,
    /// and drops the replaced runtimes whose frames have executed by now.
    pub fn recorded(&mut self, frame: u64, local: u64) {
        self.frames.push_back((frame, local));
        while self.frames.len() > REMEMBERED_FRAMES {
            self.frames.pop_front();
        }
        self.retired.retain(|r| frame < r.end + FRAMES_IN_FLIGHT as u64);
        // Only a graph that has recorded nothing can be reverted.
        self.replaced_spec = None;
    }

    /// The runtime that recorded renderer frame `frame` and the frame's number within it: the
    /// current one, or one a reload or resize retired (it keeps its frames' timestamps and
    /// counters until they can no longer be executing). `None` once that runtime is gone, or
    /// when the graph did not record that frame.
    pub fn runtime_of(&self, frame: u64) -> Option<(&GraphRuntime, u64)> {
        let local = |frames: &FrameMap| frames.iter().find(|(f, _)| *f == frame).map(|(_, l)| *l);
        if let Some(l) = local(&self.frames) {
            return Some((&self.runtime, l));
        }
        self.retired.iter().find_map(|r| local(&r.frames).map(|l| (&r.runtime, l)))
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
