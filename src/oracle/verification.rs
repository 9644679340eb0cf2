//! Exact-visibility verification of a renderer's frames, attached from outside as an observer
//! ([`crate::render::FrameObserver`]): after each frame the renderer waits for, an unculled
//! instance-id render of the same camera at the frame's sample count says which instances some
//! sample sees, and what the frame's drawing passes drew is compared with it
//! ([`crate::stats::FrameStats::verify`]: false negatives, false positives).

use super::visibility::{VisibilityOracle, VisibleIds};
use crate::error::Result;
use crate::gpu::ShaderCompiler;
use crate::graph::CompiledGraph;
use crate::render::{DrawnInstances, FrameObserver, Renderer, ViewId};
use crate::scene::FLAG_EMPTY_SLOT;
use crate::stats::{ClusterVerifyStats, FrameStats, VerifyStats};
use ash::vk;
use std::collections::BTreeSet;

/// An oracle made for one view at one output size and depth sample count.
struct ViewOracle {
    view: ViewId,
    made_for: (u32, u32, vk::SampleCountFlags),
    oracle: VisibilityOracle,
}

/// The observer: an oracle per view (made again when the view's size or sample count
/// changes), and what it saw in the last frame checked.
pub struct Verification {
    shaders: ShaderCompiler,
    oracles: Vec<ViewOracle>,
    exactly_visible: BTreeSet<u32>,
}

impl Verification {
    /// Verification of every view of `renderer`.
    pub fn new(renderer: &Renderer, shaders: &ShaderCompiler) -> Result<Self> {
        let mut verification =
            Self { shaders: shaders.try_clone()?, oracles: Vec::new(), exactly_visible: BTreeSet::new() };
        // The main view's oracle now, so that a device that cannot make one says so at once.
        verification.oracle_of(renderer, ViewId::MAIN)?;
        Ok(verification)
    }

    /// The instances seen by some sample of the last frame checked (empty before).
    pub fn exactly_visible(&self) -> &BTreeSet<u32> {
        &self.exactly_visible
    }

    /// The oracle of `view` at its current size and sample count.
    fn oracle_of(&mut self, renderer: &Renderer, view: ViewId) -> Result<&mut VisibilityOracle> {
        let settings = renderer.view_settings(view)?;
        let made_for = (settings.width, settings.height, depth_samples(renderer.view_plan(view)?));
        let at = match self.oracles.iter().position(|o| o.view == view) {
            Some(at) if self.oracles[at].made_for == made_for => at,
            found => {
                let (w, h, samples) = made_for;
                let oracle = VisibilityOracle::new(renderer.context(), &self.shaders, w, h, samples)?;
                let made = ViewOracle { view, made_for, oracle };
                match found {
                    Some(at) => {
                        self.oracles[at] = made;
                        at
                    }
                    None => {
                        self.oracles.push(made);
                        self.oracles.len() - 1
                    }
                }
            }
        };
        Ok(&mut self.oracles[at].oracle)
    }
}

impl FrameObserver for Verification {
    fn needs_draw_lists(&self) -> bool {
        true
    }

    fn completed(&mut self, renderer: &Renderer, view: ViewId, frame: u64, stats: &mut FrameStats) -> Result<()> {
        let constants = renderer.view_frame_constants_of(view, frame)?;
        let oracle = self.oracle_of(renderer, view)?;
        let seen = oracle.render(renderer.context(), renderer.gpu_scene(), constants)?;
        let clusters = renderer.drawn_clusters_in_view(view)?.unwrap_or_default();
        let cluster_check = (!clusters.is_empty()).then(|| check_clusters(renderer.scene(), &seen, &clusters));
        let visible = seen.visible;
        let lists = renderer.drawn_in_view(view)?.unwrap_or_default();
        let drawn: BTreeSet<u32> = if lists.contains(&DrawnInstances::All) {
            (0..renderer.gpu_scene().instance_count).collect()
        } else {
            lists
                .into_iter()
                .flat_map(|l| match l {
                    DrawnInstances::Some(ids) => ids,
                    DrawnInstances::All => Vec::new(),
                })
                .collect()
        };
        // An empty slot of a changing world (an instance just removed, still on last frame's
        // visible list) has an all-zero record: drawing it puts nothing on screen.
        let scene = renderer.scene();
        let empty = |id: &u32| scene.instances.get(*id as usize).is_some_and(|i| i.flags & FLAG_EMPTY_SLOT != 0);
        let drawn: BTreeSet<u32> = drawn.into_iter().filter(|id| !empty(id)).collect();
        let missed: Vec<u32> = visible.difference(&drawn).copied().collect();
        stats.verify = Some(VerifyStats {
            visible: visible.len() as u32,
            drawn: drawn.len() as u32,
            false_negatives: missed.len() as u32,
            false_positives: drawn.difference(&visible).count() as u32,
            missed: missed.into_iter().take(16).collect(),
            clusters: cluster_check,
        });
        self.exactly_visible = visible;
        Ok(())
    }
}

/// Cluster culling's draws against the oracle's samples, for the instances drawn cluster by
/// cluster at their full mesh (`drawn`: instance id and first index of each cluster drawn).
fn check_clusters(scene: &crate::scene::Scene, seen: &VisibleIds, drawn: &[(u32, u32)]) -> ClusterVerifyStats {
    // The level-0 clusters of `instance`'s mesh, if any.
    let clusters_of = |instance: u32| {
        let mesh = scene.meshes.get(scene.instances.get(instance as usize)?.mesh as usize)?;
        mesh.clusters.first().map(|c| (mesh, c.as_slice()))
    };
    let mut drawn_set: BTreeSet<(u32, usize)> = BTreeSet::new();
    for &(instance, first_index) in drawn {
        let Some((_, clusters)) = clusters_of(instance) else { continue };
        if let Ok(c) = clusters.binary_search_by_key(&first_index, |c| c.first_index) {
            drawn_set.insert((instance, c));
        }
    }
    let checked: BTreeSet<u32> = drawn_set.iter().map(|&(i, _)| i).collect();
    let mut visible: BTreeSet<(u32, usize)> = BTreeSet::new();
    for (&id, &triangle) in seen.ids.iter().zip(&seen.triangles) {
        let Some(instance) = id.checked_sub(1).filter(|i| checked.contains(i)) else { continue };
        let Some((mesh, clusters)) = clusters_of(instance) else { continue };
        let index = mesh.first_index + 3 * triangle;
        let c = clusters.partition_point(|c| c.first_index <= index).saturating_sub(1);
        visible.insert((instance, c));
    }
    ClusterVerifyStats {
        instances: checked.len() as u32,
        visible: visible.len() as u32,
        drawn: drawn_set.len() as u32,
        false_negatives: visible.difference(&drawn_set).count() as u32,
        false_positives: drawn_set.difference(&visible).count() as u32,
    }
}

/// Verification as methods of the renderer (`use cullgraph::oracle::Verify`).
pub trait Verify {
    /// Checks every headless frame against exact visibility: [`FrameStats::verify`] then
    /// reports false negatives and false positives. Costs an extra render and readbacks per
    /// frame.
    fn enable_verification(&mut self, shaders: &ShaderCompiler) -> Result<()>;

    /// The instances seen by some sample of the last frame rendered with verification on
    /// (empty before, or without verification).
    fn exactly_visible(&self) -> &BTreeSet<u32>;
}

impl Verify for Renderer {
    fn enable_verification(&mut self, shaders: &ShaderCompiler) -> Result<()> {
        let verification = Verification::new(self, shaders)?;
        self.attach(verification)
    }

    fn exactly_visible(&self) -> &BTreeSet<u32> {
        static NONE: BTreeSet<u32> = BTreeSet::new();
        self.observer::<Verification>().map_or(&NONE, Verification::exactly_visible)
    }
}

/// Samples of the graph's first depth image (what the oracle must match); 1 if none.
fn depth_samples(plan: &CompiledGraph) -> vk::SampleCountFlags {
    plan.resources
        .iter()
        .find_map(|r| match r.kind {
            crate::graph::ResolvedKind::Image { format, samples, .. } if crate::graph::formats::is_depth(format) => {
                Some(samples)
            }
            _ => None,
        })
        .unwrap_or(vk::SampleCountFlags::TYPE_1)
}
