//! Reversed-Z projections: depth 1 at the near plane, 0 at the far plane (or at infinity).
//!
//! Every projection reduces to the same few numbers, [`ProjectionParts`]: an NDC scale and
//! offset, the near and far distances and whether it is orthographic. The rasterizer's matrix
//! ([`ProjectionParts::matrix`]) and the culling view ([`crate::cull::CullView`]) are both made
//! from these numbers, so culling uses exactly the projection that draws. An engine's own matrix
//! is taken apart into them by [`ProjectionParts::from_matrix`].
//!
//! With `d = −z_view` the distance along the view axis:
//! - perspective: `ndc.x = sx·x/d − cx`, `ndc.y = cy − sy·y/d` (Vulkan's NDC y points down, so
//!   the image is upright), depth `near/d` (infinite far) or `near·(far − d) / (d·(far − near))`;
//! - orthographic: `ndc.x = sx·x − cx`, `ndc.y = cy − sy·y`, depth `(far − d) / (far − near)`.

use glam::{Mat4, Vec2, Vec4};

/// How a camera projects. All are reversed-Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Symmetric perspective with an infinite far plane; the horizontal extent follows the
    /// target's aspect.
    Perspective {
        /// Vertical field of view in degrees (0, 180).
        fov_y_deg: f32,
    },
    /// Symmetric perspective whose far plane (depth 0) culls what lies beyond it.
    PerspectiveFar {
        /// Vertical field of view in degrees (0, 180).
        fov_y_deg: f32,
        /// Distance of the far plane, beyond the near plane.
        far: f32,
    },
    /// Orthographic, centred on the view axis; the width follows the target's aspect.
    Orthographic {
        /// Visible height in world units.
        height: f32,
        /// Distance of the far plane (depth 0).
        far: f32,
    },
    /// Off-centre (asymmetric) perspective, as a VR eye's: the four edges of the view as angles
    /// from the view axis in degrees, in the sense of OpenXR's `XrFovf` (left and down are
    /// usually negative). Independent of the target's aspect.
    OffCenter {
        /// Angle of the left edge (negative: left of the axis), in (−90, 90).
        left_deg: f32,
        /// Angle of the right edge, above `left_deg`, in (−90, 90).
        right_deg: f32,
        /// Angle of the top edge, in (−90, 90).
        up_deg: f32,
        /// Angle of the bottom edge (negative: below the axis), below `up_deg`, in (−90, 90).
        down_deg: f32,
        /// Distance of the far plane; `f32::INFINITY` for none.
        far: f32,
    },
    /// Orthographic with any view-space box `left..right × bottom..top` (a shadow cascade's,
    /// or an engine's off-centre orthographic matrix). Independent of the target's aspect.
    OrthographicOffCenter {
        /// View-space x of the left edge.
        left: f32,
        /// View-space x of the right edge, above `left`.
        right: f32,
        /// View-space y of the bottom edge.
        bottom: f32,
        /// View-space y of the top edge, above `bottom`.
        top: f32,
        /// Distance of the far plane (depth 0).
        far: f32,
    },
}

/// The numbers a projection reduces to (see the module docs for the formulas).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionParts {
    /// `(sx, sy)`: NDC per unit of `x/d`, `y/d` (perspective) or of `x`, `y` (orthographic).
    pub scale: Vec2,
    /// `(cx, cy)`: the NDC offset (off-centre projections and the sub-pixel jitter).
    pub offset: Vec2,
    /// Near-plane distance (depth 1), > 0.
    pub near: f32,
    /// Far-plane distance (depth 0): `f32::INFINITY` for an infinite perspective.
    pub far: f32,
    /// Orthographic instead of perspective.
    pub orthographic: bool,
}

impl Projection {
    /// The projection's numbers on a target of `aspect` (width / height) with the near plane at
    /// `near`.
    pub fn parts(&self, aspect: f32, near: f32) -> ProjectionParts {
        let symmetric = |fov_y_deg: f32, far: f32| {
            let f = 1.0 / (fov_y_deg.to_radians() * 0.5).tan();
            ProjectionParts { scale: Vec2::new(f / aspect, f), offset: Vec2::ZERO, near, far, orthographic: false }
        };
        // Edges lo..hi map to NDC −1..1: scale 2/(hi − lo), offset (hi + lo)/(hi − lo); f64 keeps
        // nearly centred edges from cancelling.
        let edges = |lo: f64, hi: f64| ((2.0 / (hi - lo)) as f32, ((hi + lo) / (hi - lo)) as f32);
        match *self {
            Projection::Perspective { fov_y_deg } => symmetric(fov_y_deg, f32::INFINITY),
            Projection::PerspectiveFar { fov_y_deg, far } => symmetric(fov_y_deg, far),
            Projection::Orthographic { height, far } => {
                let sy = 2.0 / height;
                ProjectionParts { scale: Vec2::new(sy / aspect, sy), offset: Vec2::ZERO, near, far, orthographic: true }
            }
            Projection::OffCenter { left_deg, right_deg, up_deg, down_deg, far } => {
                let tan = |deg: f32| (deg as f64).to_radians().tan();
                let (sx, cx) = edges(tan(left_deg), tan(right_deg));
                let (sy, cy) = edges(tan(down_deg), tan(up_deg));
                ProjectionParts { scale: Vec2::new(sx, sy), offset: Vec2::new(cx, cy), near, far, orthographic: false }
            }
            Projection::OrthographicOffCenter { left, right, bottom, top, far } => {
                let (sx, cx) = edges(left as f64, right as f64);
                let (sy, cy) = edges(bottom as f64, top as f64);
                ProjectionParts { scale: Vec2::new(sx, sy), offset: Vec2::new(cx, cy), near, far, orthographic: true }
            }
        }
    }

    /// Checks the projection's own numbers against the near plane `near` (which must already be
    /// positive): a message saying what is wrong.
    pub fn validate(&self, near: f32) -> Result<(), String> {
        let angle_ok = |a: f32| a > -90.0 && a < 90.0;
        let far_ok = |far: f32| far > near && !far.is_nan();
        match *self {
            Projection::Perspective { fov_y_deg } | Projection::PerspectiveFar { fov_y_deg, .. }
                if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) =>
            {
                Err(format!("field of view {fov_y_deg} degrees must be in (0, 180)"))
            }
            Projection::PerspectiveFar { far, .. } if !(far_ok(far) && far.is_finite()) => {
                Err(format!("far plane {far} must be finite and beyond the near plane {near}"))
            }
            Projection::Orthographic { height, far } if !(height > 0.0 && height.is_finite() && far_ok(far)) => {
                Err(format!("orthographic height {height} must be positive and far {far} beyond near {near}"))
            }
            Projection::OffCenter { left_deg, right_deg, up_deg, down_deg, far } => {
                if ![left_deg, right_deg, up_deg, down_deg].into_iter().all(angle_ok) {
                    return Err(format!(
                        "off-centre angles left {left_deg}, right {right_deg}, up {up_deg}, down {down_deg} \
                         degrees must each be in (-90, 90)"
                    ));
                }
                if !(left_deg < right_deg && down_deg < up_deg) {
                    return Err(format!(
                        "off-centre angles must have left {left_deg} < right {right_deg} and \
                         down {down_deg} < up {up_deg} degrees"
                    ));
                }
                if !far_ok(far) {
                    return Err(format!("far plane {far} must be beyond the near plane {near} (or infinite)"));
                }
                Ok(())
            }
            Projection::OrthographicOffCenter { left, right, bottom, top, far } => {
                if !([left, right, bottom, top].into_iter().all(f32::is_finite) && left < right && bottom < top) {
                    return Err(format!(
                        "orthographic box left {left}, right {right}, bottom {bottom}, top {top} must be finite \
                         with left < right and bottom < top"
                    ));
                }
                if !(far_ok(far) && far.is_finite()) {
                    return Err(format!("orthographic far {far} must be finite and beyond near {near}"));
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Recognises an engine's reversed-Z projection matrix (clip = matrix × view-space point,
    /// view looking down −Z): the projection and its near-plane distance. A perspective matrix
    /// becomes [`Projection::OffCenter`] (with `far` infinite or not), an orthographic one
    /// [`Projection::OrthographicOffCenter`]; both keep the matrix's own horizontal extent
    /// whatever the target's aspect. Refuses, saying why, what [`ProjectionParts::from_matrix`]
    /// refuses.
    pub fn from_matrix(m: Mat4) -> Result<(Projection, f32), String> {
        let p = ProjectionParts::from_matrix(m)?;
        let (sx, sy) = (p.scale.x as f64, p.scale.y as f64);
        let (cx, cy) = (p.offset.x as f64, p.offset.y as f64);
        // Inverse of `parts`' edges: ndc −1 and 1 at (c ∓ 1)/s.
        let (left, right) = ((cx - 1.0) / sx, (cx + 1.0) / sx);
        let (bottom, top) = ((cy - 1.0) / sy, (cy + 1.0) / sy);
        let projection = if p.orthographic {
            Projection::OrthographicOffCenter {
                left: left as f32,
                right: right as f32,
                bottom: bottom as f32,
                top: top as f32,
                far: p.far,
            }
        } else {
            let deg = |t: f64| t.atan().to_degrees() as f32;
            Projection::OffCenter {
                left_deg: deg(left),
                right_deg: deg(right),
                up_deg: deg(top),
                down_deg: deg(bottom),
                far: p.far,
            }
        };
        projection.validate(p.near).map_err(|e| format!("the projection matrix gives {e}"))?;
        Ok((projection, p.near))
    }
}

impl ProjectionParts {
    /// The reversed-Z matrix: clip = matrix × view-space point.
    pub fn matrix(&self) -> Mat4 {
        let (sx, sy) = (self.scale.x, self.scale.y);
        let (cx, cy) = (self.offset.x, self.offset.y);
        let (near, far) = (self.near, self.far);
        if self.orthographic {
            let range = far - near;
            // depth = (far + z_view) / (far − near): 1 at −near, 0 at −far.
            Mat4::from_cols(
                Vec4::new(sx, 0.0, 0.0, 0.0),
                Vec4::new(0.0, -sy, 0.0, 0.0),
                Vec4::new(0.0, 0.0, 1.0 / range, 0.0),
                Vec4::new(0.0 - cx, cy, far / range, 1.0),
            )
        } else {
            // clip.w = d = −z_view; clip.z = a·z_view + b, so depth = b/d − a.
            let (a, b) = if far.is_finite() {
                let (n, f) = (near as f64, far as f64);
                ((n / (f - n)) as f32, (n * f / (f - n)) as f32)
            } else {
                (0.0, near)
            };
            Mat4::from_cols(
                Vec4::new(sx, 0.0, 0.0, 0.0),
                Vec4::new(0.0, -sy, 0.0, 0.0),
                Vec4::new(cx, 0.0 - cy, a, -1.0),
                Vec4::new(0.0, 0.0, b, 0.0),
            )
        }
    }

    /// The same projection moved by `jitter` pixels (+x right, +y down) on a `width` × `height`
    /// target: NDC moves by `2·jitter / size`, so every point, near or far, moves by exactly
    /// that many pixels.
    pub fn jittered(self, jitter: Vec2, width: u32, height: u32) -> Self {
        let ndc = jitter_ndc(jitter, width, height);
        Self { offset: Vec2::new(self.offset.x - ndc.x, self.offset.y + ndc.y), ..self }
    }

    /// Takes an engine's reversed-Z projection matrix apart (see [`Projection::from_matrix`]).
    ///
    /// Accepted: perspective matrices with the w row `(0, 0, −1, 0)` and orthographic ones with
    /// `(0, 0, 0, 1)`; x and y scales positive, with Vulkan's y flip (`m[1][1] < 0`); an NDC
    /// offset (off-centre); depth 1 at a near plane in front of the eye, falling to 0 at the far
    /// plane or at infinity. Refused, with the reason: non-finite entries, a singular matrix,
    /// skew (x and y mixed, or the eye shifted off the axis), a depth that grows with distance
    /// (not reversed-Z) or that depends on x or y, and a near plane at or behind the eye.
    pub fn from_matrix(m: Mat4) -> Result<Self, String> {
        let c = m.to_cols_array_2d();
        if !c.iter().flatten().all(|v| v.is_finite()) {
            return Err("the projection matrix has a non-finite entry".into());
        }
        if m.determinant() == 0.0 || !m.determinant().is_finite() {
            return Err("the projection matrix is singular".into());
        }
        let w_row = Vec4::new(c[0][3], c[1][3], c[2][3], c[3][3]);
        let orthographic = if w_row == Vec4::new(0.0, 0.0, -1.0, 0.0) {
            false
        } else if w_row == Vec4::new(0.0, 0.0, 0.0, 1.0) {
            true
        } else {
            return Err(format!(
                "the projection matrix's w row {w_row} is neither perspective (0, 0, -1, 0) nor orthographic \
                 (0, 0, 0, 1) (is it transposed, or for a view looking down +Z?)"
            ));
        };
        if c[1][0] != 0.0 || c[0][1] != 0.0 || c[0][2] != 0.0 || c[1][2] != 0.0 {
            return Err("the projection matrix is skewed: x and y or depth are mixed".into());
        }
        let (sx, sy) = (c[0][0], -c[1][1]);
        // (Finite: checked above.)
        if sx <= 0.0 {
            return Err(format!("the projection matrix's x scale {sx} must be positive (a mirrored image)"));
        }
        if sy <= 0.0 {
            return Err(format!(
                "the projection matrix's y scale {} must be negative: Vulkan's NDC y points down",
                c[1][1]
            ));
        }
        let (a, b) = (c[2][2], c[3][2]);
        let (offset, near, far) = if orthographic {
            if c[2][0] != 0.0 || c[2][1] != 0.0 {
                return Err("the orthographic projection matrix is oblique: x or y depends on depth".into());
            }
            // depth = a·z + b = (far − d)/(far − near): a = 1/(far − near), b = far/(far − near).
            if a <= 0.0 {
                return Err(format!("the projection matrix is not reversed-Z: depth grows with distance ({a})"));
            }
            let (a64, b64) = (a as f64, b as f64);
            let (near, far) = ((b64 - 1.0) / a64, b64 / a64);
            if near <= 0.0 {
                return Err(format!("the projection matrix's near plane {near} must be in front of the eye"));
            }
            (Vec2::new(-c[3][0], c[3][1]), near as f32, far as f32)
        } else {
            if c[3][0] != 0.0 || c[3][1] != 0.0 {
                return Err("the projection matrix is skewed: it moves the eye off the view axis".into());
            }
            // depth = b/d − a: b = near (a = 0, infinite far) or near·far/(far − near),
            // a = near/(far − near).
            if !(b > 0.0 && a >= 0.0) {
                return Err(format!(
                    "the projection matrix is not reversed-Z (depth 1 at the near plane falling with distance): \
                     m[2][2] = {a}, m[3][2] = {b}"
                ));
            }
            let (a64, b64) = (a as f64, b as f64);
            let (near, far) = if a == 0.0 { (b64, f64::INFINITY) } else { (b64 / (1.0 + a64), b64 / a64) };
            (Vec2::new(c[2][0], -c[2][1]), near as f32, far as f32)
        };
        if !(near > 0.0 && near.is_finite()) || far.is_nan() || far <= near {
            return Err(format!("the projection matrix's near {near} and far {far} planes are unusable"));
        }
        Ok(Self { scale: Vec2::new(sx, sy), offset, near, far, orthographic })
    }
}

/// A jitter of `jitter` pixels on a `width` × `height` target in NDC units: `2·jitter / size`.
pub fn jitter_ndc(jitter: Vec2, width: u32, height: u32) -> Vec2 {
    Vec2::new(2.0 * jitter.x / width.max(1) as f32, 2.0 * jitter.y / height.max(1) as f32)
}

/// The `index`th point of the Halton(2, 3) sequence centred on the pixel: a jitter in
/// `(−0.5, 0.5)²` pixels, the usual sequence for temporal anti-aliasing. Index 0 is skipped (it
/// would be the corner, −0.5).
pub fn halton_jitter(index: u64) -> Vec2 {
    let radical = |mut i: u64, base: u64| {
        let (mut f, mut r) = (1.0f64, 0.0f64);
        while i > 0 {
            f /= base as f64;
            r += f * (i % base) as f64;
            i /= base;
        }
        r
    };
    let i = index + 1;
    Vec2::new((radical(i, 2) - 0.5) as f32, (radical(i, 3) - 0.5) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn project(m: Mat4, p: glam::Vec3) -> glam::Vec3 {
        let c = m * p.extend(1.0);
        c.truncate() / c.w
    }

    #[test]
    fn off_centre_edges_land_on_the_ndc_border() {
        let p = Projection::OffCenter { left_deg: -40.0, right_deg: 30.0, up_deg: 35.0, down_deg: -45.0, far: 50.0 };
        let m = p.parts(1.0, 0.25).matrix();
        let at = |deg_x: f32, deg_y: f32, d: f32| {
            project(m, glam::Vec3::new(deg_x.to_radians().tan() * d, deg_y.to_radians().tan() * d, -d))
        };
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        let left_down = at(-40.0, -45.0, 2.0);
        let right_up = at(30.0, 35.0, 7.0);
        assert!(close(left_down.x, -1.0) && close(left_down.y, 1.0), "{left_down}");
        assert!(close(right_up.x, 1.0) && close(right_up.y, -1.0), "{right_up}");
        assert!(close(at(0.0, 0.0, 0.25).z, 1.0) && close(at(0.0, 0.0, 50.0).z, 0.0));
    }

    #[test]
    fn finite_far_maps_near_to_one_and_far_to_zero() {
        let m = Projection::PerspectiveFar { fov_y_deg: 60.0, far: 100.0 }.parts(1.5, 0.5).matrix();
        let z = |d: f32| project(m, glam::Vec3::new(0.0, 0.0, -d)).z;
        assert!((z(0.5) - 1.0).abs() < 1e-6 && z(100.0).abs() < 1e-6 && z(101.0) < 0.0);
        assert!((z(1.0) - 0.5 * 99.0 / 99.5).abs() < 1e-6);
    }

    #[test]
    fn matrices_decompose_into_the_projection_that_made_them() {
        let cases = [
            (
                Projection::OffCenter {
                    left_deg: -50.0,
                    right_deg: 40.0,
                    up_deg: 45.0,
                    down_deg: -52.5,
                    far: f32::INFINITY,
                },
                0.05,
            ),
            (
                Projection::OffCenter { left_deg: -30.0, right_deg: 30.0, up_deg: 20.0, down_deg: -20.0, far: 1000.0 },
                0.1,
            ),
            (Projection::OrthographicOffCenter { left: -3.0, right: 5.0, bottom: -1.0, top: 2.0, far: 80.0 }, 0.5),
        ];
        for (projection, near) in cases {
            let m = projection.parts(1.0, near).matrix();
            let (back, back_near) = Projection::from_matrix(m).unwrap();
            let again = back.parts(1.0, back_near).matrix();
            for (x, y) in m.to_cols_array().iter().zip(again.to_cols_array()) {
                assert!((x - y).abs() <= 1e-5 * x.abs().max(1.0), "{projection:?} → {back:?}: {m} vs {again}");
            }
            assert!((back_near - near).abs() <= 1e-5 * near, "{back_near} vs {near}");
        }
        // A symmetric perspective decomposes to the same numbers.
        let parts = Projection::Perspective { fov_y_deg: 70.0 }.parts(16.0 / 9.0, 0.1);
        let back = ProjectionParts::from_matrix(parts.matrix()).unwrap();
        assert_eq!(back, parts);
    }

    #[test]
    fn bad_matrices_are_refused_with_the_reason() {
        let good = Projection::PerspectiveFar { fov_y_deg: 60.0, far: 100.0 }.parts(1.0, 0.1).matrix();
        let with = |col: usize, row: usize, v: f32| {
            let mut c = good.to_cols_array_2d();
            c[col][row] = v;
            Mat4::from_cols_array_2d(&c)
        };
        let refused = |m: Mat4, words: &str| {
            let e = ProjectionParts::from_matrix(m).expect_err(words);
            assert!(e.contains(words), "{e:?} should say {words:?}");
        };
        refused(with(0, 0, f32::NAN), "non-finite");
        refused(with(3, 2, f32::INFINITY), "non-finite");
        refused(Mat4::ZERO, "singular");
        refused(with(1, 0, 0.3), "skewed");
        refused(with(3, 0, 0.3), "skewed");
        refused(with(1, 1, 1.7), "Vulkan's NDC y points down");
        refused(with(0, 0, -1.7), "mirrored");
        refused(good.transpose(), "transposed");
        // Standard (not reversed) Z: depth 0 at near, 1 at far.
        let (n, f) = (0.1f32, 100.0f32);
        refused(with(2, 2, -f / (f - n)), "not reversed-Z");
        refused(with(3, 2, -n * f / (f - n)), "not reversed-Z");
        let ortho = Projection::Orthographic { height: 4.0, far: 50.0 }.parts(1.0, 1.0).matrix();
        let mut c = ortho.to_cols_array_2d();
        c[2][2] = -c[2][2];
        refused(Mat4::from_cols_array_2d(&c), "not reversed-Z");
        let mut c = ortho.to_cols_array_2d();
        c[2][0] = 0.5;
        refused(Mat4::from_cols_array_2d(&c), "oblique");
        let mut c = ortho.to_cols_array_2d();
        c[3][2] = 0.5;
        refused(Mat4::from_cols_array_2d(&c), "in front of the eye");
    }

    #[test]
    fn jitter_moves_every_depth_by_the_same_pixels() {
        let parts = Projection::Perspective { fov_y_deg: 60.0 }.parts(2.0, 0.1);
        let (w, h) = (64, 32);
        let (m0, m1) = (parts.matrix(), parts.jittered(Vec2::new(0.25, -0.5), w, h).matrix());
        for d in [0.2f32, 3.0, 1e4] {
            let p = glam::Vec3::new(0.3 * d, -0.1 * d, -d);
            let (a, b) = (project(m0, p), project(m1, p));
            let px = (b.truncate() - a.truncate()) * Vec2::new(w as f32, h as f32) * 0.5;
            assert!((px - Vec2::new(0.25, -0.5)).abs().max_element() < 1e-3, "{px} at {d}");
            assert_eq!(a.z, b.z);
        }
    }

    #[test]
    fn halton_jitter_stays_in_the_pixel_and_covers_it() {
        let points: Vec<Vec2> = (0..16).map(halton_jitter).collect();
        assert!((points[0] - Vec2::new(0.0, 1.0 / 3.0 - 0.5)).length() < 1e-6, "{}", points[0]);
        assert!(points.iter().all(|p| p.abs().max_element() < 0.5));
        let quadrants: std::collections::BTreeSet<(bool, bool)> =
            points.iter().map(|p| (p.x > 0.0, p.y > 0.0)).collect();
        assert_eq!(quadrants.len(), 4);
    }
}
