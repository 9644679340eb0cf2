//! A renderer's views: adding, resizing and removing them, rendering several in one frame,
//! and reading each one's figures and images.

use super::graphs::{build_runtime, Graphs};
use super::view::{View, ViewFrame, ViewId, ViewRole};
use super::{DrawnInstances, Renderer};
use crate::error::{Error, Result};
use crate::gpu::transfer::record_image_to_buffer;
use crate::gpu::{Access, Buffer, BufferDesc, Image, MemoryLocation, ShaderCompiler};
use crate::graph::{CompiledGraph, FrameInputs, GraphRuntime};
use crate::passes::shared::SceneInputs;
use crate::render::{GraphSpec, RenderSettings};
use crate::scene::Camera;
use crate::stats::FrameStats;
use ash::vk;
use std::time::Instant;

/// The most views a renderer holds at once. Each view costs its own graph resources (targets,
/// pyramids, culling history) and per-frame constants, never a copy of the scene.
pub const MAX_VIEWS: usize = 64;

impl Renderer {
    /// Where `view` is in the list, or an error naming it when it is unknown or was removed.
    pub(super) fn view_index(&self, view: ViewId) -> Result<usize> {
        self.views.iter().position(|v| v.id == view).ok_or_else(|| {
            let why = if view.0 < self.next_view { "was removed" } else { "does not exist" };
            view.error(Error::Invalid(format!("this view {why}")))
        })
    }

    pub(super) fn view_state(&self, view: ViewId) -> Result<&View> {
        Ok(&self.views[self.view_index(view)?])
    }

    pub(super) fn view_state_mut(&mut self, view: ViewId) -> Result<&mut View> {
        let at = self.view_index(view)?;
        Ok(&mut self.views[at])
    }

    /// Adds a view of `settings`' size running the graph `spec`, with a culling history of its
    /// own (its first frame tests everything, as a new renderer's does). The scene is not
    /// uploaded again: every view reads the same buffers.
    pub fn add_view(&mut self, shaders: &ShaderCompiler, settings: RenderSettings, spec: &GraphSpec) -> Result<ViewId> {
        profiling::scope!("cullgraph::Renderer::add_view");
        let id = ViewId(self.next_view);
        if self.camera_views().count() >= MAX_VIEWS {
            return Err(id.error(Error::Invalid(format!("a renderer holds at most {MAX_VIEWS} views"))));
        }
        settings.validate().map_err(|e| id.error(e))?;
        let compiled = self.compiled_for(spec, &settings).map_err(|e| id.error(e))?;
        let runtime = build_runtime(&self.ctx, shaders, &compiled, spec).map_err(|e| id.error(e))?;
        let mut graphs = Graphs::new(spec, runtime, compiled);
        let main = &self.views[0].graphs.runtime;
        graphs.runtime.set_step_timing(main.step_timing());
        graphs.runtime.capture_draw_lists(main.captures_draw_lists()).map_err(|e| id.error(e))?;
        let inputs = SceneInputs::new(&self.ctx, self.gpu_scene.clone(), self.light_capacity)?;
        self.views.push(View {
            id,
            settings,
            graphs,
            inputs,
            previous_camera: None,
            adaptations: None,
            role: ViewRole::Camera,
        });
        self.next_view += 1;
        if let Err(e) = self.add_camera_shadows(shaders, id) {
            let at = self.views.len() - 1;
            self.views.remove(at);
            return Err(id.error(e));
        }
        Ok(id)
    }

    /// Removes `view`. Its resources stay alive until the frames that used it have executed;
    /// the other views are not touched. The main view cannot be removed.
    pub fn remove_view(&mut self, view: ViewId) -> Result<()> {
        let at = self.view_index(view)?;
        if view == ViewId::MAIN {
            return Err(view.error(Error::Invalid("the main view cannot be removed".into())));
        }
        let removed = self.views.remove(at);
        self.retired.views.push((self.frame_index.saturating_sub(1), removed));
        self.remove_camera_shadows(view);
        Ok(())
    }

    /// Whether the views of a frame are culled together (the default): the instance-cull passes
    /// of views running the same pass with the same settings test every view in one dispatch
    /// per phase, reading each instance once (at most 16 views per dispatch; where the device
    /// gives buffers no addresses, one dispatch per view). Off, each view culls in dispatches of
    /// its own, as a renderer per view would; the images and figures are the same either way.
    pub fn set_views_culled_together(&mut self, on: bool) {
        self.cull_together = on;
    }

    /// The views, main first, in the order they were added.
    pub fn views(&self) -> impl Iterator<Item = ViewId> + '_ {
        self.camera_views()
    }

    /// Changes the main view's output size; see [`Renderer::resize_view`].
    pub fn resize(&mut self, shaders: &ShaderCompiler, width: u32, height: u32) -> Result<()> {
        self.resize_view(shaders, ViewId::MAIN, width, height).map_err(super::unwrap_main)
    }

    /// Changes `view`'s output size from the next frame on. Only what depends on the size is
    /// made again (the view's graph resources); the scene, the other views and the frames in
    /// flight are not touched.
    ///
    /// The culling history follows this rule: what is kept per instance (last frame's
    /// visibility and the lists drawn from it) carries over, because the instances are the same;
    /// what is kept per pixel (a depth pyramid carried to the next frame) starts cleared, as in
    /// a first frame, where it hides nothing. The frame after a resize therefore culls no
    /// visible instance, and its image is the image of a view created at that size.
    pub fn resize_view(&mut self, shaders: &ShaderCompiler, view: ViewId, width: u32, height: u32) -> Result<()> {
        profiling::scope!("cullgraph::Renderer::resize_view");
        let settings = RenderSettings::new(width, height);
        settings.validate().map_err(|e| view.error(e))?;
        let state = self.view_state(view)?;
        if state.settings == settings {
            return Ok(());
        }
        let spec = state.graphs.spec.clone();
        // The scene's quantities are what the running graph was compiled for: only the size
        // changes (counting them again walks every instance).
        let compiled = FrameInputs { width, height, ..state.graphs.compiled.clone() };
        let mut runtime = build_runtime(&self.ctx, shaders, &compiled, &spec).map_err(|e| view.error(e))?;
        let frame = self.frame_index;
        let state = self.view_state_mut(view)?;
        runtime.inherit_history(&state.graphs.runtime);
        state.graphs.install(runtime, compiled, frame)?;
        state.settings = settings;
        Ok(())
    }

    /// `view`'s output size.
    pub fn view_settings(&self, view: ViewId) -> Result<&RenderSettings> {
        Ok(&self.view_state(view)?.settings)
    }

    /// `view`'s compiled graph.
    pub fn view_plan(&self, view: ViewId) -> Result<&CompiledGraph> {
        Ok(self.view_state(view)?.plan())
    }

    /// `view`'s graph runtime (resources, memory, timings).
    pub fn view_runtime(&self, view: ViewId) -> Result<&GraphRuntime> {
        Ok(self.view_state(view)?.runtime())
    }

    /// `view`'s first output image as its last recorded frame left it, and the access it was
    /// last used with.
    pub fn view_output(&self, view: ViewId) -> Result<Option<(&Image, Access)>> {
        Ok(self.view_state(view)?.output())
    }

    /// What each drawing pass of `view` drew in its last completed frame, in pass order
    /// (`None` unless an attached observer asked for the draw lists,
    /// [`crate::render::FrameObserver::needs_draw_lists`]).
    pub fn drawn_in_view(&self, view: ViewId) -> Result<Option<Vec<DrawnInstances>>> {
        let state = self.view_state(view)?;
        let Some(captured) = state.graphs.runtime.captured()? else { return Ok(None) };
        Ok(Some(crate::render::drawn::drawn(state.plan(), &self.gpu_scene, captured)))
    }

    /// The clusters `view`'s last completed frame drew through cluster lists, as (instance id,
    /// first index of the cluster's range); `None` unless draw lists are captured.
    #[cfg(feature = "verify")]
    pub(crate) fn drawn_clusters_in_view(&self, view: ViewId) -> Result<Option<Vec<(u32, u32)>>> {
        let state = self.view_state(view)?;
        let Some(captured) = state.graphs.runtime.captured()? else { return Ok(None) };
        Ok(Some(crate::render::drawn::drawn_clusters(&captured)))
    }

    /// `view`'s constants as frame `frame` was given them, once it has completed.
    pub fn view_frame_constants_of(&self, view: ViewId, frame: u64) -> Result<&Buffer> {
        Ok(&self.view_state(view)?.inputs.slot(frame).constants)
    }

    /// Renders one frame of several views headlessly (own command buffer, submit, wait) and
    /// returns each view's stats, in the order given.
    pub fn render_views(&mut self, views: &[(ViewId, &Camera)]) -> Result<Vec<FrameStats>> {
        Ok(self.render_views_inner(views, false)?.into_iter().map(|(stats, _)| stats).collect())
    }

    /// Renders one frame of several views headlessly and reads each one's first output (an
    /// `R8G8B8A8_UNORM` image of its size) back: tightly packed rows, top to bottom.
    pub fn render_views_to_rgba8(&mut self, views: &[(ViewId, &Camera)]) -> Result<Vec<(FrameStats, Vec<u8>)>> {
        self.render_views_inner(views, true)
    }

    fn render_views_inner(&mut self, views: &[(ViewId, &Camera)], read: bool) -> Result<Vec<(FrameStats, Vec<u8>)>> {
        let mut readbacks = Vec::new();
        if read {
            for &(view, _) in views {
                self.readback_error(view)?;
                let settings = self.view_settings(view)?;
                readbacks.push(Buffer::new(
                    &self.ctx,
                    &BufferDesc {
                        name: "output readback",
                        size: settings.width as u64 * settings.height as u64 * 4,
                        usage: vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuToCpu,
                    },
                )?);
            }
        }
        let frames: Vec<ViewFrame<'_>> = views.iter().map(|&(view, camera)| ViewFrame::new(view, camera)).collect();
        let ctx = self.ctx.clone();
        let mut frame = 0;
        let mut record_ms = 0.0;
        ctx.submit_and_wait(|cmd| {
            let start = Instant::now();
            frame = self.record_views(cmd, &frames)?;
            record_ms = start.elapsed().as_secs_f64() * 1e3;
            for (&(view, _), dst) in views.iter().zip(&readbacks) {
                self.record_readback(cmd, view, dst)?;
            }
            Ok::<(), Error>(())
        })?;
        let mut results = Vec::with_capacity(views.len());
        for (i, &(view, _)) in views.iter().enumerate() {
            let mut stats = self.completed_view_stats(view, frame)?;
            stats.cpu_record_ms = record_ms;
            let mut observers = std::mem::take(&mut self.observers);
            let looked = observers.iter_mut().try_for_each(|o| o.completed(self, view, frame, &mut stats));
            self.observers = observers;
            looked.map_err(|e| view.error(e))?;
            let bytes = match readbacks.get(i) {
                Some(buffer) => buffer.read_bytes()?.to_vec(),
                None => Vec::new(),
            };
            results.push((stats, bytes));
        }
        Ok(results)
    }

    /// Copies `view`'s first output into `dst` after the frame just recorded.
    pub(super) fn record_readback(&mut self, cmd: vk::CommandBuffer, view: ViewId, dst: &Buffer) -> Result<()> {
        let ctx = self.ctx.clone();
        let state = self.view_state_mut(view)?;
        let (image, access) = state
            .output()
            .ok_or_else(|| view.error(Error::Invalid("the graph's first output is not an image".into())))?;
        record_image_to_buffer(&ctx, cmd, image, access, dst);
        state.graphs.runtime.note_output_use(0, Access { layout: access.layout, ..Access::TRANSFER_READ });
        Ok(())
    }

    /// Why `view`'s first output cannot be read back as 8-bit RGBA of its size, at its
    /// declaration.
    pub(super) fn readback_error(&self, view: ViewId) -> Result<()> {
        let state = self.view_state(view)?;
        let plan = state.plan();
        let named = |e: Error| view.error(e);
        crate::render::graph_spec::shown_image_error(plan, state.settings.width, state.settings.height)
            .map_err(|e| named(e.into()))?;
        let Some(&first) = plan.outputs.first() else {
            return Err(named(Error::Invalid("the graph has no output to read back".into())));
        };
        match plan.resources[first].kind {
            crate::graph::ResolvedKind::Image { format: vk::Format::R8G8B8A8_UNORM, .. } => Ok(()),
            _ => Err(named(plan.error_at(
                first,
                Error::Invalid("must be an R8G8B8A8_UNORM image to be read back as 8-bit RGBA".into()),
            ))),
        }
    }
}
