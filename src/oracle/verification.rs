//! Exact-visibility verification of a renderer's frames, attached from outside as an observer
//! ([`crate::render::FrameObserver`]): after each frame the renderer waits for, an unculled
//! instance-id render of the same camera at the frame's sample count says which instances some
//! sample sees, and what the frame's drawing passes drew is compared with it
//! ([`crate::stats::FrameStats::verify`]: false negatives, false positives).

use super::visibility::VisibilityOracle;
use crate::error::Result;
use crate::gpu::ShaderCompiler;
use crate::graph::CompiledGraph;
use crate::render::{DrawnInstances, FrameObserver, Renderer};
use crate::scene::FLAG_EMPTY_SLOT;
use crate::stats::{FrameStats, VerifyStats};
use ash::vk;
use std::collections::BTreeSet;

/// The observer: the oracle, and what it saw in the last frame.
pub struct Verification {
    oracle: VisibilityOracle,
    exactly_visible: BTreeSet<u32>,
}

impl Verification {
    /// An oracle for `renderer`'s output size and its graph's depth sample count.
    pub fn new(renderer: &Renderer, shaders: &ShaderCompiler) -> Result<Self> {
        let settings = renderer.settings();
        let samples = depth_samples(renderer.plan());
        let oracle = VisibilityOracle::new(renderer.context(), shaders, settings.width, settings.height, samples)?;
        Ok(Self { oracle, exactly_visible: BTreeSet::new() })
    }

    /// The instances seen by some sample of the last frame checked (empty before).
    pub fn exactly_visible(&self) -> &BTreeSet<u32> {
        &self.exactly_visible
    }
}

impl FrameObserver for Verification {
    fn needs_draw_lists(&self) -> bool {
        true
    }

    fn completed(&mut self, renderer: &Renderer, frame: u64, stats: &mut FrameStats) -> Result<()> {
        let constants = renderer.frame_constants_of(frame);
        let visible = self.oracle.render(renderer.context(), renderer.gpu_scene(), constants)?.visible;
        let lists = renderer.drawn()?.unwrap_or_default();
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
        });
        self.exactly_visible = visible;
        Ok(())
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
