//! Statistics as plain data: per-frame counts and GPU timings, exported as JSON. What a pass
//! reports of its own work, its kind decodes ([`crate::graph::PassKind::decode_counters`]) into
//! an entry of a group of [`FrameStats::passes`].

use crate::gpu::PassTiming;
use crate::graph::{CounterEntry, DrawCounts};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use crate::graph::ResourceBytes;

/// What one frame did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    /// Frame number, from 0.
    pub frame: u64,
    /// Instances in the scene (all tested, when culling runs).
    pub instances: u32,
    /// Instances outside the frustum, or inside it with a screen bound that covers no sample
    /// position (small-object culling: they could make no fragment).
    pub frustum_culled: u32,
    /// Instances inside the frustum but occluded.
    pub occlusion_culled: u32,
    /// Instances drawn.
    pub drawn: u32,
    /// Indirect draw commands issued (non-empty ones, when culling compacts them).
    pub draws: u32,
    /// Triangles submitted.
    pub triangles: u64,
    /// What the passes reported of their work, by group (`culling`: each cull pass's counts;
    /// `gbuffer`: each compressed G-buffer's pool), in pass order: each entry as its kind
    /// decoded it, naming its pass.
    #[serde(flatten)]
    pub passes: BTreeMap<String, Vec<serde_json::Value>>,
    /// The same entries as their kinds decoded them, with the name of the pass that wrote each
    /// (what a kind's adaptation reads; not exported).
    #[serde(skip)]
    pub counters: Vec<(String, CounterEntry)>,
    /// Exact-visibility check of this frame (with `--verify`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verify: Option<VerifyStats>,
    /// GPU milliseconds per pass, in execution order.
    pub gpu_ms: Vec<PassTiming>,
    /// GPU milliseconds of the whole frame (first begin to last end).
    pub gpu_total_ms: f64,
    /// CPU milliseconds spent recording the frame's commands.
    pub cpu_record_ms: f64,
    /// The world changes this frame applied (a renderer made from a world; summed over the
    /// syncs before the frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub update: Option<UpdateStats>,
    /// The view's sun shadow cascades that drew this frame, nearest first
    /// ([`crate::render::Renderer::set_shadows`]); a cascade whose map did not need drawing
    /// again is left out.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shadow_cascades: Vec<ShadowViewStats>,
    /// The view's spot and point light shadow faces that drew this frame, in face order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shadow_faces: Vec<ShadowViewStats>,
}

/// What one shadow view of a camera view (a sun cascade, a light's face) drew in a frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShadowViewStats {
    /// The cascade (0 the nearest) or face.
    pub index: u32,
    /// Instances outside its frustum.
    pub frustum_culled: u32,
    /// Instances in its frustum but hidden in its map.
    pub occlusion_culled: u32,
    /// Instances drawn into its map.
    pub drawn: u32,
    /// Triangles drawn.
    pub triangles: u64,
    /// GPU milliseconds per pass of its graph.
    pub gpu_ms: Vec<PassTiming>,
}

impl ShadowViewStats {
    /// GPU milliseconds of its passes together.
    pub fn gpu_ms_total(&self) -> f64 {
        self.gpu_ms.iter().map(|t| t.ms).sum()
    }
}

impl FrameStats {
    /// The entries of `group` read as `T` (the type the kind that reports them gives), in pass
    /// order; entries that are not a `T` are left out.
    pub fn entries<T: DeserializeOwned>(&self, group: &str) -> Vec<T> {
        self.passes.get(group).into_iter().flatten().filter_map(|v| serde_json::from_value(v.clone()).ok()).collect()
    }

    /// Adds the passes' entries, and makes the frame's totals from the draw lists among them
    /// (the drawn figures of every list add up, since each draws a different set; the culled ones
    /// come from the pass that tested the most instances). Without any, the totals stay as set.
    pub fn add_counters(&mut self, entries: impl IntoIterator<Item = (String, CounterEntry)>) {
        let mut draws: Vec<DrawCounts> = Vec::new();
        for (pass, entry) in entries {
            draws.extend(entry.draws);
            self.passes.entry(entry.group.to_string()).or_default().push(entry.value.clone());
            self.counters.push((pass, entry));
        }
        if let Some(widest) = draws.iter().max_by_key(|d| d.tested) {
            self.frustum_culled = widest.frustum_culled;
            self.occlusion_culled = widest.occlusion_culled;
            self.drawn = draws.iter().map(|d| d.drawn).sum();
            self.draws = draws.iter().map(|d| d.draws).sum();
            self.triangles = draws.iter().map(|d| d.triangles).sum();
        }
    }
}

/// What applying a world's changes cost ([`crate::render::Renderer::sync`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UpdateStats {
    /// Instance changes applied: each instance inserted, changed or removed, plus each move
    /// (an instance moved twice between frames counts twice); every instance when the world was
    /// laid out anew.
    pub instances_changed: u64,
    /// Bytes queued for upload (a relayout counts the whole scene it uploads).
    pub bytes_uploaded: u64,
    /// CPU milliseconds the sync took.
    pub cpu_ms: f64,
    /// GPU milliseconds of applying the changes at the frame: the scene's uploads and edits
    /// (registrations, growth), the posed instances' deformation and the scatter of the changed
    /// slots (0 when not timed).
    pub gpu_ms: f64,
    /// Whether the world was laid out anew.
    pub relayout: bool,
}

impl UpdateStats {
    /// `self` and `other` together (two syncs before one frame).
    pub fn add(&mut self, other: &UpdateStats) {
        self.instances_changed += other.instances_changed;
        self.bytes_uploaded += other.bytes_uploaded;
        self.cpu_ms += other.cpu_ms;
        self.relayout |= other.relayout;
    }
}

/// How a frame's culling compares with exact visibility (an unculled instance-id render).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct VerifyStats {
    /// Instances visible at some sample.
    pub visible: u32,
    /// Instances drawn.
    pub drawn: u32,
    /// Visible but not drawn: culling removed something on screen. Must be 0.
    pub false_negatives: u32,
    /// Drawn but not visible: work culling could have saved.
    pub false_positives: u32,
    /// The first few false negatives (instance ids), for debugging.
    pub missed: Vec<u32>,
    /// Cluster culling checked cluster by cluster, where the frame drew instances through
    /// cluster lists at their full mesh.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clusters: Option<ClusterVerifyStats>,
}

/// How a frame's cluster culling compares with exact visibility, over the instances it drew
/// cluster by cluster at their full mesh (the level the oracle draws): a cluster is visible
/// when a triangle of it is seen at some sample.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClusterVerifyStats {
    /// Instances checked.
    pub instances: u32,
    /// Their clusters visible at some sample.
    pub visible: u32,
    /// Their clusters drawn.
    pub drawn: u32,
    /// Visible but not drawn. Must be 0.
    pub false_negatives: u32,
    /// Drawn but not visible.
    pub false_positives: u32,
}

/// A whole run of `cullgraph render`, as written to `--stats`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunStats {
    /// Vulkan device name.
    pub device: String,
    /// Scene name.
    pub scene: String,
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Instances in the scene.
    pub instances: u32,
    /// Distinct meshes (draw groups) in the scene.
    pub meshes: u32,
    /// Render graph name.
    pub graph: String,
    /// Transient memory of the graph's resources, aliased (bytes of the heaps).
    pub transient_bytes: u64,
    /// Transient memory if no two transients shared memory.
    pub transient_bytes_without_aliasing: u64,
    /// Device bytes of every resource the graph allocated (G-buffer images or the compressed
    /// G-buffer, depth, ...), before aliasing.
    pub resources: Vec<ResourceBytes>,
    /// Device bytes of the scene's textures (every size class's array with its mips).
    #[serde(default)]
    pub texture_bytes: u64,
    /// Per-frame figures.
    pub frames: Vec<FrameStats>,
    /// Error of the last frame (the saved image) against its supersampled reference (with
    /// `--reference`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<ImageError>,
    /// With several views (`--view`), each one's figures; `frames` then holds the first
    /// view's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub views: Vec<ViewRunStats>,
}

/// One view of a run with several (`cullgraph render --view`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewRunStats {
    /// The view's number (0 for the first).
    pub view: u32,
    /// Its output width in the last frame.
    pub width: u32,
    /// Its output height in the last frame.
    pub height: u32,
    /// Device bytes of its graph's resources (targets, pyramids, culling history) before
    /// transients share memory: what the view costs beside the scene, which all views share.
    pub view_bytes: u64,
    /// Its image.
    pub image: String,
    /// Its per-frame figures.
    pub frames: Vec<FrameStats>,
}

impl RunStats {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}

/// How far a rendered image is from the supersampled reference of the same frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageError {
    /// Samples per pixel of the reference (N x N for an N-times-larger render).
    pub samples_per_pixel: u32,
    /// Mean LDR-FLIP error over the pixels (0: identical; 1: maximal).
    pub mean_flip: f64,
    /// PSNR in dB over RGB in 8-bit sRGB units (JSON `null` when identical, i.e. infinite).
    #[serde(deserialize_with = "infinite_when_null")]
    pub psnr_db: f64,
}

/// Reads a number, or `null` (how JSON writes an infinite PSNR) as +infinity.
fn infinite_when_null<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}
