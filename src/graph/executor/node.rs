//! The interface between the executor and the passes: a pass records its commands given the
//! resources bound to its slots and the frame's shared inputs.

use super::resources::{Physical, RuntimeResources};
use crate::gpu::{Buffer, GpuContext, Image};
use crate::graph::plan::{Binding, PlannedPass};
use crate::render::scene_buffers::GpuScene;
use ash::vk;

/// Inputs every pass of a frame may use, owned by the renderer.
pub struct FrameData<'a> {
    /// The scene on the GPU (pools, instances, materials, the unculled draw list).
    pub scene: &'a GpuScene,
    /// This frame's [`crate::render::gpu_types::FrameConstants`].
    pub constants: &'a Buffer,
    /// This frame's point lights.
    pub lights: &'a Buffer,
    /// GPU times of the newest completed frame, for passes that show them
    /// ([`crate::passes::overlay::GpuPassTimes`], host-visible, one per frame in flight).
    pub pass_times: Option<&'a Buffer>,
    /// Frame number.
    pub frame: u64,
    /// Output size.
    pub extent: vk::Extent2D,
}

/// The resources bound to one pass's slots in this frame.
pub struct SlotBindings<'a> {
    pub(super) pass: &'a PlannedPass,
    pub(super) resources: &'a RuntimeResources,
    pub(super) frame: u64,
}

impl<'a> SlotBindings<'a> {
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
}

/// A pass instance of a compiled graph (pipelines created, ready to record).
pub trait PassNode {
    /// Records the pass's commands. Barriers around it are the executor's job.
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()>;
}
