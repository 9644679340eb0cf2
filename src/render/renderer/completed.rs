//! The figures of a frame once it has completed: its GPU timings and the counters each pass's
//! kind decoded, read back through per-frame host buffers a few frames late, never waited on.

use super::{Renderer, ViewId};
use crate::error::Result;
use crate::gpu::PassTiming;
use crate::stats::{FrameStats, ShadowViewStats};

impl Renderer {
    /// GPU timings of a recorded frame of the main view if it has completed and its timestamps
    /// were not reused.
    pub fn completed_timings(&self, frame: u64) -> Result<Vec<PassTiming>> {
        self.completed_view_timings(ViewId::MAIN, frame).map_err(super::unwrap_main)
    }

    /// GPU timings of `view`'s graph in a recorded frame, if it has completed and its
    /// timestamps were not reused (empty when the view did not render that frame).
    pub fn completed_view_timings(&self, view: ViewId, frame: u64) -> Result<Vec<PassTiming>> {
        match self.view_state(view)?.graphs.runtime_of(frame) {
            Some((runtime, index)) => runtime.timings(index),
            None => Ok(Vec::new()),
        }
    }

    /// The figures of a recorded frame of the main view once it has completed on the GPU
    /// (counters and timestamps come back through per-frame host buffers, a few frames late,
    /// never waited on). Without culling passes everything is drawn.
    pub fn completed_stats(&self, frame: u64) -> Result<FrameStats> {
        self.completed_view_stats(ViewId::MAIN, frame).map_err(super::unwrap_main)
    }

    /// [`Renderer::completed_stats`] of `view`.
    pub fn completed_view_stats(&self, view: ViewId, frame: u64) -> Result<FrameStats> {
        let timings = self.completed_view_timings(view, frame)?;
        let total = timings.iter().find(|t| t.name == "frame").map_or(0.0, |t| t.ms);
        let entries = match self.view_state(view)?.graphs.runtime_of(frame) {
            Some((runtime, index)) => runtime.counter_entries(index)?,
            None => Vec::new(),
        };
        // A world renderer's empty slots are no instances.
        let instances = self.world.as_ref().map_or(self.gpu_scene.instance_count, |w| w.instances());
        let mut stats = FrameStats {
            frame,
            instances,
            drawn: instances,
            draws: self.gpu_scene.regions.groups(),
            triangles: self.gpu_scene.triangles,
            gpu_ms: timings.into_iter().filter(|t| t.name != "frame").collect(),
            gpu_total_ms: total,
            ..Default::default()
        };
        stats.add_counters(entries);
        stats.update = match &self.world {
            Some(world) => world.update_of(frame)?,
            None => None,
        };
        if let Some(shadows) = self.shadows.cameras.iter().find(|c| c.camera == view) {
            stats.shadow_cascades = self.completed_shadow_stats(&shadows.sun.views, frame)?;
            stats.shadow_faces = self.completed_shadow_stats(&shadows.local.views, frame)?;
        }
        Ok(stats)
    }

    /// What the shadow views `views` drew in `frame`, for those that drew.
    fn completed_shadow_stats(&self, views: &[ViewId], frame: u64) -> Result<Vec<ShadowViewStats>> {
        let mut drawn = Vec::new();
        for (index, &id) in views.iter().enumerate() {
            let Some((runtime, local)) = self.view_state(id)?.graphs.runtime_of(frame) else { continue };
            // Without a cull pass every instance is drawn.
            let instances = self.world.as_ref().map_or(self.gpu_scene.instance_count, |w| w.instances());
            let mut counts = FrameStats { drawn: instances, triangles: self.gpu_scene.triangles, ..Default::default() };
            counts.add_counters(runtime.counter_entries(local)?);
            drawn.push(ShadowViewStats {
                index: index as u32,
                frustum_culled: counts.frustum_culled,
                occlusion_culled: counts.occlusion_culled,
                drawn: counts.drawn,
                triangles: counts.triangles,
                gpu_ms: runtime.timings(local)?.into_iter().filter(|t| t.name != "frame").collect(),
            });
        }
        Ok(drawn)
    }
}
