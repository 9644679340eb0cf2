//! Cameras with reversed-Z projections: depth 1 at the near plane, 0 at infinity (perspective)
//! or at the far plane (orthographic).
//!
//! Views are built relative to the eye: the GPU receives a rotation-only view matrix and
//! subtracts the (hi/lo split) eye position from every world position first.

use glam::{DVec3, Mat3, Mat4, Vec3, Vec4};

/// How the camera projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with an infinite far plane.
    Perspective {
        /// Vertical field of view in degrees (0, 180).
        fov_y_deg: f32,
    },
    /// Orthographic.
    Orthographic {
        /// Visible height in world units.
        height: f32,
        /// Distance of the far plane (depth 0).
        far: f32,
    },
}

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
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: DVec3::new(0.0, 2.0, 10.0),
            target: DVec3::ZERO,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y_deg: 60.0 },
            near: 0.1,
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

    /// Projection matrix for `aspect` (width / height), reversed-Z.
    pub fn projection_matrix(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective { fov_y_deg } => {
                let f = 1.0 / (fov_y_deg.to_radians() * 0.5).tan();
                // clip.z = near, clip.w = -z_view: depth = near / distance, 1 at the near plane.
                Mat4::from_cols(
                    Vec4::new(f / aspect, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, -f, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, 0.0, -1.0),
                    Vec4::new(0.0, 0.0, self.near, 0.0),
                )
            }
            Projection::Orthographic { height, far } => {
                let sy = 2.0 / height;
                let range = far - self.near;
                // depth = (far + z_view) / (far - near): 1 at -near, 0 at -far.
                Mat4::from_cols(
                    Vec4::new(sy / aspect, 0.0, 0.0, 0.0),
                    Vec4::new(0.0, -sy, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, 1.0 / range, 0.0),
                    Vec4::new(0.0, 0.0, far / range, 1.0),
                )
            }
        }
    }

    /// Projection times rotation: maps eye-relative world positions to clip space.
    pub fn view_projection_rel_eye(&self, aspect: f32) -> Mat4 {
        self.projection_matrix(aspect) * Mat4::from_mat3(self.view_rotation())
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
        match self.projection {
            Projection::Perspective { fov_y_deg } if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) => {
                Err(format!("field of view {fov_y_deg} degrees must be in (0, 180)"))
            }
            Projection::Orthographic { height, far } if !(height > 0.0 && far > self.near && far.is_finite()) => {
                Err(format!("orthographic height {height} must be positive and far {far} beyond near {}", self.near))
            }
            _ => Ok(()),
        }
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
