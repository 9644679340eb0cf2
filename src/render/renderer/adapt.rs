//! The kinds' adaptations of a renderer's graph: each pass whose kind has one
//! ([`crate::graph::PassKind::adaptation`]) looks at its counters of every completed frame, and
//! the settings they ask for are compiled into the graph (frames in flight finish on the old one).

use super::Renderer;
use crate::error::Result;
use crate::gpu::ShaderCompiler;
use crate::graph::{Adaptation, SettingOverride};
use crate::stats::FrameStats;

/// Each adapting pass's policy, by pass name, made when its first counters arrive.
#[derive(Default)]
pub(in crate::render) struct Adaptations(Vec<(String, Box<dyn Adaptation>)>);

impl Renderer {
    /// Lets the passes' kinds change the graph's settings from what the frames' counters say
    /// (for example the compressed G-buffer's pool, which grows when it overflows and shrinks
    /// when it stays mostly empty). Call [`Renderer::adapt`] with each completed frame.
    pub fn enable_adaptation(&mut self) {
        self.main_view_mut().adaptations = Some(Adaptations::default());
    }

    /// Feeds a completed frame's counters to the kinds' adaptations; when they ask for new
    /// settings, compiles the graph again with them (frames in flight finish on the old one)
    /// and returns what changed.
    pub fn adapt(&mut self, shaders: &ShaderCompiler, stats: &FrameStats) -> Result<Vec<SettingOverride>> {
        let main = &mut self.views[0];
        let plan = main.graphs.runtime.plan();
        let Some(Adaptations(adaptations)) = main.adaptations.as_mut() else { return Ok(Vec::new()) };
        let mut changes = Vec::new();
        for (name, entry) in &stats.counters {
            // A frame of a replaced plan names its passes as this one does.
            let Some(now) = plan.passes.iter().position(|p| p.name == *name) else { continue };
            let at = match adaptations.iter().position(|(n, _)| n == name) {
                Some(at) => at,
                None => match plan.kinds.get(&plan.passes[now].kind).and_then(|k| k.kind.adaptation()) {
                    Some(a) => {
                        adaptations.push((name.clone(), a));
                        adaptations.len() - 1
                    }
                    None => continue,
                },
            };
            changes.extend(adaptations[at].1.observe(entry, plan, now));
        }
        if !changes.is_empty() {
            let spec = main.graphs.spec.clone().with_settings(changes.clone());
            self.reload_graph(shaders, &spec)?;
        }
        Ok(changes)
    }
}
