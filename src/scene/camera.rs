//! Cameras with reversed-Z projections ([`Projection`]): depth 1 at the near plane, 0 at the far
//! plane or at infinity; optionally jittered by a sub-pixel offset for temporal anti-aliasing.
//!
//! Views are built relative to the eye: the GPU receives a rotation-only view matrix and
//! subtracts the (hi/lo split) eye position from every world position first. An engine's own
//! view and projection matrices become a camera through [`Camera::from_matrices`].

pub use super::projection::{Projection, ProjectionParts};
use glam::{DMat4, DVec3, DVec4, Mat3, Mat4, Vec2, Vec3};

/// A camera looking from `eye` at `target`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (double precision for large worlds).
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Projection.
    pub projection: Projection,
    /// Near-plane distance (depth 1).
    pub near: f32,
    /// Sub-pixel jitter in pixels (+x right, +y down), at most 1 in magnitude per axis: the
    /// raster and the culling use the jittered projection, motion vectors the unjittered one
    /// ([`crate::passes::shared::gpu_types::FrameConstants`]). Zero by default.
    pub jitter: Vec2,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: DVec3::new(0.0, 2.0, 10.0),
            target: DVec3::ZERO,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y_deg: 60.0 },
            near: 0.1,
            jitter: Vec2::ZERO,
        }
    }
}

impl Camera {
    /// A perspective camera that sees the whole box `min..max` from above and to the side, as
    /// close as it can while every corner of the box stays inside the central 90% of the view.
    pub fn framing(min: DVec3, max: DVec3, aspect: f32) -> Self {
        let center = (min + max) * 0.5;
        let radius = ((max - min).length() * 0.5).max(1e-3);
        let fov_y_deg = 50.0f32;
        let dir = DVec3::new(0.55, 0.45, 0.7).normalize();
        let mut camera = Self {
            eye: center + dir * radius * 3.0,
            target: center,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y_deg },
            near: 0.1,
            jitter: Vec2::ZERO,
        };
        let corners: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new(pick(i & 1, min.x, max.x), pick(i & 2, min.y, max.y), pick(i & 4, min.z, max.z)))
            .collect();
        let fits = |distance: f64| {
            let cam = Self { eye: center + dir * distance, ..camera.clone() };
            let vp = cam.view_projection_rel_eye(aspect).as_dmat4();
            corners.iter().all(|c| {
                let clip = vp * (*c - cam.eye).extend(1.0);
                clip.w > 0.0 && (clip.x / clip.w).abs() <= 0.9 && (clip.y / clip.w).abs() <= 0.9
            })
        };
        // Distance shrinks monotonically while the box still fits: bisect between a fitting
        // distance (far enough that the bounding sphere fits) and the box's radius.
        let half = (fov_y_deg.to_radians() as f64 * 0.5)
            .tan()
            .min((fov_y_deg.to_radians() as f64 * 0.5).tan() * aspect as f64);
        let (mut lo, mut hi) = (radius, radius / (0.9 * half).atan().sin() + radius);
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            if fits(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        camera.eye = center + dir * hi;
        camera.near = ((hi - radius) * 0.5).clamp(1e-3, 1.0) as f32;
        camera
    }

    /// Unit forward vector.
    pub fn forward(&self) -> Vec3 {
        let f = (self.target - self.eye).as_vec3();
        f.try_normalize().unwrap_or(Vec3::NEG_Z)
    }

    /// World-to-view rotation (right-handed, looking down -Z), no translation.
    pub fn view_rotation(&self) -> Mat3 {
        let f = self.forward();
        let up = if f.cross(self.up).length_squared() < 1e-8 {
            if f.y.abs() < 0.9 {
                Vec3::Y
            } else {
                Vec3::Z
            }
        } else {
            self.up
        };
        let r = f.cross(up).normalize();
        let u = r.cross(f);
        Mat3::from_cols(r, u, -f).transpose()
    }

    /// The projection's numbers for `aspect` (width / height), without the jitter.
    pub fn projection_parts(&self, aspect: f32) -> ProjectionParts {
        self.projection.parts(aspect, self.near)
    }

    /// The projection's numbers on a `width` × `height` target with this camera's jitter: what
    /// the rasterizer and the culling use.
    pub fn jittered_projection_parts(&self, width: u32, height: u32) -> ProjectionParts {
        self.projection_parts(width as f32 / height as f32).jittered(self.jitter, width, height)
    }

    /// Projection matrix for `aspect` (width / height), reversed-Z, without the jitter.
    pub fn projection_matrix(&self, aspect: f32) -> Mat4 {
        self.projection_parts(aspect).matrix()
    }

    /// Projection times rotation: maps eye-relative world positions to clip space, without the
    /// jitter.
    pub fn view_projection_rel_eye(&self, aspect: f32) -> Mat4 {
        self.projection_matrix(aspect) * Mat4::from_mat3(self.view_rotation())
    }

    /// [`Camera::view_projection_rel_eye`] with the jitter on a `width` × `height` target: the
    /// matrix the rasterizer draws with.
    pub fn jittered_view_projection_rel_eye(&self, width: u32, height: u32) -> Mat4 {
        self.jittered_projection_parts(width, height).matrix() * Mat4::from_mat3(self.view_rotation())
    }

    /// A camera from an engine's matrices: `view` maps world to view space (right-handed, looking
    /// down −Z; rigid: a rotation and a translation, in `f64` for large worlds) and `projection`
    /// is a reversed-Z projection ([`Projection::from_matrix`] says which are accepted). The
    /// jitter is zero.
    ///
    /// Errors say what is wrong: non-finite entries, a view matrix with scale, shear or a
    /// reflection, or a projection that is singular, skewed or not reversed-Z.
    pub fn from_matrices(view: DMat4, projection: Mat4) -> Result<Camera, String> {
        if !view.is_finite() {
            return Err("the view matrix has a non-finite entry".into());
        }
        if view.row(3) != DVec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(format!("the view matrix's last row {} must be (0, 0, 0, 1)", view.row(3)));
        }
        let r = glam::DMat3::from_mat4(view);
        // Rigid: Rᵀ·R = I up to what an engine's f32 rotation leaves (well below 1e-4).
        let off =
            (r.transpose() * r - glam::DMat3::IDENTITY).to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if off > 1e-4 {
            return Err(format!(
                "the view matrix is not rigid: its rotation part is scaled or sheared (RᵀR differs from the identity by {off:.3e})"
            ));
        }
        if r.determinant() < 0.0 {
            return Err("the view matrix mirrors (its rotation part has a negative determinant)".into());
        }
        let (projection, near) = Projection::from_matrix(projection)?;
        // Row i of R is view axis i in world coordinates; the eye maps to the origin. (R's own
        // inverse, not its transpose: an f32 rotation is orthonormal only to ~1e-7, which the
        // transpose would turn into a unit of error 10^7 from the origin.)
        let eye = -(r.inverse() * view.w_axis.truncate());
        let forward = -r.row(2);
        let camera =
            Camera { eye, target: eye + forward, up: r.row(1).as_vec3(), projection, near, jitter: Vec2::ZERO };
        camera.validate()?;
        Ok(camera)
    }

    /// Checks the camera for values that cannot produce an image.
    pub fn validate(&self) -> Result<(), String> {
        if !self.eye.is_finite() || !self.target.is_finite() || !self.up.is_finite() {
            return Err("camera position, target or up is not finite".into());
        }
        for (what, p) in [("position", self.eye), ("target", self.target)] {
            if let Some(e) = super::position_error(what, p) {
                return Err(format!("camera {e}"));
            }
        }
        if (self.target - self.eye).length_squared() == 0.0 {
            return Err("camera eye and target are the same point".into());
        }
        if !(self.near.is_finite() && self.near > 0.0) {
            return Err(format!("near plane {} must be positive", self.near));
        }
        if !self.jitter.is_finite() || self.jitter.abs().max_element() > 1.0 {
            return Err(format!("jitter {} pixels must be finite and at most 1 pixel per axis", self.jitter));
        }
        self.projection.validate(self.near)
    }
}

fn pick(bit: usize, a: f64, b: f64) -> f64 {
    if bit == 0 {
        a
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    #[test]
    fn engine_matrices_give_back_the_camera_that_made_them() {
        let cam = Camera {
            eye: DVec3::new(1.0e7 + 0.25, 3.0, -2.0e6),
            target: DVec3::new(1.0e7 + 10.0, 1.0, -2.0e6 - 4.0),
            projection: Projection::OffCenter {
                left_deg: -45.0,
                right_deg: 40.0,
                up_deg: 42.0,
                down_deg: -50.0,
                far: 500.0,
            },
            near: 0.05,
            ..Default::default()
        };
        let r = cam.view_rotation().as_dmat3();
        let view = DMat4::from_mat3(r) * DMat4::from_translation(-cam.eye);
        let back = Camera::from_matrices(view, cam.projection_matrix(1.0)).unwrap();
        assert!((back.eye - cam.eye).length() < 1e-6, "{} vs {}", back.eye, cam.eye);
        assert!((back.view_rotation().as_dmat3() - r).to_cols_array().iter().all(|v| v.abs() < 1e-6));
        let (m0, m1) = (cam.view_projection_rel_eye(1.0), back.view_projection_rel_eye(1.0));
        for (a, b) in m0.to_cols_array().iter().zip(m1.to_cols_array()) {
            assert!((a - b).abs() <= 1e-5 * a.abs().max(1.0), "{m0} vs {m1}");
        }
    }

    #[test]
    fn bad_view_matrices_are_refused_with_the_reason() {
        let projection = Camera::default().projection_matrix(1.0);
        let refused = |view: DMat4, words: &str| {
            let e = Camera::from_matrices(view, projection).expect_err(words);
            assert!(e.contains(words), "{e:?} should say {words:?}");
        };
        let mut nan = DMat4::IDENTITY;
        nan.w_axis.x = f64::NAN;
        refused(nan, "non-finite");
        refused(DMat4::from_scale(DVec3::splat(2.0)), "scaled or sheared");
        refused(
            DMat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.3, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
            "sheared",
        );
        refused(DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)), "mirrors");
        refused(
            DMat4::from_cols_array(&[1.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
            "last row",
        );
        let e = Camera::from_matrices(DMat4::IDENTITY, Mat4::ZERO).unwrap_err();
        assert!(e.contains("singular"), "{e}");
        assert!(Camera::from_matrices(DMat4::IDENTITY, projection).is_ok());
    }

    #[test]
    fn jitter_is_checked() {
        let cam = Camera { jitter: Vec2::new(0.5, f32::NAN), ..Default::default() };
        assert!(cam.validate().unwrap_err().contains("jitter"));
        let cam = Camera { jitter: Vec2::new(2.0, 0.0), ..Default::default() };
        assert!(cam.validate().unwrap_err().contains("at most 1 pixel"));
    }

    #[test]
    fn reversed_z_depth_is_one_at_near_and_falls_with_distance() {
        let cam = Camera { eye: DVec3::ZERO, target: DVec3::new(0.0, 0.0, -1.0), near: 0.5, ..Default::default() };
        let vp = cam.view_projection_rel_eye(1.0);
        let depth = |d: f32| {
            let c = vp * Vec4::new(0.0, 0.0, -d, 1.0);
            c.z / c.w
        };
        assert!((depth(0.5) - 1.0).abs() < 1e-6);
        assert!((depth(1.0) - 0.5).abs() < 1e-6);
        assert!(depth(1e6) > 0.0 && depth(1e6) < 1e-5);
        // +Y in view goes to -Y in NDC: Vulkan's y points down, the image is upright.
        let c = vp * Vec4::new(0.0, 1.0, -2.0, 1.0);
        assert!(c.y / c.w < 0.0);
    }

    #[test]
    fn framing_keeps_every_corner_in_view_and_fills_it() {
        let (min, max) = (DVec3::new(-70.0, 0.0, -60.0), DVec3::new(55.0, 30.0, 60.0));
        let cam = Camera::framing(min, max, 16.0 / 9.0);
        let vp = cam.view_projection_rel_eye(16.0 / 9.0).as_dmat4();
        let mut extent: f64 = 0.0;
        for i in 0..8 {
            let c = DVec3::new(pick(i & 1, min.x, max.x), pick(i & 2, min.y, max.y), pick(i & 4, min.z, max.z));
            let clip = vp * (c - cam.eye).extend(1.0);
            let (x, y) = (clip.x / clip.w, clip.y / clip.w);
            assert!(clip.w > 0.0 && x.abs() <= 0.9 + 1e-9 && y.abs() <= 0.9 + 1e-9, "corner {c} at {x},{y}");
            extent = extent.max(x.abs()).max(y.abs());
        }
        assert!(extent > 0.85, "the box fills only {extent} of the view");
    }

    #[test]
    fn orthographic_maps_near_to_one_and_far_to_zero() {
        let cam = Camera {
            eye: DVec3::ZERO,
            target: DVec3::new(0.0, 0.0, -1.0),
            near: 1.0,
            projection: Projection::Orthographic { height: 10.0, far: 101.0 },
            ..Default::default()
        };
        let vp = cam.view_projection_rel_eye(1.0);
        let z = |d: f32| (vp * Vec4::new(0.0, 0.0, -d, 1.0)).z;
        assert!((z(1.0) - 1.0).abs() < 1e-6 && z(101.0).abs() < 1e-6);
    }
}
