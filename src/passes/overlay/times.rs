//! The GPU times the overlay shows: the pass writes the newest completed frame's, in plan
//! order, into a host-visible buffer per frame in flight.

use crate::gpu::PassTiming;

/// Passes whose GPU time the per-frame buffer carries.
pub(crate) const MAX_TIMED: usize = 64;

/// The newest completed frame's GPU times as the overlay reads them (`OverlayTimes` in
/// `shaders/overlay/overlay_common.glsl`); one host-visible buffer per frame in flight.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct GpuPassTimes {
    /// Entries of `ms` in use (the plan's passes, in execution order).
    pub count: u32,
    /// The frame they were measured in; `u32::MAX` when none has completed yet.
    pub frame: u32,
    /// The whole frame, milliseconds; negative when unknown.
    pub total_ms: f32,
    /// Unused.
    pub pad: f32,
    /// Per pass, milliseconds; negative when unknown.
    pub ms: [f32; MAX_TIMED],
}

/// Bytes of [`GpuPassTimes`].
pub(crate) const PASS_TIMES_BYTES: u64 = std::mem::size_of::<GpuPassTimes>() as u64;

impl GpuPassTimes {
    /// No times yet.
    pub fn none() -> Self {
        Self { count: 0, frame: u32::MAX, total_ms: -1.0, pad: 0.0, ms: [-1.0; MAX_TIMED] }
    }

    /// The times of `frame` (scopes named as the passes, plus "frame") in the order of
    /// `passes` (the plan's names).
    pub fn from_timings(passes: &[String], frame: u64, timings: &[PassTiming]) -> Self {
        let mut out = Self::none();
        out.frame = u32::try_from(frame).unwrap_or(u32::MAX - 1);
        out.count = passes.len().min(MAX_TIMED) as u32;
        let find = |name: &str| timings.iter().find(|t| t.name == name).map(|t| t.ms as f32);
        for (slot, pass) in out.ms.iter_mut().zip(passes) {
            *slot = find(pass).unwrap_or(-1.0);
        }
        out.total_ms = find("frame").unwrap_or(-1.0);
        out
    }
}
