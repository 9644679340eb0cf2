//! A view of the renderer's world: its own camera, output size, graph instance and culling
//! history, over the scene buffers every view shares.

use super::adapt::Adaptations;
use super::graphs::Graphs;
use super::shadows::ViewShadowData;
use crate::error::{Error, Result};
use crate::gpu::{Access, Image};
use crate::graph::{CompiledGraph, GraphRuntime, Imports};
use crate::passes::shared::gpu_types::{FrameConstants, GpuPointLight};
use crate::passes::shared::SceneInputs;
use crate::render::RenderSettings;
use crate::scene::{Camera, Scene};

/// Names a view of a [`super::Renderer`]. Ids are never given out twice: a removed view's id
/// stays refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ViewId(pub(super) u32);

impl ViewId {
    /// The view a renderer is made with.
    pub const MAIN: ViewId = ViewId(0);

    /// The number of the view: 0 for the first, counting every view ever added.
    pub fn number(self) -> u32 {
        self.0
    }
}

impl ViewId {
    /// `e`, naming this view.
    pub(super) fn error(self, e: Error) -> Error {
        match e {
            Error::View { .. } => e,
            e => Error::View { view: self.0, source: Box::new(e) },
        }
    }
}

impl std::fmt::Display for ViewId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "view {}", self.0)
    }
}

/// One view's camera and host resources for a frame of [`super::Renderer::record_views`].
#[derive(Clone, Copy)]
pub struct ViewFrame<'a> {
    /// The view.
    pub view: ViewId,
    /// Its camera this frame.
    pub camera: &'a Camera,
    /// The host resources its graph imports.
    pub imports: &'a Imports,
}

impl<'a> ViewFrame<'a> {
    /// `view` seen by `camera`, importing nothing.
    pub fn new(view: ViewId, camera: &'a Camera) -> Self {
        static NONE: std::sync::OnceLock<Imports> = std::sync::OnceLock::new();
        Self { view, camera, imports: NONE.get_or_init(Imports::new) }
    }
}

/// What a view is to its renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ViewRole {
    /// A camera the host adds and lists in its frames.
    Camera,
    /// A sun cascade or a light's face of a camera view's shadows: the renderer adds it to the
    /// frames that list that camera view and need its map drawn (`shadows/`, whose
    /// `CameraShadows` say which camera view and layer it draws); the host never sees its id.
    Shadow,
}

/// A view's state.
pub(super) struct View {
    pub id: ViewId,
    /// Output size.
    pub settings: RenderSettings,
    /// The graph it runs, and the ones a reload or resize replaced.
    pub graphs: Graphs,
    /// The shared scene and this view's per-frame buffers.
    pub inputs: SceneInputs,
    /// The camera of the last frame it recorded.
    pub previous_camera: Option<Camera>,
    /// Its kinds' adaptation policies, when enabled.
    pub adaptations: Option<Adaptations>,
    /// A camera or a shadow cascade.
    pub role: ViewRole,
}

impl View {
    /// The compiled graph being executed.
    pub fn plan(&self) -> &CompiledGraph {
        self.graphs.runtime.plan()
    }

    /// The running graph's runtime.
    pub fn runtime(&self) -> &GraphRuntime {
        &self.graphs.runtime
    }

    /// The graph's first output image as the last recorded frame left it.
    pub fn output(&self) -> Option<(&Image, Access)> {
        self.graphs.runtime.output_image(0)
    }

    /// Writes frame `frame`'s constants and eye-relative lights for `camera`, with the shadows
    /// `shadows` says.
    pub fn write_frame_data(
        &mut self,
        scene: &Scene,
        frame: u64,
        camera: &Camera,
        shadows: &ViewShadowData,
        levels_for: Option<(&Camera, u32, u32)>,
    ) -> Result<()> {
        let previous = self.previous_camera.as_ref().unwrap_or(camera);
        let mut constants = FrameConstants::new(scene, camera, previous, self.settings.width, self.settings.height);
        if let Some((lod_camera, width, height)) = levels_for {
            constants.choose_levels_for(camera.eye, lod_camera, width, height);
        }
        constants.sun_shadows = shadows.sun;
        constants.local_shadows = shadows.local;
        let mut lights: Vec<GpuPointLight> = scene.lights.iter().map(|l| GpuPointLight::new(l, camera.eye)).collect();
        for (light, &shadow) in lights.iter_mut().zip(&shadows.lights) {
            light.shadow = shadow;
        }
        let slot = self.inputs.slot_mut(frame);
        slot.write_constants(&constants)?;
        if !lights.is_empty() {
            slot.lights.write_bytes(0, bytemuck::cast_slice(&lights))?;
        }
        Ok(())
    }

    /// `e`, naming this view.
    pub fn error(&self, e: Error) -> Error {
        self.id.error(e)
    }
}
