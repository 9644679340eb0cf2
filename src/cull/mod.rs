//! The culling math on the CPU: the twin of `shaders/common/cull_math.glsl` and
//! `shaders/common/hiz.glsl`, with the same names (without the `cull_`/`hiz_` prefix) and the same
//! operation order, so that the CPU and the GPU reach the same decisions. The passes size their
//! pyramids with it, and verification checks the GPU against it.
//!
//! - [`math`]: frustum tests, screen rectangles and nearest depths of spheres and boxes, the Hi-Z
//!   level choice.
//! - [`hiz`]: the Hi-Z pyramid (any size, MSAA), its level sizes and the occlusion test.
//!
//! # Conventions (shared with the shaders)
//!
//! - **Eye-relative inputs.** Positions are world position minus eye, as `f32`, exactly as the GPU
//!   gets them after subtracting the hi/lo split eye position (`instance_rel_eye` in
//!   `scene.glsl`). The view rotation is world→view (a [`glam::Mat3`], row *i* is view axis *i*
//!   in world coordinates); view space is right-handed and looks down −Z, so the distance of a
//!   point in front of the eye is `d = -z_view`.
//! - **Projection** ([`math::CullView`]): perspective
//!   `ndc = (sx·x/d − cx, cy − sy·y/d)` (symmetric: `sx = f / aspect`, `sy = f = 1 / tan(fov_y / 2)`,
//!   `c = 0`), reversed-Z depth `near / d` (1 at the near plane, 0 at infinity) or, with a finite
//!   far plane, `near·(far − d) / (d·(far − near))`; orthographic `ndc = (sx·x − cx, cy − sy·y)`
//!   (centred: `sy = 2 / height`, `sx = sy / aspect`), depth `(far − d) / (far − near)`. The
//!   offset `(cx, cy)` comes from off-centre projections and the camera's sub-pixel jitter. The y
//!   flip makes Vulkan's NDC y (pointing down) give an upright image. These are exactly the
//!   numbers of the matrix the rasterizer draws with
//!   ([`crate::scene::Camera::jittered_view_projection_rel_eye`]).
//! - **Pixels.** Framebuffer coordinates `px = (ndc.x + 1)·W/2`, `py = (ndc.y + 1)·H/2`; pixel
//!   `(i, j)` is the square `[i, i+1) × [j, j+1)`, row 0 at the top. Rectangles are inclusive
//!   integer ranges `[x0, x1] × [y0, y1]` that cover every pixel whose area the bound's projection
//!   touches (closed squares, so touching an edge counts).
//! - **Depth.** Reversed-Z, perspective with an infinite or a finite far plane; `D32_SFLOAT`; the Hi-Z pyramid
//!   keeps the **minimum** (farthest) depth of each footprint; an object is occluded only when its
//!   nearest depth is **strictly** smaller than every texel it touches.
//! - **Near plane.** A bound any part of which may be closer than the near plane (or behind the
//!   eye, or around it) is visible and never projected.
//! - **Conservative.** Every approximation errs toward "visible": a visible object is never
//!   culled. The `f32` error allowances are documented on [`math::REL_EPS`] and
//!   [`math::PIXEL_EPS`] and proved by brute force in `tests/oracle_cull_math.rs`.

pub mod hiz;
pub mod math;

pub use hiz::{HiZPyramid, HizVariant};
pub use math::{CullView, PixelRect, ScreenBounds};
