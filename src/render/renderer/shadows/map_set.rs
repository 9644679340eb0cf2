//! A set of shadow views that each draw one layer of a shadow-map array, and what each layer
//! was last drawn for (so that an unchanged map is kept).

use super::super::view::ViewId;
use super::frame::ShadowViewFrame;
use crate::gpu::{Access, DepthArray, GpuContext};
use crate::graph::Imports;
use crate::scene::Camera;
use ash::vk;

/// Where a view's graph reads the maps once they are drawn: the lighting in compute, the
/// transparent surfaces in fragment shaders.
pub(super) const SAMPLED: Access = Access {
    stage: vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw(),
    ),
    access: vk::AccessFlags2::SHADER_SAMPLED_READ,
    layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
};

/// Views that each draw one layer of a shadow-map array.
pub(in crate::render::renderer) struct MapSet {
    /// The views, layer by layer.
    pub views: Vec<ViewId>,
    /// One layer per view.
    pub maps: DepthArray,
    /// Whether a recorded frame has put every layer in the sampled layout (a frame whose
    /// recording fails is discarded, so until one is recorded each frame does it again).
    pub ready: bool,
    /// What each layer was last drawn for (`None`: never drawn).
    pub drawn_for: Vec<Option<MapKey>>,
}

impl MapSet {
    /// The frame of layer `layer` seen by `camera`, unless it holds what it would draw.
    pub(super) fn frame(
        &self,
        layer: usize,
        camera: &Camera,
        key: MapKey,
        of: ViewId,
        keep: bool,
    ) -> Option<ShadowViewFrame> {
        if keep && self.drawn_for[layer].as_ref() == Some(&key) {
            return None;
        }
        // Every layer is in the sampled layout: since the last frame's reads, or since this
        // frame's start (`MapSet::make_ready`).
        let imports = Imports::new().image("depth", self.maps.layer(layer as u32), SAMPLED, SAMPLED);
        Some(ShadowViewFrame {
            view: self.views[layer],
            camera: camera.clone(),
            imports,
            of,
            key,
            maps: self.maps.id(),
        })
    }

    /// Notes that `frame`, one of these views, was recorded.
    pub(super) fn recorded(&mut self, frame: &ShadowViewFrame) -> bool {
        let Some(layer) = self.views.iter().position(|&v| v == frame.view) else { return false };
        self.drawn_for[layer] = Some(frame.key.clone());
        true
    }

    /// Puts every layer in the sampled layout, unless a recorded frame did (the layers no
    /// light has taken yet are bound too). Their contents are undefined until drawn.
    pub(super) fn make_ready(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        if !self.ready {
            transition_to_sampled(ctx, cmd, &self.maps);
        }
    }
}

/// What a cascade's map depends on: its camera, the sun, and the world's version (any change of
/// a world counts, which is conservative: a change the cascade cannot see redraws it too).
/// Casters that take their camera view's levels of detail keep, in a kept map, the levels of
/// the frame it was drawn in: drawing every light's faces again whenever the camera moves would
/// cost more than the levels save.
#[derive(Clone, Debug, PartialEq)]
pub(in crate::render::renderer) struct MapKey {
    pub camera: Camera,
    pub sun: glam::Vec3,
    pub world_version: Option<u64>,
}

/// Records the move of every layer of `maps` from undefined contents to the sampled layout.
pub(super) fn transition_to_sampled(ctx: &GpuContext, cmd: vk::CommandBuffer, maps: &DepthArray) {
    let barriers = [crate::gpu::barrier::image_barrier_raw(maps.handle(), maps.range(), Access::NONE, SAMPLED)];
    // SAFETY: `cmd` is recording; the image is ours, and no recorded frame has used it yet.
    unsafe { ctx.device().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers)) };
}
