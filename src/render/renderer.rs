//! The renderer: owns the scene on the GPU and a render graph's runtime, and records a frame
//! either into its own command buffer (headless) or into a host engine's.
//!
//! Every pass is a node of the graph (`graph/default.ron` unless told otherwise); the renderer
//! only provides what all passes share: scene buffers, per-frame constants and lights.

use super::graph_spec::GraphSpec;
use super::observer::FrameObserver;
#[cfg(feature = "images")]
use super::output::{rgba_from_bytes, RgbaImage};
use crate::error::{Error, Result};
use crate::gpu::{Access, Buffer, GpuContext, Image, ShaderCompiler, UploadBatch};
use crate::graph::{CompiledGraph, FrameInputs, GraphRuntime, Imports, FRAMES_IN_FLIGHT};
use crate::passes::shared::{frame_inputs, GpuScene, SceneInputs};
use crate::scene::{Camera, Scene};
use crate::stats::FrameStats;
use ash::vk;
use graphs::{build_runtime, Graphs};
use std::sync::Arc;
use view::{View, ViewRole};

mod adapt;
mod completed;
mod deform;
mod graphs;
mod lockstep;
mod readback;
mod shadows;
mod update_ring;
mod view;
mod views;
mod world_sync;

pub use shadows::{ShadowSettings, MAX_SHADOWED_LIGHTS};
pub use view::{ViewFrame, ViewId};
pub use views::MAX_VIEWS;

/// The name under which a graph imports the world's user data
/// ([`crate::scene::world::World::with_user_data`]): `Imported(Buffer(size: ...))` resource
/// `user_data` is bound to the renderer's [`GpuScene::user_data`] (words per slot, in slot
/// order) unless the host provides a buffer of that name.
pub const USER_DATA_IMPORT: &str = "user_data";

pub use super::drawn::DrawnInstances;
pub use readback::OutputF32;

/// How [`Renderer::set_graph_params`] applied a change of params.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamsApplied {
    /// Only settings the passes take live changed: nothing was made again.
    Live,
    /// Something else changed (a shader variant, a size): the graph was rebuilt.
    Rebuilt,
}

/// Output size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
}

impl RenderSettings {
    /// `width` x `height`.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height }
    }

    fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::Invalid(format!("output size {}x{} is empty", self.width, self.height)));
        }
        Ok(())
    }
}

/// Scene uploads waiting for the next frame, and those recorded into recent frames (kept until
/// those frames have executed).
#[derive(Default)]
struct Uploads {
    pending: Option<UploadBatch>,
    recorded: Vec<(u64, UploadBatch)>,
}

/// What recent frames may still be using after it was replaced or removed, with the last frame
/// that could use it: kept until that frame has executed.
#[derive(Default)]
struct Retired {
    inputs: Vec<(u64, SceneInputs)>,
    views: Vec<(u64, View)>,
    shadow_maps: Vec<(u64, crate::gpu::DepthArray)>,
}

impl Retired {
    /// Drops what only frames before `frame - FRAMES_IN_FLIGHT + 1` used (they have executed
    /// once `frame` is recorded).
    fn recorded(&mut self, frame: u64) {
        let in_flight = FRAMES_IN_FLIGHT as u64;
        self.inputs.retain(|(last, _)| frame < last + in_flight);
        self.views.retain(|(last, _)| frame < last + in_flight);
        self.shadow_maps.retain(|(last, _)| frame < last + in_flight);
    }
}

/// Renders a world through one or more views.
///
/// The renderer holds the world's GPU state (scene, instances, meshes, materials, textures,
/// lights), uploaded once, and any number of views over it ([`ViewId`]). Each view has its own
/// camera, output size, graph and culling history; views can be added
/// ([`Renderer::add_view`]), resized ([`Renderer::resize_view`]) and removed
/// ([`Renderer::remove_view`]) between any two frames without disturbing the others. A renderer
/// is made with one view, [`ViewId::MAIN`], which the single-camera methods
/// ([`Renderer::record`], [`Renderer::render`], [`Renderer::plan`], ...) address.
pub struct Renderer {
    ctx: GpuContext,
    /// The scene as the GPU holds it: the caller's own, shared, for a scene rendered as it is;
    /// the renderer's copy of a world in slot order ([`Renderer::from_world`]).
    scene: Arc<Scene>,
    /// The scene on the GPU, shared by every view.
    gpu_scene: Arc<GpuScene>,
    /// Point lights each view's per-frame light buffers hold.
    light_capacity: usize,
    uploads: Uploads,
    retired: Retired,
    /// The views, in the order they were added.
    views: Vec<View>,
    /// The number the next added view gets.
    next_view: u32,
    /// Whether passes that can be recorded together for several views are ([`Renderer::set_views_culled_together`]).
    cull_together: bool,
    frame_index: u64,
    /// What looks at each headless frame of the main view once it has completed.
    observers: Vec<Box<dyn FrameObserver>>,
    /// The world this renderer mirrors, when made from one ([`Renderer::from_world`]).
    world: Option<world_sync::WorldMirror>,
    /// The sun's shadows: settings, and each camera view's cascades and maps.
    shadows: shadows::ShadowState,
    /// Frames of several views (or with shadow views) kept to replay.
    frame_replays: Option<lockstep::FrameReplays>,
}

impl Renderer {
    /// Prepares `scene` for rendering through the default graph. Uploads are recorded into the first frame.
    ///
    /// The scene is taken by value or shared (`Arc<Scene>`): a caller that keeps its scene (for
    /// other renderers, a reference image, exact visibility) shares it, and the host then holds
    /// its instances once. The renderer never changes it.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        scene: impl Into<Arc<Scene>>,
        settings: RenderSettings,
    ) -> Result<Self> {
        Self::with_graph(ctx, shaders, scene, settings, &GraphSpec::default_graph())
    }

    /// Prepares `scene` (by value or shared, as for [`Renderer::new`]) for rendering through the
    /// graph `spec`.
    pub fn with_graph(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        scene: impl Into<Arc<Scene>>,
        settings: RenderSettings,
        spec: &GraphSpec,
    ) -> Result<Self> {
        profiling::scope!("cullgraph::Renderer::with_graph");
        let scene = scene.into();
        settings.validate()?;
        crate::scene::validate::validate_scene(&scene)?;
        let compiled = frame_inputs(&spec.kinds, &scene, settings.width, settings.height)?;
        let runtime = build_runtime(ctx, shaders, &compiled, spec)?;
        let mut uploads = UploadBatch::default();
        let gpu_scene = Arc::new(GpuScene::upload(ctx, &scene, &mut uploads)?);
        let lights = scene.lights.len();
        Self::assemble(ctx, scene, gpu_scene, lights, uploads, runtime, compiled, settings, spec)
    }

    /// A renderer of `scene` (as the GPU holds it) with its first uploads and its main view.
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        ctx: &GpuContext,
        scene: Arc<Scene>,
        gpu_scene: Arc<GpuScene>,
        light_capacity: usize,
        uploads: UploadBatch,
        runtime: GraphRuntime,
        compiled: FrameInputs,
        settings: RenderSettings,
        spec: &GraphSpec,
    ) -> Result<Self> {
        let main = View {
            id: ViewId::MAIN,
            settings,
            graphs: Graphs::new(spec, runtime, compiled),
            inputs: SceneInputs::new(ctx, gpu_scene.clone(), light_capacity)?,
            previous_camera: None,
            adaptations: None,
            role: ViewRole::Camera,
        };
        Ok(Self {
            ctx: ctx.clone(),
            scene,
            gpu_scene,
            light_capacity,
            uploads: Uploads { pending: Some(uploads), recorded: Vec::new() },
            retired: Retired::default(),
            views: vec![main],
            next_view: 1,
            cull_together: true,
            frame_index: 0,
            observers: Vec::new(),
            world: None,
            shadows: shadows::ShadowState::new(ctx)?,
            frame_replays: None,
        })
    }

    /// The main view: always the first ([`Renderer::remove_view`] refuses to remove it).
    fn main_view(&self) -> &View {
        &self.views[0]
    }

    fn main_view_mut(&mut self) -> &mut View {
        &mut self.views[0]
    }

    /// What a graph of `spec` is compiled for on this renderer's scene at `settings`.
    fn compiled_for(&mut self, spec: &GraphSpec, settings: &RenderSettings) -> Result<FrameInputs> {
        match &mut self.world {
            Some(world) => world.compiled_for(&spec.kinds, &mut self.scene, settings),
            None => frame_inputs(&spec.kinds, &self.scene, settings.width, settings.height),
        }
    }

    /// Replaces the main view's graph. On error the current graph stays in place and keeps rendering.
    pub fn reload_graph(&mut self, shaders: &ShaderCompiler, spec: &GraphSpec) -> Result<()> {
        self.reload_view_graph(shaders, ViewId::MAIN, spec).map_err(unwrap_main)
    }

    /// Replaces `view`'s graph. On error the current graph stays in place and keeps rendering.
    pub fn reload_view_graph(&mut self, shaders: &ShaderCompiler, view: ViewId, spec: &GraphSpec) -> Result<()> {
        let settings = self.view_state(view)?.settings.clone();
        let compiled = self.compiled_for(spec, &settings).map_err(|e| view.error(e))?;
        let runtime = build_runtime(&self.ctx, shaders, &compiled, spec).map_err(|e| view.error(e))?;
        let frame = self.frame_index;
        self.view_state_mut(view)?.graphs.reload(spec, runtime, compiled, frame)
    }

    /// Sets the main view's graph params (`name`, value expression), as `--param` does at load:
    /// see [`Renderer::set_view_graph_params`].
    pub fn set_graph_params(&mut self, shaders: &ShaderCompiler, params: &[(&str, &str)]) -> Result<ParamsApplied> {
        self.set_view_graph_params(shaders, ViewId::MAIN, params).map_err(unwrap_main)
    }

    /// Sets `view`'s graph params (`name`, value expression; later values of a name replace
    /// earlier ones). When only settings that the passes take live change (the exposure, the
    /// debug view), nothing is made again and the next frame records with them; otherwise the
    /// graph is rebuilt as by [`Renderer::reload_view_graph`]. On error nothing changes.
    pub fn set_view_graph_params(
        &mut self,
        shaders: &ShaderCompiler,
        view: ViewId,
        params: &[(&str, &str)],
    ) -> Result<ParamsApplied> {
        let graphs = &self.view_state(view)?.graphs;
        let mut spec = graphs.spec.clone();
        spec.overrides.retain(|(name, _)| !params.iter().any(|(p, _)| p == name));
        let spec = spec.with_overrides(params.iter().map(|(n, v)| (n.to_string(), v.to_string())));
        let plan = spec.compile_for(&self.ctx, shaders, &graphs.compiled).map_err(|e| view.error(e))?;
        let graphs = &mut self.view_state_mut(view)?.graphs;
        if graphs.runtime.update_settings(plan).map_err(|e| view.error(e))? {
            graphs.spec = spec;
            return Ok(ParamsApplied::Live);
        }
        self.reload_view_graph(shaders, view, &spec)?;
        Ok(ParamsApplied::Rebuilt)
    }

    /// Puts back the graph that the last [`Renderer::reload_graph`] replaced, as it was, when
    /// the new one has not recorded a frame: a graph that loads and compiles can still fail at
    /// its first frame (a pass refusing what is bound to it), and a hot reload then falls back to
    /// the last good graph without rebuilding it from files that may have changed meanwhile.
    pub fn revert_reload(&mut self) -> Result<()> {
        self.main_view_mut().graphs.revert()
    }

    /// Starts or stops timing the steps of multi-dispatch passes separately, in every view:
    /// each frame's [`FrameStats::gpu_ms`] then also holds `pass/step` entries (see
    /// [`GraphRuntime::set_step_timing`]).
    pub fn set_step_timing(&mut self, on: bool) {
        for view in &mut self.views {
            view.graphs.runtime.set_step_timing(on);
        }
    }

    /// Lets every view's frames replay an earlier frame's recording when nothing that decides
    /// their commands changed (on, the default; see [`GraphRuntime::record`]), or has every
    /// frame record every pass.
    pub fn set_frame_replay(&mut self, on: bool) {
        for view in &mut self.views {
            view.graphs.runtime.set_replay(on);
        }
    }

    /// Attaches `observer`: from now on it looks at every frame of every view that
    /// [`Renderer::render`] and its variants wait for.
    pub fn attach(&mut self, observer: impl FrameObserver) -> Result<()> {
        if observer.needs_draw_lists() {
            for view in &mut self.views {
                view.graphs.runtime.capture_draw_lists(true)?;
            }
        }
        self.observers.push(Box::new(observer));
        Ok(())
    }

    /// The attached observer of type `T`, if any.
    pub fn observer<T: FrameObserver>(&self) -> Option<&T> {
        self.observers.iter().find_map(|o| (&**o as &dyn std::any::Any).downcast_ref::<T>())
    }

    /// Frames recorded so far (the index the next one gets).
    pub fn frames_recorded(&self) -> u64 {
        self.frame_index
    }

    /// The scene being rendered. For a renderer of a world ([`Renderer::from_world`]): its
    /// slots, empty ones included, each with its instance's mesh, material and flags, but with
    /// the transform it had when it was last written whole: moves are applied to the GPU only.
    /// The world's current state is [`crate::scene::world::World::live_scene`].
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// [`Renderer::scene`], shared: what a caller keeps instead of a copy (for a reference
    /// image or exact visibility after the renderer is gone). A world renderer's copy stays its
    /// own: a sync that changes more than transforms, or a graph reload, copies it first while
    /// it is shared.
    pub fn shared_scene(&self) -> Arc<Scene> {
        self.scene.clone()
    }

    /// The main view's output size.
    pub fn settings(&self) -> &RenderSettings {
        &self.main_view().settings
    }

    /// The main view's compiled graph.
    pub fn plan(&self) -> &CompiledGraph {
        self.main_view().plan()
    }

    /// What the main view's graph is compiled for: its size and the scene's quantities (with
    /// the room a world keeps to grow).
    pub fn plan_inputs(&self) -> &FrameInputs {
        &self.main_view().graphs.compiled
    }

    /// The main view's graph runtime (resources, memory, timings).
    pub fn runtime(&self) -> &GraphRuntime {
        self.main_view().runtime()
    }

    /// Starts or stops copying every view's draw lists to the host each frame, for
    /// [`Renderer::drawn`], [`Renderer::drawn_in_view`] and [`Renderer::drawn_handles`] (the
    /// visible set an engine reads back, with or without the `verify` feature). An attached
    /// observer that needs the lists keeps them on.
    pub fn capture_draw_lists(&mut self, on: bool) -> Result<()> {
        let on = on || self.observers.iter().any(|o| o.needs_draw_lists());
        for view in &mut self.views {
            view.graphs.runtime.capture_draw_lists(on)?;
        }
        Ok(())
    }

    /// What each drawing pass of the main view drew in the last completed frame, in pass order
    /// (`None` unless draw lists are captured: [`Renderer::capture_draw_lists`], or an
    /// attached observer that needs them, [`FrameObserver::needs_draw_lists`]).
    pub fn drawn(&self) -> Result<Option<Vec<DrawnInstances>>> {
        self.drawn_in_view(ViewId::MAIN)
    }

    /// The main view's constants as frame `frame` was given them
    /// ([`crate::passes::shared::gpu_types::FrameConstants`]), once it
    /// has completed (the buffer is reused `FRAMES_IN_FLIGHT` frames later).
    pub fn frame_constants_of(&self, frame: u64) -> &Buffer {
        &self.main_view().inputs.slot(frame).constants
    }

    /// The GPU device.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The scene as the GPU holds it (buffers of instances, cull bounds, draw lists), shared by
    /// every view, for an engine's own passes and for checks.
    pub fn gpu_scene(&self) -> &GpuScene {
        &self.gpu_scene
    }

    /// The main view's first output image as left by the last recorded frame, and the access it
    /// was last used with. `None` before the first frame or when the first output is a buffer.
    pub fn output(&self) -> Option<(&Image, Access)> {
        self.main_view().output()
    }

    /// Records one frame of the main view into `cmd` (which must be recording) for `camera`;
    /// returns its index.
    ///
    /// This is the embedding entry point: nothing is submitted. At most [`FRAMES_IN_FLIGHT`]
    /// recorded frames may be executing at once.
    pub fn record(&mut self, cmd: vk::CommandBuffer, camera: &Camera) -> Result<u64> {
        self.record_with_imports(cmd, camera, &Imports::new())
    }

    /// Like [`Renderer::record`], with the host resources the graph imports (e.g. the engine's
    /// back buffer as the lighting output).
    pub fn record_with_imports(&mut self, cmd: vk::CommandBuffer, camera: &Camera, imports: &Imports) -> Result<u64> {
        self.record_views(cmd, &[ViewFrame { view: ViewId::MAIN, camera, imports }]).map_err(unwrap_main)
    }

    /// Records one frame of the world into `cmd` (which must be recording): the world's
    /// uploads and updates once, then each listed view's graph with its camera, in the order
    /// given. Views not listed keep their state and history for a later frame. Returns the
    /// frame's index.
    ///
    /// Before anything is recorded every view and camera is checked: an unknown or removed
    /// view, a view listed twice or an unusable camera is an error naming the view, and the
    /// frame is not consumed.
    pub fn record_views(&mut self, cmd: vk::CommandBuffer, views: &[ViewFrame<'_>]) -> Result<u64> {
        profiling::scope!("cullgraph::Renderer::record");
        if views.is_empty() {
            return Err(Error::Invalid("a frame must render at least one view".into()));
        }
        let mut order = Vec::with_capacity(views.len());
        for (i, frame_view) in views.iter().enumerate() {
            let at = self.view_index(frame_view.view)?;
            if self.views[at].role != ViewRole::Camera {
                return Err(frame_view.view.error(Error::Invalid("this view does not exist".into())));
            }
            if views[..i].iter().any(|earlier| earlier.view == frame_view.view) {
                return Err(frame_view.view.error(Error::Invalid("listed twice in one frame".into())));
            }
            frame_view.camera.validate().map_err(|e| frame_view.view.error(Error::Invalid(format!("camera: {e}"))))?;
            order.push(at);
        }
        // Before the views' frame data is written: it may give every view new scene inputs.
        self.fit_previous_records()?;
        let frame = self.frame_index;
        let cameras: Vec<(ViewId, &Camera)> = views.iter().map(|fv| (fv.view, fv.camera)).collect();
        let (cascades, shadow_data) = self.plan_shadow_frame(cmd, &cameras)?;
        for ((&at, frame_view), shadows) in order.iter().zip(views).zip(&shadow_data) {
            self.views[at].write_frame_data(&self.scene, frame, frame_view.camera, shadows, None)?;
        }
        let mut cascade_order = Vec::with_capacity(cascades.len());
        for cascade in &cascades {
            let at = self.view_index(cascade.view)?;
            // A caster takes the level of detail its camera view takes (a shadow graph choosing
            // levels: `ShadowSettings::lod_threshold`).
            let of = self.view_index(cascade.of)?;
            let of_camera = views.iter().find(|v| v.view == cascade.of).map(|v| v.camera);
            let (width, height) = (self.views[of].settings.width, self.views[of].settings.height);
            let levels_for = of_camera.map(|c| (c, width, height));
            self.views[at].write_frame_data(&self.scene, frame, &cascade.camera, &Default::default(), levels_for)?;
            cascade_order.push(at);
        }
        match &mut self.world {
            Some(world) => {
                self.ctx.begin_label(cmd, "update scene");
                world.record_updates(&self.ctx, cmd, frame, &self.gpu_scene, self.uploads.pending.as_ref())?;
                self.ctx.end_label(cmd);
            }
            None => {
                if let Some(batch) = &self.uploads.pending {
                    self.ctx.begin_label(cmd, "upload scene");
                    batch.record(&self.ctx, cmd);
                    self.ctx.end_label(cmd);
                }
            }
        }
        // The scene's user data is every graph's to import as `user_data`, unless the host
        // gives a buffer of that name itself.
        let with_user_data: Vec<Option<Imports>> = views
            .iter()
            .map(|fv| {
                let data = self.gpu_scene.user_data.as_ref()?;
                if fv.imports.get(USER_DATA_IMPORT).is_some() {
                    return None;
                }
                let read = Access {
                    stage: vk::PipelineStageFlags2::ALL_COMMANDS,
                    access: vk::AccessFlags2::SHADER_STORAGE_READ,
                    layout: vk::ImageLayout::UNDEFINED,
                };
                Some(fv.imports.clone().buffer(USER_DATA_IMPORT, data.handle(), data.size(), read, read))
            })
            .collect();
        // The cascades first: each camera view's lighting waits for its own.
        let mut slots: Vec<Option<&mut View>> = self.views.iter_mut().map(Some).collect();
        let mut listed = Vec::with_capacity(cascades.len() + views.len());
        for (&at, cascade) in cascade_order.iter().zip(&cascades) {
            let view = slots[at].take().expect("each cascade listed once");
            let mut part = lockstep::FramePart::new(view, &cascade.camera, &cascade.imports);
            // Its map's layer, which the shadow state's array id tells apart from earlier ones.
            part.import_key = Some(cascade.maps);
            listed.push(part);
        }
        for ((&at, fv), merged) in order.iter().zip(views).zip(&with_user_data) {
            let view = slots[at].take().expect("each view listed once");
            let mut part = lockstep::FramePart::new(view, fv.camera, merged.as_ref().unwrap_or(fv.imports));
            // The renderer's own imports, or the host's where it vouches for its images.
            part.import_key = match fv.imports.names().next() {
                None => Some(0),
                Some(_) => fv.imports.generation(),
            };
            part.waits_for = cascades.iter().enumerate().filter(|(_, c)| c.of == fv.view).map(|(i, _)| i).collect();
            listed.push(part);
        }
        lockstep::record(&self.ctx, cmd, frame, listed, self.cull_together, &mut self.frame_replays)?;
        self.shadow_frame_recorded(cascades);

        // Uploads and replaced state recorded FRAMES_IN_FLIGHT frames ago have executed by now.
        let in_flight = FRAMES_IN_FLIGHT as u64;
        self.uploads.recorded.retain(|(f, _)| frame < f + in_flight);
        self.retired.recorded(frame);
        if let Some(world) = &mut self.world {
            world.recorded(frame);
        }
        if let Some(batch) = self.uploads.pending.take() {
            self.uploads.recorded.push((frame, batch));
        }
        self.frame_index += 1;
        Ok(frame)
    }

    /// Renders one frame of the main view headlessly (own command buffer, submit, wait) and
    /// returns its stats.
    pub fn render(&mut self, camera: &Camera) -> Result<FrameStats> {
        let mut frames = self.render_views(&[(ViewId::MAIN, camera)]).map_err(unwrap_main)?;
        Ok(frames.remove(0))
    }

    /// Renders one frame headlessly and reads the main view's first output back as an image.
    #[cfg(feature = "images")]
    pub fn render_to_image(&mut self, camera: &Camera) -> Result<(FrameStats, RgbaImage)> {
        let (stats, bytes) = self.render_to_rgba8(camera)?;
        let settings = self.settings();
        Ok((stats, rgba_from_bytes(settings.width, settings.height, bytes)?))
    }

    /// Renders one frame headlessly and reads the main view's first output (an
    /// `R8G8B8A8_UNORM` image of the output size) back: tightly packed rows, top to bottom.
    pub fn render_to_rgba8(&mut self, camera: &Camera) -> Result<(FrameStats, Vec<u8>)> {
        let mut frames = self.render_views_to_rgba8(&[(ViewId::MAIN, camera)]).map_err(unwrap_main)?;
        Ok(frames.remove(0))
    }
}

/// An error of the main view as a single-view renderer reports it: without naming the view.
fn unwrap_main(e: Error) -> Error {
    match e {
        Error::View { view: 0, source } => *source,
        e => e,
    }
}

/// An engine records on its render thread: a renderer moves there whole.
const _: () = {
    const fn assert_send<T: Send>() {}
    assert_send::<Renderer>();
};
