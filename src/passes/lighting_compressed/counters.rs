//! Counters of the compressed G-buffer (`Stats` in `shaders/lighting/lighting_compressed.comp`):
//! how full the pool was, what overflowed, and how many distinct surfaces the pixels hold; the
//! entry of the frame's stats the kind makes of them (group `GROUP` of [`FrameStats`]).

use crate::graph::CounterEntry;
use crate::stats::FrameStats;
use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

/// The group of the frame's stats (and key of its JSON) that compressed G-buffers report in.
pub(crate) const GROUP: &str = "gbuffer";

/// The counters as the GPU writes them (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GbufferCounters {
    /// Pool blocks fragments asked for (more than the pool when it overflowed).
    pub allocated: u32,
    /// Fragments dropped because the pool was full.
    pub overflow_fragments: u32,
    /// Samples those fragments covered (shaded with the pixel's head instead).
    pub overflow_samples: u32,
    /// Blocks in the pool.
    pub pool_blocks: u32,
    /// Pixels.
    pub pixels: u32,
    /// Unused (the GPU leaves it 0).
    pub pad: [u32; 3],
    /// Pixels with 1, 2, ... 8 distinct surfaces. The GPU counts only the pixels with two or
    /// more (the few edge pixels, so the count costs nearly nothing) and leaves entry 0 at 0:
    /// [`GbufferCounters::surfaces_per_pixel`] completes it.
    pub histogram: [u32; 8],
}

impl GbufferCounters {
    /// Pixels with 1, 2, ... 8 distinct surfaces, the single-surface count derived from the
    /// pixel count.
    pub fn surfaces_per_pixel(&self) -> [u32; 8] {
        let mut h = self.histogram;
        h[0] = self.pixels.saturating_sub(h[1..].iter().sum());
        h
    }
}

/// One compressed G-buffer's figures in a frame, as reported.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GbufferPassStats {
    /// The lighting pass that read it.
    pub pass: String,
    /// Pool blocks available.
    pub pool_blocks: u32,
    /// Pool blocks used (at most `pool_blocks`).
    pub pool_used: u32,
    /// Pool blocks fragments asked for (what an unbounded pool would have used).
    pub pool_requested: u32,
    /// Fragments dropped because the pool was full (0 means every edge sample was kept).
    pub overflow_fragments: u32,
    /// Samples those fragments covered.
    pub overflow_samples: u32,
    /// Pixels with 1, 2, ... 8 distinct surfaces.
    pub surfaces_per_pixel: [u32; 8],
}

impl GbufferPassStats {
    /// From the counters of pass `pass`.
    pub fn new(pass: &str, c: &GbufferCounters) -> Self {
        Self {
            pass: pass.into(),
            pool_blocks: c.pool_blocks,
            pool_used: c.allocated.min(c.pool_blocks),
            pool_requested: c.allocated,
            overflow_fragments: c.overflow_fragments,
            overflow_samples: c.overflow_samples,
            surfaces_per_pixel: c.surfaces_per_pixel(),
        }
    }
}

impl GbufferPassStats {
    /// The compressed G-buffers' figures of `frame`, in pass order.
    pub fn of(frame: &FrameStats) -> Vec<GbufferPassStats> {
        frame.entries(GROUP)
    }

    /// Pixels of the image (every pixel has at least one surface).
    pub fn pixels(&self) -> u64 {
        self.surfaces_per_pixel.iter().map(|&n| n as u64).sum()
    }

    /// The entry of the frame's stats for `counters` of pass `pass`.
    pub(crate) fn entry(pass: &str, counters: &[u8]) -> Option<CounterEntry> {
        let c: GbufferCounters = bytemuck::try_pod_read_unaligned(counters).ok()?;
        let value = serde_json::to_value(GbufferPassStats::new(pass, &c)).ok()?;
        Some(CounterEntry { group: GROUP, value, draws: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_surface_pixels_are_the_rest() {
        let c = GbufferCounters { pixels: 100, histogram: [0, 7, 2, 1, 0, 0, 0, 0], ..Default::default() };
        assert_eq!(c.surfaces_per_pixel(), [90, 7, 2, 1, 0, 0, 0, 0]);
    }
}
