//! One frame's shadows: the cascades fitted to each listed camera view and the faces of its
//! most important lights, the shadow views that must draw, and what the camera views' constants
//! and lights say of them.

use super::super::view::ViewId;
use super::super::Renderer;
use super::map_set::{transition_to_sampled, MapKey};
use crate::error::Result;
use crate::graph::Imports;
use crate::passes::shared::gpu_types::{GpuLocalShadows, GpuSunShadows, NO_SHADOW};
use crate::passes::shared::ShadowMaps;
use crate::scene::cascades::{fit_cascades, CascadeSettings};
use crate::scene::light_faces::shadowed_lights;
use crate::scene::Camera;
use ash::vk;
use glam::Mat4;

/// What one camera view's frame constants and lights say of its shadows.
#[derive(Default)]
pub(in crate::render::renderer) struct ViewShadowData {
    pub sun: GpuSunShadows,
    pub local: GpuLocalShadows,
    /// Per light of the scene: its [`crate::passes::shared::gpu_types::GpuPointLight::shadow`]
    /// (empty: none casts a shadow).
    pub lights: Vec<[u32; 4]>,
}

/// One cascade's or face's part of a frame: its view, camera and the import of its layer.
pub(in crate::render::renderer) struct ShadowViewFrame {
    pub view: ViewId,
    pub camera: Camera,
    pub imports: Imports,
    /// The camera view whose lighting waits for it.
    pub of: ViewId,
    /// What its map is drawn for.
    pub key: MapKey,
    /// The id of the map array whose layer it draws ([`crate::gpu::DepthArray::id`]).
    pub maps: u64,
}

impl Renderer {
    /// This frame's shadow views of the listed camera views (`cameras`: id and camera), with
    /// what each camera view's constants and lights say of its shadows; views without shadows
    /// get none. Points every listed camera view at its maps (or the unread fallback), and
    /// makes the fallback ready until a frame that did so has been recorded.
    pub(in crate::render::renderer) fn plan_shadow_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        cameras: &[(ViewId, &Camera)],
    ) -> Result<(Vec<ShadowViewFrame>, Vec<ViewShadowData>)> {
        if !self.shadows.fallback_ready {
            transition_to_sampled(&self.ctx, cmd, &self.shadows.fallback);
        }
        let mut frames = Vec::new();
        let mut data = Vec::with_capacity(cameras.len());
        let mut made_ready = Vec::new();
        let fallback = self.shadows.fallback_maps();
        let world_version = self.synced_version();
        let keep = self.shadows.keep_unchanged;
        let sun = self.scene.sun.direction;
        for &(id, camera) in cameras {
            let at = self.view_index(id)?;
            let samples = self.views[at].graphs.runtime.first_pass_sampling_shadows().is_some();
            let shadows = self.shadows.cameras.iter_mut().find(|c| c.camera == id);
            let (Some(settings), Some(shadows), true) = (&self.shadows.settings, shadows, samples) else {
                self.views[at].inputs.set_shadow_maps(fallback);
                data.push(ViewShadowData::default());
                continue;
            };
            shadows.sun.make_ready(&self.ctx, cmd);
            shadows.local.make_ready(&self.ctx, cmd);
            made_ready.push(id);
            let mut view_data = ViewShadowData::default();
            let key = |camera: &Camera| MapKey { camera: camera.clone(), sun, world_version };
            let view_settings = &self.views[at].settings;
            let aspect = view_settings.width as f32 / view_settings.height as f32;
            let fit = CascadeSettings {
                count: settings.cascades,
                distance: self.shadows.distance.max(camera.near * 2.0),
                lambda: settings.lambda,
                resolution: settings.resolution,
                caster_reach: self.shadows.reach,
            };
            // A camera the cascades cannot be fitted to (no depth range to split) is lit
            // without the sun's shadows, as the fallback says; the camera itself was checked.
            if let Ok(cascades) = fit_cascades(camera, aspect, sun, &fit) {
                view_data.sun.info = [cascades.len() as u32, settings.resolution, 0, 0];
                for (c, cascade) in cascades.iter().enumerate() {
                    view_data.sun.cascades[c] = relative_to(camera, &cascade.camera).to_cols_array_2d();
                    view_data.sun.texel[c] = cascade.texel as f32;
                    // A map whose camera, sun and world did not change since it was drawn is kept.
                    frames.extend(shadows.sun.frame(c, &cascade.camera, key(&cascade.camera), id, keep));
                }
            }
            let budget = settings.local_lights as usize;
            let chosen = shadowed_lights(
                &self.scene.lights,
                camera,
                self.shadows.distance as f64,
                budget,
                settings.local_resolution,
            );
            if !chosen.is_empty() {
                view_data.lights = vec![[NO_SHADOW, 0, 0, 0]; self.scene.lights.len()];
            }
            let mut next_face = 0;
            for light in chosen {
                let first = next_face;
                for face in &light.faces {
                    view_data.local.faces[next_face] = relative_to(camera, face).to_cols_array_2d();
                    frames.extend(shadows.local.frame(next_face, face, key(face), id, keep));
                    next_face += 1;
                }
                view_data.lights[light.light] =
                    [first as u32, light.faces.len() as u32, light.texel_per_unit.to_bits(), 0];
            }
            let maps = ShadowMaps {
                on: true,
                sun: shadows.sun.maps.array_view(),
                local: shadows.local.maps.array_view(),
                sampler: self.shadows.sampler.handle(),
                arrays: [shadows.sun.maps.id(), shadows.local.maps.id()],
            };
            self.views[at].inputs.set_shadow_maps(maps);
            data.push(view_data);
        }
        self.shadows.made_ready = made_ready;
        Ok((frames, data))
    }
}

/// The matrix from `view`'s eye-relative positions to `shadow`'s clip space.
fn relative_to(view: &Camera, shadow: &Camera) -> Mat4 {
    let offset = (view.eye - shadow.eye).as_vec3();
    shadow.view_projection_rel_eye(1.0) * Mat4::from_translation(offset)
}

impl Renderer {
    /// Notes what a frame planned by [`Renderer::plan_shadow_frame`] did, once it has been
    /// recorded whole: the fallback's layout, and the maps its shadow views drew (a frame whose
    /// recording failed is discarded by its host, so nothing is noted for it).
    pub(in crate::render::renderer) fn shadow_frame_recorded(&mut self, frames: Vec<ShadowViewFrame>) {
        self.shadows.fallback_ready = true;
        let made_ready = std::mem::take(&mut self.shadows.made_ready);
        for shadows in self.shadows.cameras.iter_mut().filter(|c| made_ready.contains(&c.camera)) {
            shadows.sun.ready = true;
            shadows.local.ready = true;
        }
        for frame in frames {
            let Some(shadows) = self.shadows.cameras.iter_mut().find(|c| c.camera == frame.of) else { continue };
            if !shadows.sun.recorded(&frame) {
                shadows.local.recorded(&frame);
            }
        }
    }
}
