//! Counters the instance-cull passes write on the GPU (`CullStats` in
//! `shaders/cull/cull_common.glsl`), and the entry of the frame's stats the kind makes of them
//! (group `GROUP` of [`FrameStats`]).

use crate::graph::{CounterEntry, DrawCounts};
use crate::stats::FrameStats;
use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

/// The group of the frame's stats (and key of its JSON) that cull passes report in.
pub(crate) const GROUP: &str = "culling";

/// One cull pass's counters as the GPU writes them (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct CullCounters {
    /// Instances the pass evaluated.
    pub tested: u32,
    /// Of those, outside the frustum.
    pub frustum_culled: u32,
    /// Inside the frustum but behind the Hi-Z.
    pub occlusion_culled: u32,
    /// Instances in the pass's draw list.
    pub drawn: u32,
    /// Non-empty draw commands.
    pub draws: u32,
    /// Triangles drawn, low word.
    pub triangles_lo: u32,
    /// Triangles drawn, high word.
    pub triangles_hi: u32,
    /// Instances whose visibility bit the pass set (late phase).
    pub survivors: u32,
    /// Instances drawn at each level of detail (every drawn one at 0 without levels of detail).
    pub level_instances: [u32; 8],
}

impl CullCounters {
    /// Triangles drawn.
    pub fn triangles(&self) -> u64 {
        (self.triangles_hi as u64) << 32 | self.triangles_lo as u64
    }
}

/// One cull pass's figures in a frame, as reported.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CullPassStats {
    /// Pass name in the graph.
    pub pass: String,
    /// Instances evaluated.
    pub tested: u32,
    /// Outside the frustum.
    pub frustum_culled: u32,
    /// Behind the Hi-Z.
    pub occlusion_culled: u32,
    /// Instances drawn by this pass's list.
    pub drawn: u32,
    /// Draw commands.
    pub draws: u32,
    /// Triangles.
    pub triangles: u64,
    /// Instances drawn at each level of detail, from the full mesh (0) on, up to the coarsest
    /// level drawn (empty when nothing was drawn).
    #[serde(default)]
    pub level_instances: Vec<u32>,
}

impl CullPassStats {
    /// From the counters of pass `pass`.
    pub fn new(pass: &str, c: &CullCounters) -> Self {
        Self {
            pass: pass.into(),
            tested: c.tested,
            frustum_culled: c.frustum_culled,
            occlusion_culled: c.occlusion_culled,
            drawn: c.drawn,
            draws: c.draws,
            triangles: c.triangles(),
            level_instances: {
                let used = c.level_instances.iter().rposition(|&n| n != 0).map_or(0, |last| last + 1);
                c.level_instances[..used].to_vec()
            },
        }
    }
}

impl CullPassStats {
    /// The cull passes' figures of `frame`, in pass order.
    pub fn of(frame: &FrameStats) -> Vec<CullPassStats> {
        frame.entries(GROUP)
    }

    /// Instances drawn at each level of detail in `frame`, over its cull passes and draw lists,
    /// from the full mesh (0) on, up to the coarsest level drawn.
    pub fn level_totals(frame: &FrameStats) -> Vec<u32> {
        let mut sum: Vec<u32> = Vec::new();
        for pass in Self::of(frame) {
            sum.resize(sum.len().max(pass.level_instances.len()), 0);
            for (s, n) in sum.iter_mut().zip(&pass.level_instances) {
                *s += n;
            }
        }
        sum
    }

    /// The entry of the frame's stats for `counters` of pass `pass` (`None` if they are not a
    /// whole record).
    pub(crate) fn entry(pass: &str, counters: &[u8]) -> Option<CounterEntry> {
        let c: CullCounters = bytemuck::try_pod_read_unaligned(counters).ok()?;
        let stats = CullPassStats::new(pass, &c);
        let draws = DrawCounts {
            tested: stats.tested,
            frustum_culled: stats.frustum_culled,
            occlusion_culled: stats.occlusion_culled,
            drawn: stats.drawn,
            draws: stats.draws,
            triangles: stats.triangles,
        };
        Some(CounterEntry { group: GROUP, value: serde_json::to_value(stats).ok()?, draws: Some(draws) })
    }
}
