//! Conservative culling math: frustum tests, screen rectangles with nearest depths, and the Hi-Z
//! level choice, for bounding spheres and axis-aligned boxes given relative to the eye.
//!
//! This is the CPU twin of `shaders/common/cull_math.glsl`. Each function here has a GLSL
//! counterpart with the same name prefixed by `cull_` (`project_sphere` ↔ `cull_project_sphere`)
//! that performs the same `f32` operations in the same order (the GLSL marks them `precise` so
//! that no multiply-add is fused), so that the two agree decision for decision; the tests in
//! `tests/cull_math_gpu.rs` check it.
//!
//! # How the computation stays conservative
//!
//! Every quantity is computed in `f32` and then widened by an error allowance that bounds the
//! rounding error of the whole computation, including the rotation into view space:
//!
//! - `M` is an upper bound on the length of every point of the bound (`|center|₁ + r` for a
//!   sphere, the largest `|corner|₁` for a box; the L1 norm bounds the L2 norm). A rotated point
//!   carries an absolute error of a few `ε·M` (`ε = 2⁻²⁴`).
//! - Distances along the view axis are lowered by `REL_EPS · M` ([`REL_EPS`] = 32 ε): `d_lo` is a
//!   lower bound on the true nearest distance. If `d_lo < near` the bound may reach the near plane:
//!   it is visible and not projected ([`ScreenBounds::CrossesNear`]).
//! - Perspective screen extents are tangents `t = x / d`. With the inputs perturbed by `c·ε·M`
//!   and a handful of rounded operations, the computed `t` is within
//!   `c'·ε·(M / d_lo)·(1 + |t|)` of the exact one (the derivation is on [`project_sphere`] and
//!   [`project_aabb`]; `c'` ≤ 8 for both), so each extent is pushed outward by
//!   `REL_EPS·(M / d_lo)·(1 + |t|)`, four times that. When `M / d_lo` exceeds [`MAX_CONDITION`] the
//!   first-order bound would no longer be reliable and the bound is treated as crossing the near
//!   plane (visible) instead: its nearest point is then within `M / 32768` of the eye.
//! - Orthographic extents are `x ± r` (or corner `x`), pushed out by `REL_EPS · M`.
//! - The conversion to pixels, `(ndc + 1)·W/2`, is pushed out by [`PIXEL_EPS`]`·max(W, H)`
//!   pixels (2⁻¹⁸ per pixel of viewport: 32 times the rounding of a coordinate of that size),
//!   then `x0 = floor(lo)`, `x1 = floor(hi)`.
//! - The nearest depth uses `d_lo`, so it lies at least `32 ε` (relative) above the exact depth of
//!   the nearest point, which also absorbs the rasterizer's own depth rounding (a few ulps for
//!   `D32_SFLOAT`). Orthographic depth adds `REL_EPS · far / (far − near)` for the same reason.
//!
//! NaN or infinite inputs give "visible" (kept by the frustum tests, `CrossesNear` for the
//! projections).

use crate::scene::{Camera, ProjectionParts};
use glam::{Mat3, UVec2, Vec2, Vec3};

/// Relative error allowance `K·ε` with `K = 32`, `ε = 2⁻²⁴`: distances and view-space extents are
/// widened by `REL_EPS · M` where `M` bounds the length of the bound's points (see the module docs).
/// About 4 times the worst rounding error of the computation it covers.
pub const REL_EPS: f32 = 1.0 / 524_288.0; // 2^-19

/// Pixel allowance per pixel of the viewport's larger side (2⁻¹⁸): the rounding of
/// `(ndc + 1)·W/2` with `|ndc| ≤ 2` is below `2⁻²²·W`, so `max(W, H)·2⁻¹⁸` is 16 times that
/// (`1/64` pixel at 4096, `1/16` at 16384).
pub const PIXEL_EPS: f32 = 1.0 / 262_144.0; // 2^-18

/// Pixels the small-object test widens a rectangle by beyond [`PIXEL_EPS`]: a rasterizer snaps
/// vertices to a sub-pixel grid of at least 4 bits (Vulkan's minimum), which moves an edge by up
/// to 1/32 pixel, and the vertex shader's own rounding of a bound with `M / d_lo` ≤
/// [`SMALL_CONDITION`] moves it by less than 1/16 pixel at 16384 pixels (`8ε·(M/d_lo)·(1 + |t|)`
/// in tangent, times `W/2·s`); 1/8 covers both.
pub const SAMPLE_MARGIN: f32 = 0.125;

/// Largest `M / d_lo` (perspective), or `M·s_y / 2` (orthographic: `M` over half the view's
/// height), for which the small-object test is made; a bound conditioned worse is taken to cover
/// a sample. Small objects are far from the eye compared with their size, where this is about 2.
pub const SMALL_CONDITION: f32 = 4.0;

/// The sample positions of Vulkan's standard 1, 2, 4 and 8-sample patterns together, in
/// sixteenths of a pixel from its top-left corner: a bound holding none of them in any pixel
/// makes no fragment at any of those sample counts. GLSL: `CULL_SAMPLES`.
pub const STANDARD_SAMPLES: [(u8, u8); 15] = [
    (8, 8),
    (12, 12),
    (4, 4),
    (6, 2),
    (14, 6),
    (2, 10),
    (10, 14),
    (9, 5),
    (7, 11),
    (13, 9),
    (5, 3),
    (3, 13),
    (1, 7),
    (11, 15),
    (15, 1),
];

/// Largest accepted `M / d_lo` (2¹⁵) for a perspective projection: beyond it the bound's nearest
/// point is so close to the eye compared with its size that it is treated as crossing the near
/// plane (visible, not projected). This keeps `REL_EPS · M / d_lo ≤ 2⁻⁴`, where the first-order
/// error bound holds with room to spare.
pub const MAX_CONDITION: f32 = 32_768.0; // 2^15

/// Coordinates larger than this (2⁶⁰) in magnitude are treated like NaN: visible, kept. This
/// keeps every square and product in the formulas finite.
pub const MAX_COORD: f32 = 1_152_921_504_606_846_976.0; // 2^60

/// Extents are clamped to ±`BIG` where a tangent's denominator vanishes (never for valid inputs);
/// also the start value of minimum searches (larger than anything a valid input produces).
const BIG: f32 = 1.0e30;

/// What the culling math needs to know about the camera and the target.
///
/// GLSL: `struct CullView` in `cull_math.glsl` (same fields; `orthographic` is a `uint`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CullView {
    /// World→view rotation (view looks down −Z).
    pub rotation: Mat3,
    /// `(sx, sy)`: NDC per unit of `x / d` and `y / d` (perspective: `f / aspect`, `f`) or per
    /// unit of `x` and `y` (orthographic: `2 / (height·aspect)`, `2 / height`). NDC y is `-sy·y…`.
    pub scale: Vec2,
    /// Near-plane distance (depth 1), > 0.
    pub near: f32,
    /// Far-plane distance (depth 0): finite for orthographic, `f32::INFINITY` for a perspective
    /// without a far plane.
    pub far: f32,
    /// Orthographic instead of perspective.
    pub orthographic: bool,
    /// Target size in pixels (the Hi-Z pyramid's level 0).
    pub viewport: UVec2,
    /// `(cx, cy)`: NDC offset of an off-centre projection and of the sub-pixel jitter:
    /// `ndc = (sx·x/d − cx, cy − sy·y/d)` (perspective) or `(sx·x − cx, cy − sy·y)`.
    pub offset: Vec2,
}

impl CullView {
    /// Perspective with vertical field of view `fov_y` (radians), `aspect` = width / height.
    pub fn perspective(rotation: Mat3, fov_y: f32, aspect: f32, near: f32, viewport: UVec2) -> Self {
        let f = 1.0 / (fov_y * 0.5).tan();
        Self {
            rotation,
            scale: Vec2::new(f / aspect, f),
            near,
            far: f32::INFINITY,
            orthographic: false,
            viewport,
            offset: Vec2::ZERO,
        }
    }

    /// Orthographic showing `height` world units vertically, between `near` and `far`.
    pub fn orthographic(rotation: Mat3, height: f32, aspect: f32, near: f32, far: f32, viewport: UVec2) -> Self {
        let sy = 2.0 / height;
        Self {
            rotation,
            scale: Vec2::new(sy / aspect, sy),
            near,
            far,
            orthographic: true,
            viewport,
            offset: Vec2::ZERO,
        }
    }

    /// A view with `rotation` projecting as `parts` onto a `viewport`-sized target.
    pub fn from_parts(rotation: Mat3, parts: &ProjectionParts, viewport: UVec2) -> Self {
        Self {
            rotation,
            scale: parts.scale,
            near: parts.near,
            far: parts.far,
            orthographic: parts.orthographic,
            viewport,
            offset: parts.offset,
        }
    }

    /// The view of `camera` on a `width` × `height` target, jitter included: exactly the numbers
    /// of the matrix the rasterizer draws with ([`Camera::jittered_view_projection_rel_eye`]).
    pub fn from_camera(camera: &Camera, width: u32, height: u32) -> Self {
        let parts = camera.jittered_projection_parts(width, height);
        Self::from_parts(camera.view_rotation(), &parts, UVec2::new(width, height))
    }
}

/// An inclusive rectangle of pixels `[x0, x1] × [y0, y1]` (row 0 at the top).
///
/// GLSL: a `uvec4(x0, y0, x1, y1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// Last column (inclusive).
    pub x1: u32,
    /// Last row (inclusive).
    pub y1: u32,
}

impl PixelRect {
    /// Columns covered (`x1 − x0 + 1`).
    pub fn width(&self) -> u32 {
        self.x1 - self.x0 + 1
    }
    /// Rows covered (`y1 − y0 + 1`).
    pub fn height(&self) -> u32 {
        self.y1 - self.y0 + 1
    }
    /// Whether pixel `(x, y)` is inside.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..=self.x1).contains(&x) && (self.y0..=self.y1).contains(&y)
    }
}

/// Where a bound lands on the screen.
///
/// GLSL: the `CULL_CROSSES_NEAR`, `CULL_OFF_SCREEN`, `CULL_ON_SCREEN` status codes with the
/// rectangle and depth as `out` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScreenBounds {
    /// Some part may be closer than the near plane (or behind the eye, or the eye is inside):
    /// visible, not projected. Also the answer for NaN or infinite input.
    CrossesNear,
    /// Entirely in front of the near plane, and no pixel is touched.
    OffScreen,
    /// Entirely in front of the near plane and touching the pixels of `rect` (clamped to the
    /// screen, conservative).
    OnScreen {
        /// Pixels touched.
        rect: PixelRect,
        /// Largest reversed-Z depth any point of the bound can have (its nearest point), rounded
        /// up by the error allowance.
        nearest_depth: f32,
        /// False when the bound, widened by [`SAMPLE_MARGIN`], holds no sample position of the
        /// standard 1, 2, 4 or 8-sample patterns: nothing inside it can make a fragment, so
        /// culling it changes no image. True when it may, or when the bound is conditioned too
        /// badly to tell ([`SMALL_CONDITION`]).
        covers_sample: bool,
    },
}

/// `Mat3 * p` with the summation order of the GLSL twin: `(r0·x + r1·y) + r2·z` per row.
/// GLSL: `cull_to_view`.
pub fn to_view(r: &Mat3, p: Vec3) -> Vec3 {
    Vec3::new(
        (r.x_axis.x * p.x + r.y_axis.x * p.y) + r.z_axis.x * p.z,
        (r.x_axis.y * p.x + r.y_axis.y * p.y) + r.z_axis.y * p.z,
        (r.x_axis.z * p.x + r.y_axis.z * p.y) + r.z_axis.z * p.z,
    )
}

/// `|x| + |y| + |z|`, an upper bound of the length. GLSL: `cull_l1`.
fn l1(v: Vec3) -> f32 {
    (v.x.abs() + v.y.abs()) + v.z.abs()
}

/// `a·b` in the fixed order `(x + y) + z`. GLSL: `cull_dot`.
fn dot3(a: Vec3, b: Vec3) -> f32 {
    (a.x * b.x + a.y * b.y) + a.z * b.z
}

/// Finite and at most [`MAX_COORD`] in magnitude. GLSL: `cull_finite3`.
fn finite3(v: Vec3) -> bool {
    finite1(v.x) && finite1(v.y) && finite1(v.z)
}

/// Finite and at most [`MAX_COORD`] in magnitude (false for NaN). GLSL: `cull_finite1`.
fn finite1(v: f32) -> bool {
    v.abs() <= MAX_COORD
}

/// Frustum test of a sphere (eye-relative `center`, `radius` ≥ 0): `false` only when the sphere
/// lies entirely outside one plane of the view frustum (the four sides and the near plane; also
/// the far plane for orthographic), with the distance to the plane beyond `radius + REL_EPS·M`.
///
/// Conservative: a sphere that intersects the frustum is always kept (as may be one near a
/// corner that does not). Planes, in view space with `d = −z` and the offset `(cx, cy)`:
/// perspective `sx·x + (1 − cx)·d ≥ 0`, `−sx·x + (1 + cx)·d ≥ 0` (normal length
/// `√(sx² + (1 ∓ cx)²)`), the same in y, `near ≤ d ≤ far` (`far` may be infinite);
/// orthographic `sx·x − cx ≥ −1`, `sx·x − cx ≤ 1`, the same in y, `near ≤ d ≤ far`, with
/// `REL_EPS·|c|` more room for the rounding of the offset.
/// The perspective side planes pass through the eye, so any field of view below 180°, any
/// aspect, offset and near distance work. The allowance `REL_EPS·M·|n|` also covers the
/// rounding of `(1 ∓ c)·d` (relative `ε`, and `M ≥ d`).
///
/// GLSL: `bool cull_sphere_in_frustum(CullView view, vec3 center, float radius)`.
pub fn sphere_in_frustum(view: &CullView, center: Vec3, radius: f32) -> bool {
    if !finite3(center) || !finite1(radius) {
        return true;
    }
    let c = to_view(&view.rotation, center);
    let d = -c.z;
    let rm = radius + REL_EPS * (l1(center) + radius);
    let (sx, sy) = (view.scale.x, view.scale.y);
    let (cx, cy) = (view.offset.x, view.offset.y);
    if d + rm < view.near || d - rm > view.far {
        return false;
    }
    if !view.orthographic {
        let (wl, wr, wb, wt) = (1.0 - cx, 1.0 + cx, 1.0 - cy, 1.0 + cy);
        let (ll, lr) = ((sx * sx + wl * wl).sqrt(), (sx * sx + wr * wr).sqrt());
        let (lb, lt) = ((sy * sy + wb * wb).sqrt(), (sy * sy + wt * wt).sqrt());
        let sxx = sx * c.x;
        let syy = sy * c.y;
        if sxx + wl * d < -(rm * ll) || wr * d - sxx < -(rm * lr) {
            return false;
        }
        if syy + wb * d < -(rm * lb) || wt * d - syy < -(rm * lt) {
            return false;
        }
    } else {
        let (ox, oy) = (REL_EPS * cx.abs(), REL_EPS * cy.abs());
        if sx * (c.x - rm) - cx > 1.0 + ox || sx * (c.x + rm) - cx < -(1.0 + ox) {
            return false;
        }
        if sy * (c.y - rm) - cy > 1.0 + oy || sy * (c.y + rm) - cy < -(1.0 + oy) {
            return false;
        }
    }
    true
}

/// Frustum test of an axis-aligned box given by its eye-relative corners `min`, `max` (world
/// axes): `false` only when the box lies entirely outside one frustum plane, by more than
/// `REL_EPS·M·|n|`.
///
/// Each view-space plane `n·v + w ≥ 0` is moved to eye-relative world space (`n_w = Rᵀ n`, so
/// the rows of the rotation combine) and the box's farthest point along it is
/// `n_w·center + |n_w|·half` (exact for a box). Same planes as [`sphere_in_frustum`].
///
/// GLSL: `bool cull_aabb_in_frustum(CullView view, vec3 bmin, vec3 bmax)`.
pub fn aabb_in_frustum(view: &CullView, min: Vec3, max: Vec3) -> bool {
    if !finite3(min) || !finite3(max) {
        return true;
    }
    let center = (min + max) * 0.5;
    let half = (max - min).abs() * 0.5;
    let m = REL_EPS * (l1(center) + l1(half));
    let r = &view.rotation;
    // Rows of the rotation: the view axes in world coordinates.
    let row0 = Vec3::new(r.x_axis.x, r.y_axis.x, r.z_axis.x);
    let row1 = Vec3::new(r.x_axis.y, r.y_axis.y, r.z_axis.y);
    let row2 = Vec3::new(r.x_axis.z, r.y_axis.z, r.z_axis.z);
    // Largest value of n·p + w over the box.
    let reach = |n: Vec3, w: f32| (dot3(n, center) + dot3(n.abs(), half)) + w;
    let (sx, sy) = (view.scale.x, view.scale.y);
    let (cx, cy) = (view.offset.x, view.offset.y);
    // d = -row2·p ≥ near; far - d = far + row2·p ≥ 0 (never false for an infinite far).
    if reach(-row2, -view.near) < -m || reach(row2, view.far) < -m {
        return false;
    }
    let (ax, ay) = (row0 * sx, row1 * sy);
    let (wl, wr, wb, wt) = (1.0 - cx, 1.0 + cx, 1.0 - cy, 1.0 + cy);
    if !view.orthographic {
        let (ll, lr) = ((sx * sx + wl * wl).sqrt(), (sx * sx + wr * wr).sqrt());
        let (lb, lt) = ((sy * sy + wb * wb).sqrt(), (sy * sy + wt * wt).sqrt());
        if reach(ax - row2 * wl, 0.0) < -(m * ll) || reach(-ax - row2 * wr, 0.0) < -(m * lr) {
            return false;
        }
        if reach(ay - row2 * wb, 0.0) < -(m * lb) || reach(-ay - row2 * wt, 0.0) < -(m * lt) {
            return false;
        }
    } else {
        let (ox, oy) = (REL_EPS * cx.abs(), REL_EPS * cy.abs());
        if reach(ax, wl) < -(m * sx) - ox || reach(-ax, wr) < -(m * sx) - ox {
            return false;
        }
        if reach(ay, wb) < -(m * sy) - oy || reach(-ay, wt) < -(m * sy) - oy {
            return false;
        }
    }
    true
}

/// The two tangents `x/d` from the eye to the circle of radius `r` around `(a, d)` in a plane
/// through the view axis (Mara & McGuire 2013): `(lo, hi)`.
///
/// With `ρ² = a² + d²`, `v = √(ρ² − r²)` and the circle's center at angle `θ` from the axis and
/// half-angle `α` (`sin α = r/ρ`): `v·a ∓ r·d = ρ² sin(θ ∓ α)`, `v·d ± r·a = ρ² cos(θ ∓ α)`, so
/// the quotients are `tan(θ ∓ α)`. `czr2 = (d − r)(d + r)` is passed in factored form, which
/// keeps it accurate when `d ≈ r` (no cancellation of `d² − r²`). The denominators are
/// `ρ² cos(θ ∓ α) ≥ ρ²·d_lo / M > 0` for a circle in front of the eye.
///
/// GLSL: `vec2 cull_tangents(float a, float d, float r, float czr2)`.
fn tangents(a: f32, d: f32, r: f32, czr2: f32) -> (f32, f32) {
    let v = (a * a + czr2).sqrt();
    let num_lo = v * a - r * d;
    let den_lo = v * d + r * a;
    let num_hi = v * a + r * d;
    let den_hi = v * d - r * a;
    let lo = if den_lo > 0.0 { (num_lo / den_lo).max(-BIG) } else { -BIG };
    let hi = if den_hi > 0.0 { (num_hi / den_hi).min(BIG) } else { BIG };
    (lo, hi)
}

/// Converts NDC extents (already widened) to the inclusive pixel rectangle: `None` when off
/// screen. `lo`/`hi` are `(x, y)` in NDC (y down).
///
/// `px = (clamp(ndc, −2, 2) + 1)·W/2 ∓ PIXEL_EPS·max(W, H)`, `x0 = floor(px_lo)`,
/// `x1 = floor(px_hi)`; off screen when `x1 < 0` or `x0 ≥ W` (or the same in y); then clamped to
/// `[0, W−1] × [0, H−1]`. Clamping NDC to ±2 keeps the numbers small without changing which
/// pixels are touched.
///
/// GLSL: `bool cull_pixel_rect(CullView view, vec2 lo, vec2 hi, out uvec4 rect)`.
/// With the rectangle, whether the extents widened by [`SAMPLE_MARGIN`] may hold a sample
/// position ([`box_covers_sample`]; always when `testable` is false).
///
/// GLSL: `bool cull_pixel_rect(CullView view, vec2 lo, vec2 hi, bool testable, out uvec4 rect,
/// out bool covers_sample)`.
fn pixel_rect(view: &CullView, lo: Vec2, hi: Vec2, testable: bool) -> Option<(PixelRect, bool)> {
    let w = view.viewport.x as f32;
    let h = view.viewport.y as f32;
    let pe = w.max(h) * PIXEL_EPS;
    let fx_lo = (lo.x.clamp(-2.0, 2.0) + 1.0) * (0.5 * w) - pe;
    let fx_hi = (hi.x.clamp(-2.0, 2.0) + 1.0) * (0.5 * w) + pe;
    let fy_lo = (lo.y.clamp(-2.0, 2.0) + 1.0) * (0.5 * h) - pe;
    let fy_hi = (hi.y.clamp(-2.0, 2.0) + 1.0) * (0.5 * h) + pe;
    let covers_sample = !testable
        || box_covers_sample(
            fx_lo - SAMPLE_MARGIN,
            fx_hi + SAMPLE_MARGIN,
            fy_lo - SAMPLE_MARGIN,
            fy_hi + SAMPLE_MARGIN,
        );
    let (x_lo, x_hi, y_lo, y_hi) = (fx_lo.floor(), fx_hi.floor(), fy_lo.floor(), fy_hi.floor());
    if x_hi < 0.0 || y_hi < 0.0 || x_lo >= w || y_lo >= h {
        return None;
    }
    let rect = PixelRect {
        x0: x_lo.max(0.0) as u32,
        y0: y_lo.max(0.0) as u32,
        x1: x_hi.min(w - 1.0) as u32,
        y1: y_hi.min(h - 1.0) as u32,
    };
    Some((rect, covers_sample))
}

/// Whether the pixel-space box `[x_lo, x_hi] × [y_lo, y_hi]` (inclusive; y down, pixel `i`
/// spanning `[i, i + 1)`) holds a sample position of any standard pattern
/// ([`STANDARD_SAMPLES`]). A box 2 pixels or more across, or with NaN, always does.
///
/// GLSL: `bool cull_box_covers_sample(float x_lo, float x_hi, float y_lo, float y_hi)`.
pub fn box_covers_sample(x_lo: f32, x_hi: f32, y_lo: f32, y_hi: f32) -> bool {
    // NaN extents compare as not narrow: covered.
    let narrow = |a: f32, b: f32| (b - a).partial_cmp(&2.0) == Some(std::cmp::Ordering::Less);
    if !narrow(x_lo, x_hi) || !narrow(y_lo, y_hi) {
        return true;
    }
    let mut py = y_lo.floor();
    while py <= y_hi {
        let mut px = x_lo.floor();
        while px <= x_hi {
            for &(sx, sy) in &STANDARD_SAMPLES {
                let x = px + sx as f32 * 0.0625;
                let y = py + sy as f32 * 0.0625;
                if x >= x_lo && x <= x_hi && y >= y_lo && y <= y_hi {
                    return true;
                }
            }
            px += 1.0;
        }
        py += 1.0;
    }
    false
}

/// Finishes a projection from view-space extents: `t` = x extent `(lo, hi)`, `u` = y extent
/// (y up), each with its outward allowance `e`, and the lowered nearest distance `d_lo`.
/// `testable`: the bound is conditioned well enough for the small-object test
/// ([`SMALL_CONDITION`]).
fn finish(
    view: &CullView,
    t: (f32, f32, f32, f32),
    u: (f32, f32, f32, f32),
    d_lo: f32,
    testable: bool,
) -> ScreenBounds {
    let (sx, sy) = (view.scale.x, view.scale.y);
    let (cx, cy) = (view.offset.x, view.offset.y);
    let (ox, oy) = (REL_EPS * cx.abs(), REL_EPS * cy.abs());
    let lo = Vec2::new((sx * (t.0 - t.2) - cx) - ox, (cy - sy * (u.1 + u.3)) - oy);
    let hi = Vec2::new((sx * (t.1 + t.3) - cx) + ox, (cy - sy * (u.0 - u.2)) + oy);
    let nearest_depth = if view.orthographic {
        (view.far - (d_lo - REL_EPS * view.far)) / (view.far - view.near)
    } else if view.far <= MAX_COORD {
        // near·far / (d·(far − near)) − near / (far − near), the first term raised by REL_EPS
        // (relative) for the rounding here and the rasterizer's (a few ε of it each). While
        // d_lo ≤ far the first term is the larger, so that covers the second's rounding too;
        // beyond the far plane nothing is drawn (true depths < 0), and 0 bounds them.
        let k = (view.near / d_lo) * (view.far / (view.far - view.near));
        ((k + REL_EPS * k) - view.near / (view.far - view.near)).max(0.0)
    } else {
        view.near / d_lo
    };
    match pixel_rect(view, lo, hi, testable) {
        Some((rect, covers_sample)) => ScreenBounds::OnScreen { rect, nearest_depth, covers_sample },
        None => ScreenBounds::OffScreen,
    }
}

/// Screen rectangle and nearest depth of a sphere (eye-relative `center`, `radius` ≥ 0).
///
/// Steps (GLSL `uint cull_project_sphere(CullView view, vec3 center, float radius,
/// out uvec4 rect, out float nearest_depth)` does the same):
/// 1. `c = R·center`, `d = −c.z`, `M = |center|₁ + r`, `d_lo = (d − r) − REL_EPS·M`.
/// 2. `d_lo < near` (or NaN) → [`ScreenBounds::CrossesNear`]. Perspective also when
///    `M > d_lo·MAX_CONDITION`.
/// 3. Perspective: the exact extents of the projected sphere, separately in x and y (Mara &
///    McGuire 2013; see `tangents`): the projection of a sphere onto the plane spanned by the
///    view axis and x is the disk of radius `r` around `(c.x, d)`, and its x/d range is bounded by
///    the two tangents from the eye. Exact rather than the 8 corners of the sphere's view-space
///    box, which are conservative too (the box contains the sphere and lies in front of the eye)
///    but up to `√2`× wider off-axis and far wider near the eye.
///    Error: the rotation moves `c` by ≤ 3ε·M, which turns a tangent by at most
///    `3εM/v` radians (`v` = distance to the tangent point), i.e. `3εM/d_t·√(1+t²)` in `t`; the
///    formula's own rounding gives numerator and denominator errors ≤ 3ερ² against a
///    denominator `ρ² cos θ_t`, i.e. ≤ `6ε(1 + |t|)·√(1+t²)` in `t`; with `√(1+t²) ≤ M/d_lo` both
///    are below `8ε·(M/d_lo)·(1 + |t|)`, and the allowance is `REL_EPS·(M/d_lo)·(1 + |t|)`.
///    Orthographic: `c.x ± r`, `c.y ± r`, allowance `REL_EPS·M`.
/// 4. NDC `sx·t − cx` and `cy − sy·u`, widened by `REL_EPS·|c|` for the offset's rounding; pixel
///    rectangle as described on the module; nearest depth `near / d_lo` (perspective, infinite
///    far), `max(k·(1 + REL_EPS) − near/(far − near), 0)` with `k = (near/d_lo)·far/(far − near)`
///    (perspective, finite far: while `d_lo ≤ far`, `k` is the larger term, so its allowance
///    covers the subtraction and the rasterizer's own rounding of `near·far/(far − near)/d`; past
///    the far plane nothing is drawn and 0 bounds every depth) or
///    `(far − d_lo + REL_EPS·far)/(far − near)` (orthographic).
pub fn project_sphere(view: &CullView, center: Vec3, radius: f32) -> ScreenBounds {
    if !finite3(center) || !finite1(radius) || radius < 0.0 {
        return ScreenBounds::CrossesNear;
    }
    let c = to_view(&view.rotation, center);
    let d = -c.z;
    let m = l1(center) + radius;
    let margin = REL_EPS * m;
    let d_lo = (d - radius) - margin;
    // NaN compares false: not in front.
    if d_lo.is_nan() || d_lo < view.near {
        return ScreenBounds::CrossesNear;
    }
    if view.orthographic {
        let t = (c.x - radius, c.x + radius, margin, margin);
        let u = (c.y - radius, c.y + radius, margin, margin);
        let testable = m * view.scale.y <= 2.0 * SMALL_CONDITION;
        return finish(view, t, u, d_lo, testable);
    }
    if m > d_lo * MAX_CONDITION {
        return ScreenBounds::CrossesNear;
    }
    let q = margin / d_lo;
    let czr2 = (d - radius) * (d + radius);
    let (tx_lo, tx_hi) = tangents(c.x, d, radius, czr2);
    let (ty_lo, ty_hi) = tangents(c.y, d, radius, czr2);
    let t = (tx_lo, tx_hi, q * (1.0 + tx_lo.abs()), q * (1.0 + tx_hi.abs()));
    let u = (ty_lo, ty_hi, q * (1.0 + ty_lo.abs()), q * (1.0 + ty_hi.abs()));
    finish(view, t, u, d_lo, m <= d_lo * SMALL_CONDITION)
}

/// Screen rectangle and nearest depth of an axis-aligned box with eye-relative corners `min`,
/// `max` (world axes; the box they span, whichever way round).
///
/// Steps (GLSL `uint cull_project_aabb(CullView view, vec3 bmin, vec3 bmax, out uvec4 rect,
/// out float nearest_depth)` does the same):
/// 1. The 8 corners (exact: each coordinate is one of the inputs) are rotated to view space;
///    `d_min` = their smallest `−z`; `M = Σ_axes max(|min|, |max|)`; `d_lo = d_min − REL_EPS·M`.
/// 2. `d_lo < near` → [`ScreenBounds::CrossesNear`] (perspective also when
///    `M > d_lo·MAX_CONDITION`).
/// 3. Perspective: `t = x/d`, `u = y/d` of each corner; min and max. For a box entirely in front
///    of the eye the projection is the convex hull of the projected corners, so this is exact.
///    Error: a corner's rotated coordinates are off by ≤ 3εM, so `t` by
///    `≤ 3εM(1 + |t|)/d + ε|t| ≤ 4ε(M/d_lo)(1 + |t|)`; allowance `REL_EPS·(M/d_lo)·(1 + |t|)`.
///    Orthographic: corner `x`, `y` min and max, allowance `REL_EPS·M`.
/// 4. As for the sphere.
pub fn project_aabb(view: &CullView, min: Vec3, max: Vec3) -> ScreenBounds {
    if !finite3(min) || !finite3(max) {
        return ScreenBounds::CrossesNear;
    }
    let m = (min.x.abs().max(max.x.abs()) + min.y.abs().max(max.y.abs())) + min.z.abs().max(max.z.abs());
    let margin = REL_EPS * m;
    let mut corners = [Vec3::ZERO; 8];
    let mut d_min = BIG;
    for (i, corner) in corners.iter_mut().enumerate() {
        let p = Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        );
        *corner = to_view(&view.rotation, p);
        d_min = d_min.min(-corner.z);
    }
    let d_lo = d_min - margin;
    // NaN compares false: not in front.
    if d_lo.is_nan() || d_lo < view.near {
        return ScreenBounds::CrossesNear;
    }
    let (mut t_lo, mut t_hi, mut u_lo, mut u_hi) = (BIG, -BIG, BIG, -BIG);
    if view.orthographic {
        for v in &corners {
            (t_lo, t_hi) = (t_lo.min(v.x), t_hi.max(v.x));
            (u_lo, u_hi) = (u_lo.min(v.y), u_hi.max(v.y));
        }
        let testable = m * view.scale.y <= 2.0 * SMALL_CONDITION;
        return finish(view, (t_lo, t_hi, margin, margin), (u_lo, u_hi, margin, margin), d_lo, testable);
    }
    if m > d_lo * MAX_CONDITION {
        return ScreenBounds::CrossesNear;
    }
    for v in &corners {
        let d = -v.z;
        let (t, u) = (v.x / d, v.y / d);
        (t_lo, t_hi) = (t_lo.min(t), t_hi.max(t));
        (u_lo, u_hi) = (u_lo.min(u), u_hi.max(u));
    }
    let q = margin / d_lo;
    let t = (t_lo, t_hi, q * (1.0 + t_lo.abs()), q * (1.0 + t_hi.abs()));
    let u = (u_lo, u_hi, q * (1.0 + u_lo.abs()), q * (1.0 + u_hi.abs()));
    finish(view, t, u, d_lo, m <= d_lo * SMALL_CONDITION)
}

/// `⌈log₂ n⌉` for `n ≥ 1` (0 for `n ≤ 1`). GLSL: `cull_ceil_log2` (`findMSB(n − 1) + 1`).
pub fn ceil_log2(n: u32) -> u32 {
    if n <= 1 {
        0
    } else {
        32 - (n - 1).leading_zeros()
    }
}

/// The Hi-Z level for a rectangle: `L = ⌈log₂ max(w, h)⌉` with `w = x1 − x0 + 1`,
/// `h = y1 − y0 + 1` in level-0 texels (pixels). The caller clamps `L` to the pyramid's last level.
///
/// **The rectangle touches at most 2×2 texels of level `L`, for every alignment.** Level `L`
/// texel `t` of an axis covers pixels `t·2^L … t·2^L + 2^L − 1`, except the last texel, which
/// also covers everything beyond (the pyramid folds the dropped row/column of odd levels into
/// it; see [`crate::cull::hiz`]): pixel `x` is covered by `min(x >> L, size_L − 1)`.
/// Since `w ≤ 2^L`, `x1 − x0 < 2^L`. Let `a = x0 >> L` and `b = x1 >> L`; then
/// `b·2^L ≤ x1 < x0 + 2^L < (a + 1)·2^L + 2^L`, so `b < a + 2`, i.e. `b ≤ a + 1`.
/// `min(·, size_L − 1)` is monotone and never increases a difference, so the clamped texels
/// `tx0 = min(a, size_L − 1)` and `tx1 = min(b, size_L − 1)` differ by at most 1 as well, and
/// every pixel `x0 ≤ x ≤ x1` is covered by a texel in `[tx0, tx1]` (monotonicity). The same holds
/// in y. This includes the clamped last texel of odd and non-power-of-two levels, and a level
/// `L` past the pyramid's end (clamped to the last level, 1×1).
///
/// **`floor(log₂)` is not enough**: for `w = 6` it gives level 2 (texels of 4 pixels), and the
/// rectangle `x = 3..8` touches texels 0, 1 and 2; a 2×2 read misses one.
///
/// **Finer variant** ([`crate::cull::hiz::HizVariant::Finer`]): level `L' = max(L − 1, 0)`.
/// Now `x1 − x0 < 2^L = 2·2^L'`, so by the same argument `b ≤ a + 2`: at most 3×3 texels (the
/// test loops over all of them; 4×4 is never needed). Each level-`L'` texel touched is inside the
/// footprint of a level-`L` texel touched, so the finer minimum is never smaller: it culls at
/// least as much as the coarse test.
///
/// GLSL: `uint cull_hiz_level(uvec4 rect)`.
pub fn hiz_level(rect: PixelRect) -> u32 {
    ceil_log2(rect.width().max(rect.height()))
}

#[cfg(test)]
mod tests {

    #[test]
    fn a_box_covers_a_sample_only_when_one_of_the_standard_positions_lies_in_it() {
        // The pixel centre, the 1-sample position.
        assert!(box_covers_sample(0.45, 0.55, 0.45, 0.55));
        // Between every position of pixel (0, 0): the nearest ones are 1/16 from the corner.
        assert!(!box_covers_sample(0.0, 0.05, 0.0, 0.05));
        assert!(!box_covers_sample(10.0, 10.05, 7.0, 7.05));
        // The 8-sample position (1/16, 7/16) on its edge counts (inclusive).
        assert!(box_covers_sample(0.0, 0.0625, 0.4375, 0.5));
        // Starting in the pixel to the left, pixel 0's positions still count.
        assert!(box_covers_sample(-0.1, 0.07, 0.4, 0.45));
        // The 8-sample pattern has positions 1/16 from the corners: a box around a corner
        // between four pixels covers one.
        assert!(box_covers_sample(31.9, 32.1, 31.9, 32.1));
        // Two pixels or more across, or NaN: assumed covered.
        assert!(box_covers_sample(0.0, 2.0, 0.0, 0.01));
        assert!(box_covers_sample(f32::NAN, 0.1, 0.0, 0.1));
        // Every standard position is in the set: a box around any of them covers it.
        for &(x, y) in &STANDARD_SAMPLES {
            let (x, y) = (3.0 + x as f32 / 16.0, 5.0 + y as f32 / 16.0);
            assert!(box_covers_sample(x - 0.01, x + 0.01, y - 0.01, y + 0.01), "({x}, {y})");
        }
    }

    #[test]
    fn a_distant_speck_covers_no_sample_and_a_near_one_is_not_tested() {
        let view = CullView::perspective(Mat3::IDENTITY, 60f32.to_radians(), 1.0, 0.1, UVec2::new(64, 64));
        // A 1 mm box 100 m ahead (a two-thousandth of a pixel) at pixel coordinates (x, y).
        let pixel = 2.0 * 100.0 * (30f32.to_radians()).tan() / 64.0;
        let speck = |x: f32, y: f32| {
            let at = Vec3::new((x - 32.0) * pixel, (32.0 - y) * pixel, -100.0);
            project_aabb(&view, at - Vec3::splat(5e-4), at + Vec3::splat(5e-4))
        };
        let covers = |b: ScreenBounds| match b {
            ScreenBounds::OnScreen { covers_sample, .. } => covers_sample,
            other => panic!("{other:?}"),
        };
        // At (32.3, 32.5) every standard position is more than 1/8 pixel away along x or y.
        assert!(!covers(speck(32.3, 32.5)));
        // On pixel (32, 32)'s centre, or within 1/8 pixel of it: covered.
        assert!(covers(speck(32.5, 32.5)));
        assert!(covers(speck(32.38, 32.5)));
        // A large bound is always taken as covering.
        assert!(covers(project_aabb(&view, Vec3::new(-1.0, -1.0, -11.0), Vec3::new(1.0, 1.0, -9.0))));
    }
    use super::*;

    fn front_view(w: u32, h: u32) -> CullView {
        CullView::perspective(Mat3::IDENTITY, 90f32.to_radians(), w as f32 / h as f32, 0.1, UVec2::new(w, h))
    }

    #[test]
    fn ceil_log2_matches_the_definition() {
        for n in 1..5000u32 {
            let expect = (n as f64).log2().ceil() as u32;
            assert_eq!(ceil_log2(n), expect, "n = {n}");
        }
        assert_eq!(ceil_log2(u32::MAX), 32);
    }

    #[test]
    fn centered_sphere_projects_symmetrically() {
        let view = front_view(100, 100);
        match project_sphere(&view, Vec3::new(0.0, 0.0, -10.0), 1.0) {
            ScreenBounds::OnScreen { rect, nearest_depth, .. } => {
                // tan of the half angle: 1/sqrt(99); 100 px span 2 units of tan at fov 90.
                let half = 50.0 / 99f32.sqrt();
                assert_eq!(rect.x0, (50.0 - half).floor() as u32);
                assert_eq!(rect.x1, (50.0 + half).floor() as u32);
                assert_eq!((rect.x0, rect.x1), (rect.y0, rect.y1));
                assert!((0.1 / 9.0..0.1 / 9.0 * 1.0001).contains(&nearest_depth));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn near_plane_and_eye_inside_are_visible() {
        let view = front_view(64, 64);
        assert_eq!(project_sphere(&view, Vec3::new(0.0, 0.0, -1.0), 0.95), ScreenBounds::CrossesNear);
        assert_eq!(project_sphere(&view, Vec3::ZERO, 5.0), ScreenBounds::CrossesNear);
        assert_eq!(project_sphere(&view, Vec3::new(0.0, 0.0, 5.0), 1.0), ScreenBounds::CrossesNear);
        assert_eq!(project_aabb(&view, Vec3::splat(-1.0), Vec3::splat(1.0)), ScreenBounds::CrossesNear);
        assert_eq!(project_sphere(&view, Vec3::new(f32::NAN, 0.0, -5.0), 1.0), ScreenBounds::CrossesNear);
        assert!(sphere_in_frustum(&view, Vec3::ZERO, 5.0));
        assert!(sphere_in_frustum(&view, Vec3::new(f32::NAN, 0.0, 0.0), 1.0));
        // Behind the eye: outside the frustum.
        assert!(!sphere_in_frustum(&view, Vec3::new(0.0, 0.0, 5.0), 1.0));
        assert!(!aabb_in_frustum(&view, Vec3::new(-1.0, -1.0, 4.0), Vec3::new(1.0, 1.0, 6.0)));
    }

    #[test]
    fn off_screen_and_outside() {
        let view = front_view(64, 64);
        // 45° half-angle: x = 20 at d = 10 is far outside.
        assert_eq!(project_sphere(&view, Vec3::new(20.0, 0.0, -10.0), 1.0), ScreenBounds::OffScreen);
        assert!(!sphere_in_frustum(&view, Vec3::new(20.0, 0.0, -10.0), 1.0));
        assert!(!aabb_in_frustum(&view, Vec3::new(19.0, -1.0, -11.0), Vec3::new(21.0, 1.0, -9.0)));
        // Touching the edge plane: kept.
        assert!(sphere_in_frustum(&view, Vec3::new(10.0 + 2f32.sqrt(), 0.0, -10.0), 1.0));
    }

    #[test]
    fn hiz_level_spans_at_most_two_texels() {
        for w in 1..70u32 {
            let l = hiz_level(PixelRect { x0: 0, y0: 0, x1: w - 1, y1: 0 });
            for x0 in 0..70u32 {
                let x1 = x0 + w - 1;
                assert!((x1 >> l) - (x0 >> l) <= 1, "w {w} x0 {x0}");
                if l > 0 {
                    assert!((x1 >> (l - 1)) - (x0 >> (l - 1)) <= 2, "finer: w {w} x0 {x0}");
                }
            }
        }
    }
}
