//! Counters the instance-cull passes write on the GPU (`CullStats` in
//! `shaders/cull/cull_common.glsl`), and how a frame's figures are made from them.

use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

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
    /// Unused.
    pub pad: [u32; 8],
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
        }
    }
}

/// A frame's totals over its cull passes: drawn, draws and triangles add up over the passes
/// (each draws a different set); the culled counts come from the pass that evaluated the most
/// instances (the late or single pass tests everything).
pub fn totals(passes: &[CullPassStats]) -> (u32, u32, u32, u32, u64) {
    let widest = passes.iter().max_by_key(|p| p.tested);
    let frustum = widest.map_or(0, |p| p.frustum_culled);
    let occlusion = widest.map_or(0, |p| p.occlusion_culled);
    let drawn = passes.iter().map(|p| p.drawn).sum();
    let draws = passes.iter().map(|p| p.draws).sum();
    let triangles = passes.iter().map(|p| p.triangles).sum();
    (frustum, occlusion, drawn, draws, triangles)
}
