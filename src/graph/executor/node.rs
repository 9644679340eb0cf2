//! The interface between the executor and the passes: a pass records its commands given the
//! resources bound to its slots and the frame's shared inputs.

use super::resources::{Physical, RuntimeResources};
use crate::gpu::{Access, Buffer, GpuContext, GpuTimer, Image};
use crate::graph::plan::{Binding, PlannedPass};
use ash::vk;
use std::any::Any;
use std::cell::{Cell, RefCell};

/// What every pass of a frame may use besides its slots.
pub struct FrameData<'a> {
    /// Frame number.
    pub frame: u64,
    /// Output size.
    pub extent: vk::Extent2D,
    /// Whatever the host of the graph shares with its passes (the scene on the GPU and this
    /// frame's constants, for cullgraph's renderer). The graph never looks inside: each pass
    /// kind downcasts it to the type it was written for.
    pub shared: &'a dyn Any,
    /// The host's word that `shared`, and what it imports, are as they were in an earlier frame
    /// with the same key: the same buffers, images and counts, so that every pass would record
    /// the same commands (what the buffers hold may differ). Frames with equal keys may replay
    /// one recording (`graph::executor::replay`). `None`: never replay.
    pub replay_key: Option<u64>,
    /// The host's word that the images it imports under equal keys are the same images, not
    /// new ones that Vulkan gave old handles: their wrappers (and the views made of their parts)
    /// are then kept from frame to frame, which a replayed frame needs (a host that gives other
    /// images under one key stays correct, but its frames do not replay). `None`: a fresh
    /// wrapper every frame, and no replay of a frame that imports an image.
    pub import_key: Option<u64>,
}

/// The resources bound to one pass's slots in this frame.
pub struct SlotBindings<'a> {
    pub(super) pass: &'a PlannedPass,
    pub(super) resources: &'a RuntimeResources,
    pub(super) frame: u64,
}

impl<'a> SlotBindings<'a> {
    /// The name of the pass in the graph, for messages.
    pub fn pass_name(&self) -> &'a str {
        &self.pass.name
    }

    /// The binding of `slot`, if the graph bound it.
    pub fn binding(&self, slot: &str) -> Option<&'a Binding> {
        self.pass.bindings.iter().find(|b| b.slot == slot)
    }

    /// The image bound to `slot`.
    pub fn image(&self, slot: &str) -> Option<&'a Image> {
        let b = self.binding(slot)?;
        match self.resources.get(self.resources.index(b.resource, b.version, self.frame)?) {
            Physical::Image(i) => Some(i),
            _ => None,
        }
    }

    /// The buffer bound to `slot`.
    pub fn buffer(&self, slot: &str) -> Option<&'a Buffer> {
        let b = self.binding(slot)?;
        match self.resources.get(self.resources.index(b.resource, b.version, self.frame)?) {
            Physical::Buffer(buf) => Some(buf),
            _ => None,
        }
    }

    /// The image bound to a required slot (validation guarantees it is there).
    pub fn required_image(&self, slot: &str) -> crate::Result<&'a Image> {
        self.image(slot).ok_or_else(|| missing(self.pass, slot))
    }

    /// The buffer bound to a required slot (validation guarantees it is there).
    pub fn required_buffer(&self, slot: &str) -> crate::Result<&'a Buffer> {
        self.buffer(slot).ok_or_else(|| missing(self.pass, slot))
    }

    /// Every binding of the pass.
    pub fn all(&self) -> &'a [Binding] {
        &self.pass.bindings
    }

    /// The physical object of a binding.
    pub fn physical(&self, binding: &Binding) -> Option<&'a Physical> {
        self.resources.index(binding.resource, binding.version, self.frame).map(|i| self.resources.get(i))
    }
}

fn missing(pass: &PlannedPass, slot: &str) -> crate::Error {
    crate::Error::Invalid(format!("pass '{}' has nothing bound to slot '{slot}'", pass.name))
}

/// What a pass sees while recording.
pub struct PassContext<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The command buffer being recorded.
    pub cmd: vk::CommandBuffer,
    /// Scene and per-frame data.
    pub frame: &'a FrameData<'a>,
    /// The resources bound to the pass's slots.
    pub slots: SlotBindings<'a>,
    /// Timestamps between the pass's steps, when the runtime was asked for them.
    pub steps: StepTimer<'a>,
    /// The GPU times of the newest frame that has completed, for kinds that read them
    /// ([`crate::graph::PassKind::reads_timings`]); `None` until one has.
    pub timings: Option<&'a CompletedTimings>,
}

/// The GPU times of a completed frame of the runtime.
#[derive(Clone, Debug, PartialEq)]
pub struct CompletedTimings {
    /// The runtime's number of that frame.
    pub frame: u64,
    /// Each pass's scope and the whole frame's (`frame`).
    pub passes: Vec<crate::gpu::PassTiming>,
}

impl PassContext<'_> {
    /// Marks the start of step `name` of a pass with several dispatches (see [`StepTimer`]).
    pub fn step(&self, name: &str) {
        self.steps.step(self.cmd, name);
    }
}

/// Times the steps of one pass separately ([`crate::graph::executor::GraphRuntime::set_step_timing`]):
/// each [`StepTimer::step`] closes the previous step's scope and opens `pass/step`; the
/// executor closes the last one. Does nothing unless step timing is on.
pub struct StepTimer<'a> {
    timer: Option<&'a RefCell<GpuTimer>>,
    pass: &'a str,
    open: Cell<bool>,
}

impl<'a> StepTimer<'a> {
    /// A timer writing into `timer` (`None`: step timing off) for the pass named `pass`.
    pub(super) fn new(timer: Option<&'a RefCell<GpuTimer>>, pass: &'a str) -> Self {
        Self { timer, pass, open: Cell::new(false) }
    }

    /// Ends the open step, if any, and begins `name`.
    pub fn step(&self, cmd: vk::CommandBuffer, name: &str) {
        let Some(timer) = self.timer else { return };
        let mut timer = timer.borrow_mut();
        if self.open.replace(true) {
            timer.end(cmd);
        }
        timer.begin(cmd, &format!("{}/{name}", self.pass));
    }

    /// Ends the open step, if any.
    pub(super) fn finish(&self, cmd: vk::CommandBuffer) {
        if let (Some(timer), true) = (self.timer, self.open.replace(false)) {
            timer.borrow_mut().end(cmd);
        }
    }
}

/// A pass instance of a compiled graph (pipelines created, ready to record).
pub trait PassNode: Send {
    /// Records the pass's commands. Barriers around it are the executor's job.
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()>;

    /// What this run needs of the pass's own earlier runs through memory that the graph does
    /// not see (a buffer the pass owns): the (source, destination) of a global memory barrier.
    /// Called right before [`PassNode::record`]; the executor folds it into the barrier it
    /// records before the pass anyway, so the pass records none of its own (a separate barrier
    /// costs more than widening that one). `None` (the default): nothing to wait for.
    fn own_dependency(&mut self) -> Option<(Access, Access)> {
        None
    }

    /// Whether the pass reads the instance records of the world's previous frame
    /// ([`crate::passes::shared::GpuScene::previous_instance_binds`], for motion vectors): a
    /// renderer of a changing world keeps them, one more record per slot and a copy of each
    /// moved one per frame, only while some view's pass does. Without them a pass is given the
    /// current records (no motion). Asked once, when the graph runtime is made: the answer holds
    /// for the node's life. `false` (the default): it does not.
    fn reads_previous_instances(&self) -> bool {
        false
    }

    /// Whether the pass samples the renderer's shadow maps (the sun's and the lights', bound
    /// from the frame's shared data, not the graph): a renderer then records the shadow views'
    /// drawing before it. `false` (the default): it does not.
    fn samples_shadow_maps(&self) -> bool {
        false
    }

    /// Passes whose nodes return equal keys can be recorded together, one call of
    /// [`PassNode::record_together`] for several runtimes (the views of one renderer): the same
    /// kind with settings that one dispatch can serve. `None` (the default): never.
    fn together_key(&self) -> Option<u64> {
        None
    }

    /// Records this pass for several runtimes at once: `contexts[0]` is this node's own,
    /// `contexts[1..]` those of `others` (the same kind's nodes, with equal
    /// [`PassNode::together_key`]s), whose state it may use through [`PassNode::as_any_mut`].
    /// The executor's barriers before and after are already each runtime's.
    fn record_together(
        &mut self,
        contexts: &[PassContext<'_>],
        others: &mut [&mut (dyn PassNode + 'static)],
    ) -> crate::Result<()> {
        let _ = others;
        match contexts {
            [own] => self.record(own),
            _ => Err(crate::Error::Invalid("this pass cannot be recorded together with others".into())),
        }
    }

    /// The settings this node takes without being made again
    /// ([`crate::graph::GraphRuntime::update_settings`]): push constants, say, as opposed to
    /// what its pipelines or resources were made with. `[]` (the default): none.
    fn live_settings(&self) -> &'static [&'static str] {
        &[]
    }

    /// Takes `pass`'s settings, of which only [`PassNode::live_settings`] differ from those the
    /// node has; frames already recorded keep the old ones.
    fn apply_settings(&mut self, pass: &PlannedPass) -> crate::Result<()> {
        let _ = pass;
        Ok(())
    }

    /// The node's state as far as it decides the commands [`PassNode::record`] records beyond
    /// the plan, the node's settings and the frame's shared data
    /// ([`FrameData::replay_key`]): equal values promise equal commands, so that a frame can
    /// be recorded once and replayed while nothing changes. A node that records on its first
    /// run what it skips later, say, returns whether it has run. `None` (the default): the
    /// commands may differ from frame to frame (they hold the frame number, or data the
    /// recording writes on the host), and frames of its graph are always recorded.
    fn replay_state(&self) -> Option<u64> {
        None
    }

    /// The node as `Any`, for [`PassNode::record_together`] to reach the other nodes' state.
    fn as_any_mut(&mut self) -> Option<&mut dyn Any> {
        None
    }
}
