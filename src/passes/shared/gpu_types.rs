//! GPU-side layouts of scene and frame data; mirrors `shaders/common/scene.glsl`.

use crate::scene::projection::jitter_ndc;
use crate::scene::{Camera, Instance, Material, PointLight, Scene, Transform};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Mat4, Vec3};

/// Splits a double into a float on a grid and the float remainder. `hi + lo` keeps the value to
/// 2^-24 of the grid: 6e-8 units below 2^24 (60 nm in metres), relative 2^-47 beyond. (Splitting
/// off the nearest float kept more bits near the origin, where nothing needs them.) `hi` is the
/// whole number of units below the value while whole numbers are exact
/// floats (|v| < 2^24), a coarser power-of-two grid beyond. Moving scene and camera together by a
/// whole number of units then moves only the `hi` parts, and the shaders' `hi - eye_hi` is exact:
/// the eye-relative positions, and the image, are the same bits at the origin and at 10^7 (for
/// coordinates that the move itself does not round: floats, as glTF stores them, or doubles
/// without bits below 2^-29). Rounding `v` to the nearest float for `hi` instead gives a
/// different remainder at each offset.
pub fn split_hi_lo(v: DVec3) -> (Vec3, Vec3) {
    let split = |x: f64| {
        let hi = (x / hi_grid(x)).floor() * hi_grid(x);
        (hi as f32, (x - hi) as f32)
    };
    let (x, y, z) = (split(v.x), split(v.y), split(v.z));
    (Vec3::new(x.0, y.0, z.0), Vec3::new(x.1, y.1, z.1))
}

/// The grid of `x`'s hi part: 1 while whole numbers are exact floats, else the power of two that
/// keeps `x / grid` within a float's 24 bits.
fn hi_grid(x: f64) -> f64 {
    const EXACT_WHOLE: f64 = (1u32 << 24) as f64;
    let m = x.abs();
    // (NaN and infinity, refused at upload, take the unit grid.)
    if m < EXACT_WHOLE || !m.is_finite() {
        1.0
    } else {
        2f64.powi(m.log2().floor() as i32 - 23)
    }
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
    /// Packs a scene instance; an empty slot ([`crate::scene::FLAG_EMPTY_SLOT`]) packs as zeros
    /// but its flags: every vertex lands on one point, so it draws nothing, and a cull bound
    /// derived from it on the GPU keeps the flag.
    pub fn new(instance: &Instance) -> Self {
        if instance.flags & crate::scene::FLAG_EMPTY_SLOT != 0 {
            return Self { material_flags: crate::scene::FLAG_EMPTY_SLOT << 24, ..Self::zeroed() };
        }
        let (rows, translation_lo) = Self::transform_words(&instance.transform);
        Self { rows, translation_lo, material_flags: Self::material_flags_of(instance) }
    }

    /// The record's last word for `instance` (not an empty slot): its material and flags.
    pub fn material_flags_of(instance: &Instance) -> u32 {
        (instance.material & 0xFF_FFFF) | (instance.flags << 24)
    }

    /// The record's transform part: rows of the linear part with the translation's hi part in
    /// `w`, and the translation's lo part.
    pub fn transform_words(transform: &Transform) -> ([[f32; 4]; 3], [f32; 3]) {
        let (hi, lo) = split_hi_lo(transform.translation);
        let m = transform.linear;
        let row = |r: usize, t: f32| [m.col(0)[r], m.col(1)[r], m.col(2)[r], t];
        ([row(0, hi.x), row(1, hi.y), row(2, hi.z)], lo.to_array())
    }
}

/// One texture of a material as the shaders read it (48 bytes; `MaterialTexture` in
/// `shaders/common/scene.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuMaterialTexture {
    /// The texture-coordinate transform's first row: `u' = x * u + y * v + z`.
    pub row0: [f32; 4],
    /// Its second row.
    pub row1: [f32; 4],
    /// `class << 16 | layer` in the texture arrays ([`super::textures::GpuTextures`]), or
    /// [`super::textures::NO_TEXTURE`].
    pub placement: u32,
    /// Wrap of u (bits 0-1) and v (bits 2-3) as `Wrap` (0 repeat, 1 mirrored repeat, 2 clamp),
    /// nearest magnification (bit 4) and minification (bit 5).
    pub sampling: u32,
    /// Padding.
    pub pad: [u32; 2],
}

impl Default for GpuMaterialTexture {
    fn default() -> Self {
        Self {
            row0: [1.0, 0.0, 0.0, 0.0],
            row1: [0.0, 1.0, 0.0, 0.0],
            placement: super::textures::NO_TEXTURE,
            sampling: 0,
            pad: [0; 2],
        }
    }
}

/// `alpha_mode` of [`GpuMaterial`].
pub const ALPHA_OPAQUE: u32 = 0;
/// See [`ALPHA_OPAQUE`].
pub const ALPHA_MASK: u32 = 1;
/// See [`ALPHA_OPAQUE`].
pub const ALPHA_BLEND: u32 = 2;
/// [`GpuMaterial::flags`]: back faces are drawn (and lit with the flipped normal).
pub const MATERIAL_DOUBLE_SIDED: u32 = 1;

/// A material as the shaders read it (304 bytes; `GpuMaterial` in `shaders/common/scene.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// Linear albedo.
    pub albedo: [f32; 3],
    /// Roughness.
    pub roughness: f32,
    /// Metalness.
    pub metallic: f32,
    /// Base colour alpha.
    pub alpha: f32,
    /// Alpha below which a masked material's fragments are discarded.
    pub alpha_cutoff: f32,
    /// `ALPHA_*`.
    pub alpha_mode: u32,
    /// Emitted linear radiance.
    pub emissive: [f32; 3],
    /// Scale of the normal texture's x and y.
    pub normal_scale: f32,
    /// How much the occlusion texture darkens.
    pub occlusion_strength: f32,
    /// `MATERIAL_*` bits.
    pub flags: u32,
    /// Padding.
    pub pad: [f32; 2],
    /// Per [`crate::scene::TextureSlot`], in its order.
    pub textures: [GpuMaterialTexture; 5],
}

impl GpuMaterial {
    /// `m` for the shaders, its textures placed as `placements` (by scene texture) says.
    pub fn new(m: &Material, placements: &[u32]) -> Self {
        let (alpha_mode, alpha_cutoff) = match m.alpha_mode {
            crate::scene::AlphaMode::Opaque => (ALPHA_OPAQUE, 0.0),
            crate::scene::AlphaMode::Mask { cutoff } => (ALPHA_MASK, cutoff),
            crate::scene::AlphaMode::Blend => (ALPHA_BLEND, 0.0),
        };
        let mut textures = [GpuMaterialTexture::default(); 5];
        for (gpu, t) in textures.iter_mut().zip(&m.textures) {
            let Some(t) = t else { continue };
            let [r0, r1] = t.transform.rows();
            let wrap = |w: crate::scene::texture::Wrap| w as u32;
            *gpu = GpuMaterialTexture {
                row0: r0.to_array(),
                row1: r1.to_array(),
                placement: placements.get(t.texture as usize).copied().unwrap_or(super::textures::NO_TEXTURE),
                sampling: wrap(t.sampler.wrap_u)
                    | wrap(t.sampler.wrap_v) << 2
                    | (t.sampler.nearest_mag as u32) << 4
                    | (t.sampler.nearest_min as u32) << 5,
                pad: [0; 2],
            };
        }
        Self {
            albedo: m.albedo.to_array(),
            roughness: m.roughness.clamp(0.0, 1.0),
            metallic: m.metallic.clamp(0.0, 1.0),
            alpha: m.alpha.clamp(0.0, 1.0),
            alpha_cutoff,
            alpha_mode,
            emissive: m.emissive.to_array(),
            normal_scale: m.normal_scale,
            occlusion_strength: m.occlusion_strength.clamp(0.0, 1.0),
            flags: if m.double_sided { MATERIAL_DOUBLE_SIDED } else { 0 },
            pad: [0.0; 2],
            textures,
        }
    }
}

/// A point light relative to the eye.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPointLight {
    /// xyz: eye-relative position, w: range.
    pub position_range: [f32; 4],
    /// rgb: color, w: the spot cone's angle scale, 1 / (cos inner - cos outer) (0 for a point
    /// light).
    pub color: [f32; 4],
    /// xyz: the direction a spot light travels, w: cos of its outer angle (below -1 for a point
    /// light, so that every direction is inside).
    pub spot: [f32; 4],
    /// Its shadow: x the first of its faces in [`GpuLocalShadows::faces`] ([`NO_SHADOW`]: it
    /// casts none), y its faces (1: one view along its cone; 6: a cube), z the bits of the
    /// world size of a texel of its maps one unit from the light, w unused.
    pub shadow: [u32; 4],
}

/// [`GpuPointLight::shadow`]'s first face of a light that casts no shadow.
pub const NO_SHADOW: u32 = u32::MAX;

/// The most shadow-map faces of spot and point lights a view holds (4 point lights' cubes).
pub const MAX_LOCAL_FACES: usize = 24;

/// The shadow maps of a view's spot and point lights (see `LocalShadows` in `scene.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuLocalShadows {
    /// Per face: the view's eye-relative world to the face's clip space (perspective,
    /// reversed-Z), the face's layer being its index.
    pub faces: [[[f32; 4]; 4]; MAX_LOCAL_FACES],
}

impl Default for GpuLocalShadows {
    fn default() -> Self {
        Self { faces: [[[0.0; 4]; 4]; MAX_LOCAL_FACES] }
    }
}

impl GpuPointLight {
    /// The light relative to `eye`.
    pub fn new(light: &PointLight, eye: DVec3) -> Self {
        let p = (light.position - eye).as_vec3();
        let (spot, scale) = match light.spot {
            Some(cone) => {
                let (cos_inner, cos_outer) = (cone.inner_angle.cos(), cone.outer_angle.cos());
                let d = cone.direction;
                ([d.x, d.y, d.z, cos_outer], 1.0 / (cos_inner - cos_outer).max(1e-3))
            }
            None => ([0.0, 0.0, 0.0, -2.0], 0.0),
        };
        Self {
            position_range: [p.x, p.y, p.z, light.range],
            color: [light.color.x, light.color.y, light.color.z, scale],
            spot,
            shadow: [NO_SHADOW, 0, 0, 0],
        }
    }
}

/// The culling view of a frame as the shaders read it (`CullView` in `cull_math.glsl`,
/// scalar layout, 72 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCullView {
    /// World-to-view rotation, column-major.
    pub rotation: [f32; 9],
    /// NDC scale (see [`crate::cull::math::CullView::scale`]).
    pub scale: [f32; 2],
    /// Near-plane distance.
    pub near: f32,
    /// Far-plane distance (infinity for a perspective without one).
    pub far: f32,
    /// 1 for orthographic.
    pub orthographic: u32,
    /// Viewport (Hi-Z level 0) size.
    pub viewport: [u32; 2],
    /// NDC offset (see [`crate::cull::math::CullView::offset`]): off-centre projection and jitter.
    pub offset: [f32; 2],
}

impl GpuCullView {
    /// The culling view of `camera` on a `width` x `height` target.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let v = crate::cull::math::CullView::from_camera(camera, width, height);
        Self {
            rotation: v.rotation.to_cols_array(),
            scale: v.scale.to_array(),
            near: v.near,
            far: v.far,
            orthographic: v.orthographic as u32,
            viewport: v.viewport.to_array(),
            offset: v.offset.to_array(),
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
    /// This frame's eye-relative world to clip without the sub-pixel jitter (`view_proj` is
    /// jittered): motion vectors compare unjittered positions, so that the jitter does not move
    /// still pixels.
    pub view_proj_unjittered: [[f32; 4]; 4],
    /// Last frame's world relative to last frame's eye, to clip, without its jitter.
    pub prev_view_proj_unjittered: [[f32; 4]; 4],
    /// xy: this frame's jitter, zw: last frame's, in NDC units (2 / size per pixel): the amount
    /// `view_proj` moves a point's NDC position by (+y down, as NDC).
    pub jitter: [f32; 4],
    /// The sun's shadow maps as this view samples them (all zero: no shadows).
    pub sun_shadows: GpuSunShadows,
    /// The spot and point lights' shadow maps as this view samples them.
    pub local_shadows: GpuLocalShadows,
    /// The view whose pixels levels of detail are chosen for: a shadow view's camera view
    /// ([`FrameConstants::choose_levels_for`]), any other view's own `cull_view`.
    pub lod_view: GpuCullView,
    /// xyz: this view's eye less [`FrameConstants::lod_view`]'s eye.
    pub lod_eye_offset: [f32; 4],
}

/// The sun's shadow cascades of one view (see `SunShadows` in `shadows.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSunShadows {
    /// Per cascade: the view's eye-relative world to the cascade's clip space (orthographic:
    /// x and y in -1..1 across the map, z the reversed depth the map holds).
    pub cascades: [[[f32; 4]; 4]; 4],
    /// Per cascade: the world size of one texel of its map.
    pub texel: [f32; 4],
    /// x: cascades (0: no shadows), y: map size in texels, z and w: unused.
    pub info: [u32; 4],
}

impl FrameConstants {
    /// Constants for `camera` looking at `scene` on a `width` x `height` target, where
    /// `previous` was last frame's camera (the same camera on the first frame). `view_proj` and
    /// the culling views carry each camera's jitter; the `*_unjittered` matrices do not.
    pub fn new(scene: &Scene, camera: &Camera, previous: &Camera, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height as f32;
        let vp: Mat4 = camera.jittered_view_projection_rel_eye(width, height);
        let vp_unjittered: Mat4 = camera.view_projection_rel_eye(aspect);
        let jitter = jitter_ndc(camera.jitter, width, height);
        let prev_jitter = jitter_ndc(previous.jitter, width, height);
        let (eye_hi, eye_lo) = split_hi_lo(camera.eye);
        let (prev_eye_hi, prev_eye_lo) = split_hi_lo(previous.eye);
        let prev_vp: Mat4 = previous.view_projection_rel_eye(aspect);
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
            view_proj_unjittered: vp_unjittered.to_cols_array_2d(),
            prev_view_proj_unjittered: prev_vp.to_cols_array_2d(),
            jitter: [jitter.x, jitter.y, prev_jitter.x, prev_jitter.y],
            sun_shadows: GpuSunShadows::default(),
            local_shadows: GpuLocalShadows::default(),
            lod_view: GpuCullView::new(camera, width, height),
            lod_eye_offset: [0.0; 4],
        }
    }

    /// Levels of detail chosen for `camera` on a `width` x `height` target (a shadow view's
    /// camera view), where this view's eye is `eye`: each instance then takes the level that
    /// view takes.
    pub fn choose_levels_for(&mut self, eye: glam::DVec3, camera: &Camera, width: u32, height: u32) {
        self.lod_view = GpuCullView::new(camera, width, height);
        self.lod_eye_offset = (eye - camera.eye).as_vec3().extend(0.0).to_array();
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
        for v in [
            DVec3::new(1.0e7 + 0.123456, -9_999_999.875, 3.0e6 + 1.0 / 3.0),
            DVec3::new(-0.4, 0.25, 16_777_215.75),
            DVec3::new(3.0e8 + 0.5, -5.0e9, 1.0e12 + 7.0),
        ] {
            let (hi, lo) = split_hi_lo(v);
            let back = hi.as_dvec3() + lo.as_dvec3();
            for axis in 0..3 {
                // 2^-24 of the unit grid below 2^24, of the value's own magnitude beyond.
                let allowed = v[axis].abs().max(16_777_216.0) * 2f64.powi(-47);
                assert!((back[axis] - v[axis]).abs() <= allowed, "axis {axis}: {back:?} vs {v:?}");
            }
        }
    }

    #[test]
    fn a_whole_offset_moves_only_the_hi_part_and_eye_relative_sums_stay_the_same_bits() {
        // Float coordinates, as glTF stores them: adding 10^7 in f64 is exact for them. (A double
        // with bits below 2^-29 is rounded by the move itself, before any split.)
        let eye = Vec3::new(3.25, 1.7, -12.125).as_dvec3();
        let point = Vec3::new(-40.123456, 2.0 / 3.0, 7.000001).as_dvec3();
        let rel = |p: DVec3, e: DVec3| {
            let ((ph, pl), (eh, el)) = (split_hi_lo(p), split_hi_lo(e));
            (ph - eh) + (pl - el)
        };
        for offset in [DVec3::new(1.0e7, 0.0, -1.0e7), DVec3::new(-3.0, 123_456.0, 8_000_000.0)] {
            let (near, far) = (split_hi_lo(point), split_hi_lo(point + offset));
            assert_eq!(near.1, far.1, "the lo part does not move");
            assert_eq!(far.0 - near.0, offset.as_vec3(), "the hi part moves by the offset");
            assert_eq!(rel(point, eye), rel(point + offset, eye + offset));
        }
    }

    #[test]
    fn the_raster_gets_the_jittered_matrix_and_motion_vectors_the_unjittered_ones() {
        let scene = Scene::default();
        let (w, h) = (64, 48);
        let previous = Camera { jitter: glam::Vec2::new(0.25, -0.125), ..Default::default() };
        let camera =
            Camera { eye: DVec3::new(0.5, 2.0, 9.0), jitter: glam::Vec2::new(-0.375, 0.4), ..previous.clone() };
        let k = FrameConstants::new(&scene, &camera, &previous, w, h);
        let aspect = w as f32 / h as f32;
        let cols = |m: Mat4| m.to_cols_array_2d();
        assert_eq!(k.view_proj, cols(camera.jittered_view_projection_rel_eye(w, h)));
        assert_eq!(k.view_proj_unjittered, cols(camera.view_projection_rel_eye(aspect)));
        // Last frame's unjittered matrix: not last frame's jittered one, nor this frame's.
        assert_eq!(k.prev_view_proj_unjittered, cols(previous.view_projection_rel_eye(aspect)));
        assert_ne!(k.prev_view_proj_unjittered, cols(previous.jittered_view_projection_rel_eye(w, h)));
        assert_eq!(k.jitter, [-0.375 * 2.0 / 64.0, 0.4 * 2.0 / 48.0, 0.25 * 2.0 / 64.0, -0.125 * 2.0 / 48.0]);
        // The jittered and unjittered matrices differ by exactly the jitter in NDC.
        let p = glam::Vec4::new(0.3, -0.2, -4.0, 1.0);
        let (a, b) =
            (Mat4::from_cols_array_2d(&k.view_proj) * p, Mat4::from_cols_array_2d(&k.view_proj_unjittered) * p);
        let moved = a.truncate().truncate() / a.w - b.truncate().truncate() / b.w;
        assert!((moved - glam::Vec2::new(k.jitter[0], k.jitter[1])).abs().max_element() < 1e-6, "{moved}");
        // The culling views carry each frame's jitter too (they test against pyramids of jittered depth).
        assert_eq!(k.cull_view.offset, [-k.jitter[0], k.jitter[1]]);
        assert_eq!(k.prev_cull_view.offset, [-k.jitter[2], k.jitter[3]]);
        // A view chooses levels of detail for itself unless told otherwise.
        assert_eq!((k.lod_view, k.lod_eye_offset), (k.cull_view, [0.0; 4]));
        let mut shadow = k;
        shadow.choose_levels_for(previous.eye + glam::DVec3::new(0.0, 50.0, -2.0), &previous, 320, 180);
        assert_eq!(shadow.lod_view, GpuCullView::new(&previous, 320, 180));
        assert_eq!(shadow.lod_eye_offset, [0.0, 50.0, -2.0, 0.0]);
    }

    #[test]
    fn layouts_match_the_shader_sizes() {
        assert_eq!(std::mem::size_of::<GpuInstance>(), 64);
        assert_eq!(std::mem::size_of::<GpuMaterialTexture>(), 48);
        assert_eq!(std::mem::size_of::<GpuMaterial>(), 64 + 5 * 48);
        assert_eq!(std::mem::size_of::<GpuPointLight>(), 64);
        assert_eq!(std::mem::size_of::<GpuCullView>(), 72);
        assert_eq!(
            std::mem::size_of::<FrameConstants>(),
            2 * 64 + 6 * 16 + 2 * 72 + 2 * 16 + 2 * 64 + 16 + 288 + 24 * 64 + 72 + 16
        );
        assert_eq!(std::mem::size_of::<GpuSunShadows>(), 4 * 64 + 2 * 16);
        assert_eq!(std::mem::size_of::<DrawIndexedIndirect>(), 20);
    }
}
