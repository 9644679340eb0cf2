//! GPU-side layouts of scene and frame data; mirrors `shaders/common/scene.glsl`.

use crate::scene::{Camera, Instance, Material, PointLight, Scene};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4, Vec3};

/// Splits a double into a float and the float remainder, so that `hi + lo` carries ~48 bits.
pub fn split_hi_lo(v: DVec3) -> (Vec3, Vec3) {
    let hi = v.as_vec3();
    let lo = (v - hi.as_dvec3()).as_vec3();
    (hi, lo)
}

/// One instance as the shaders read it (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuInstance {
    /// Rows of the linear part with the translation's hi part in `w`.
    pub rows: [[f32; 4]; 3],
    /// Translation minus its hi part.
    pub translation_lo: [f32; 3],
    /// Material index (24 bits) | flags << 24.
    pub material_flags: u32,
}

impl GpuInstance {
    /// Packs a scene instance.
    pub fn new(instance: &Instance) -> Self {
        let (hi, lo) = split_hi_lo(instance.transform.translation);
        let m = instance.transform.linear;
        let row = |r: usize, t: f32| [m.col(0)[r], m.col(1)[r], m.col(2)[r], t];
        Self {
            rows: [row(0, hi.x), row(1, hi.y), row(2, hi.z)],
            translation_lo: lo.to_array(),
            material_flags: (instance.material & 0xFF_FFFF) | (instance.flags << 24),
        }
    }
}

/// A material as the shaders read it (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Linear albedo.
    pub albedo: [f32; 3],
    /// Roughness.
    pub roughness: f32,
    /// Metalness.
    pub metallic: f32,
    /// Padding to 32 bytes.
    pub pad: [f32; 3],
}

impl From<&Material> for GpuMaterial {
    fn from(m: &Material) -> Self {
        Self {
            albedo: m.albedo.to_array(),
            roughness: m.roughness.clamp(0.0, 1.0),
            metallic: m.metallic.clamp(0.0, 1.0),
            pad: [0.0; 3],
        }
    }
}

/// A point light relative to the eye.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPointLight {
    /// xyz: eye-relative position, w: range.
    pub position_range: [f32; 4],
    /// rgb: color.
    pub color: [f32; 4],
}

impl GpuPointLight {
    /// The light relative to `eye`.
    pub fn new(light: &PointLight, eye: DVec3) -> Self {
        let p = (light.position - eye).as_vec3();
        Self { position_range: [p.x, p.y, p.z, light.range], color: [light.color.x, light.color.y, light.color.z, 0.0] }
    }
}

/// The culling view of a frame as the shaders read it (`CullView` in `cull_math.glsl`,
/// scalar layout, 64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCullView {
    /// World-to-view rotation, column-major.
    pub rotation: [f32; 9],
    /// NDC scale (see [`crate::oracle::cull_math::CullView::scale`]).
    pub scale: [f32; 2],
    /// Near-plane distance.
    pub near: f32,
    /// Orthographic far-plane distance.
    pub far: f32,
    /// 1 for orthographic.
    pub orthographic: u32,
    /// Viewport (Hi-Z level 0) size.
    pub viewport: [u32; 2],
}

impl GpuCullView {
    /// The culling view of `camera` on a `width` x `height` target.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let v = crate::oracle::cull_math::CullView::from_camera(camera, width, height);
        Self {
            rotation: v.rotation.to_cols_array(),
            scale: v.scale.to_array(),
            near: v.near,
            far: v.far,
            orthographic: v.orthographic as u32,
            viewport: v.viewport.to_array(),
        }
    }
}

/// Per-frame constants (see `FrameConstants` in `scene.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameConstants {
    /// Eye-relative world to clip.
    pub view_proj: [[f32; 4]; 4],
    /// Clip to eye-relative world.
    pub inv_view_proj: [[f32; 4]; 4],
    /// Eye position, hi part.
    pub eye_hi: [f32; 4],
    /// Eye position, lo part.
    pub eye_lo: [f32; 4],
    /// Direction the sunlight travels.
    pub sun_direction: [f32; 4],
    /// Sun radiance.
    pub sun_color: [f32; 4],
    /// Width, height, point light count, unused.
    pub size_lights: [u32; 4],
    /// Sky ambient rgb, unused.
    pub ambient: [f32; 4],
    /// This frame's culling view.
    pub cull_view: GpuCullView,
    /// Last frame's culling view (for tests against last frame's Hi-Z).
    pub prev_cull_view: GpuCullView,
    /// Last frame's eye, hi part.
    pub prev_eye_hi: [f32; 4],
    /// Last frame's eye, lo part.
    pub prev_eye_lo: [f32; 4],
}

impl FrameConstants {
    /// Constants for `camera` looking at `scene` on a `width` x `height` target, where
    /// `previous` was last frame's camera (the same camera on the first frame).
    pub fn new(scene: &Scene, camera: &Camera, previous: &Camera, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height as f32;
        let vp: Mat4 = camera.view_projection_rel_eye(aspect);
        let (eye_hi, eye_lo) = split_hi_lo(camera.eye);
        let (prev_eye_hi, prev_eye_lo) = split_hi_lo(previous.eye);
        let sun = scene.sun;
        Self {
            view_proj: vp.to_cols_array_2d(),
            inv_view_proj: vp.inverse().to_cols_array_2d(),
            eye_hi: eye_hi.extend(0.0).to_array(),
            eye_lo: eye_lo.extend(0.0).to_array(),
            sun_direction: sun.direction.normalize_or(Vec3::NEG_Y).extend(0.0).to_array(),
            sun_color: sun.color.extend(0.0).to_array(),
            size_lights: [width, height, scene.lights.len() as u32, 0],
            ambient: [0.22, 0.27, 0.35, 0.0],
            cull_view: GpuCullView::new(camera, width, height),
            prev_cull_view: GpuCullView::new(previous, width, height),
            prev_eye_hi: prev_eye_hi.extend(0.0).to_array(),
            prev_eye_lo: prev_eye_lo.extend(0.0).to_array(),
        }
    }
}

/// `VkDrawIndexedIndirectCommand` (20 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct DrawIndexedIndirect {
    /// Indices per instance.
    pub index_count: u32,
    /// Instances drawn.
    pub instance_count: u32,
    /// First index in the pool.
    pub first_index: u32,
    /// Added to each index.
    pub vertex_offset: i32,
    /// Start of the group's slice of the compacted instance list.
    pub first_instance: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hi_lo_keeps_precision_far_from_origin() {
        let v = DVec3::new(1.0e7 + 0.123456, -9_999_999.875, 3.0e6 + 1.0 / 3.0);
        let (hi, lo) = split_hi_lo(v);
        let back = hi.as_dvec3() + lo.as_dvec3();
        assert!((back - v).abs().max_element() < 1e-6, "{back:?} vs {v:?}");
    }

    #[test]
    fn layouts_match_the_shader_sizes() {
        assert_eq!(std::mem::size_of::<GpuInstance>(), 64);
        assert_eq!(std::mem::size_of::<GpuMaterial>(), 32);
        assert_eq!(std::mem::size_of::<GpuPointLight>(), 32);
        assert_eq!(std::mem::size_of::<GpuCullView>(), 64);
        assert_eq!(std::mem::size_of::<FrameConstants>(), 2 * 64 + 6 * 16 + 2 * 64 + 2 * 16);
        assert_eq!(std::mem::size_of::<DrawIndexedIndirect>(), 20);
    }
}
