//! What a kind makes of the counters its passes write: an entry of the frame's stats, and a
//! policy that changes settings from them.

use crate::graph::plan::CompiledGraph;

/// What one pass's counters say of a frame, decoded by its kind
/// ([`crate::graph::PassKind::decode_counters`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CounterEntry {
    /// The group of the frame's stats it belongs to (a key of the stats JSON, e.g. `culling`):
    /// one per kind, or shared by kinds that report the same figures.
    pub group: &'static str,
    /// The figures, as plain data (their JSON object, which names the pass).
    pub value: serde_json::Value,
    /// What the pass culled and drew, when it draws a list: the frame's totals are made from
    /// these.
    pub draws: Option<DrawCounts>,
}

/// What a culling pass says of the instances of a frame: the frame's totals add up the drawn
/// figures of every pass (each draws a different set) and take the culled ones from the pass
/// that tested the most instances.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DrawCounts {
    /// Instances evaluated.
    pub tested: u32,
    /// Outside the frustum.
    pub frustum_culled: u32,
    /// Inside the frustum but occluded.
    pub occlusion_culled: u32,
    /// Instances drawn.
    pub drawn: u32,
    /// Draw commands.
    pub draws: u32,
    /// Triangles drawn.
    pub triangles: u64,
}

/// The slots of the draw list a pass draws, and how to read it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawList {
    /// The slots of its indirect commands, its draw count and its instance ids.
    pub slots: [&'static str; 3],
    /// Which of its commands the pass draws.
    pub order: DrawOrder,
    /// The slots of the cluster lists the pass may draw too, with the list's instance ids:
    /// each list's commands and its counts (`cluster_cull`'s outputs; captured where bound).
    pub cluster_slots: &'static [[&'static str; 2]],
}

/// Which commands of a draw list a pass draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DrawOrder {
    /// A culled list of the scene's draw groups, laid out in regions, each with its own count
    /// (the opaque regions are drawn; how the host's scene lays them out says which).
    Regions,
    /// The first `count` commands, in order (a sorted list).
    Sorted,
}

/// A setting of a pass to change: the pass, the setting and its new value as RON would write it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SettingOverride {
    /// The pass.
    pub pass: String,
    /// The setting.
    pub setting: String,
    /// Its value (`0.375`, `true`, `per_mip`).
    pub value: String,
}

/// A kind's policy for changing the graph's settings from a pass's counters, read back a few
/// frames late: one per pass, holding its own state between frames.
pub trait Adaptation: Send {
    /// Looks at one completed frame's counters of the pass at `pass` in `plan`, the plan that
    /// is running now (frames still in flight may report an older one). Returns the settings to
    /// change; the host compiles the graph again with them.
    fn observe(&mut self, counters: &CounterEntry, plan: &CompiledGraph, pass: usize) -> Vec<SettingOverride>;
}
