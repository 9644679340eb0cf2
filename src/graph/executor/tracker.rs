//! What last touched each physical resource: the executor fills the source half of every
//! first-use-in-frame barrier from it (previous frame, or an aliased resource in this frame).

use crate::gpu::Access;
use ash::vk;

/// The accesses to one physical resource since its last write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PhysState {
    /// Current image layout (`UNDEFINED` for buffers and fresh images).
    pub layout: vk::ImageLayout,
    /// Stage and access of the last write.
    pub write: (vk::PipelineStageFlags2, vk::AccessFlags2),
    /// Stages that read since that write.
    pub read_stages: vk::PipelineStageFlags2,
}

impl Default for PhysState {
    fn default() -> Self {
        Self {
            layout: vk::ImageLayout::UNDEFINED,
            write: (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            read_stages: vk::PipelineStageFlags2::NONE,
        }
    }
}

/// Per physical resource state.
#[derive(Clone, Default, PartialEq)]
pub struct Tracker {
    states: Vec<PhysState>,
}

impl Tracker {
    /// A tracker for `count` physical resources, all untouched.
    pub fn new(count: usize) -> Self {
        Self { states: vec![PhysState::default(); count] }
    }

    /// State of one physical resource.
    pub fn state(&self, phys: usize) -> PhysState {
        self.states[phys]
    }

    /// Records that `access` happened to `phys` (a write if `writes`).
    pub fn apply(&mut self, phys: usize, access: Access, writes: bool) {
        let s = &mut self.states[phys];
        if writes {
            s.write = (access.stage, access.access & write_bits());
            s.read_stages = vk::PipelineStageFlags2::NONE;
        } else {
            s.read_stages |= access.stage;
        }
        s.layout = access.layout;
    }

    /// Sets the state of `phys` to what a host says it last did with it.
    pub fn set_external(&mut self, phys: usize, access: Access) {
        self.states[phys] = PhysState {
            layout: access.layout,
            write: (access.stage, access.access & write_bits()),
            read_stages: access.stage,
        };
    }

    /// The access everything in `phys_set` last did: what a new use of that memory waits for.
    pub fn pending(&self, phys_set: &[usize]) -> Access {
        let mut out = Access {
            stage: vk::PipelineStageFlags2::NONE,
            access: vk::AccessFlags2::NONE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        for &p in phys_set {
            let s = &self.states[p];
            out.stage |= s.write.0 | s.read_stages;
            out.access |= s.write.1;
        }
        out
    }
}

/// Access bits that are writes (only writes need to be made available).
fn write_bits() -> vk::AccessFlags2 {
    vk::AccessFlags2::SHADER_STORAGE_WRITE
        | vk::AccessFlags2::SHADER_WRITE
        | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE
        | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE
        | vk::AccessFlags2::TRANSFER_WRITE
        | vk::AccessFlags2::HOST_WRITE
        | vk::AccessFlags2::MEMORY_WRITE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pending_collects_the_last_write_and_the_reads_after_it() {
        let mut t = Tracker::new(2);
        t.apply(0, Access::COLOR_ATTACHMENT, true);
        t.apply(0, Access::COMPUTE_READ, false);
        let p = t.pending(&[0, 1]);
        assert_eq!(p.stage, vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT | vk::PipelineStageFlags2::COMPUTE_SHADER);
        assert_eq!(p.access, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
        t.apply(0, Access::COMPUTE_WRITE, true);
        assert_eq!(t.pending(&[0]).stage, vk::PipelineStageFlags2::COMPUTE_SHADER);
        assert_eq!(t.state(0).layout, vk::ImageLayout::GENERAL);
    }
}
