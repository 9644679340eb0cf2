//! CPU reference ("oracle") for everything the culling passes decide: the same conservative
//! projection and Hi-Z math as the shaders, exact visibility by ray casting, and image metrics.
//!
//! - [`cull_math`]: frustum tests, screen rectangles and nearest depths of spheres and boxes, the
//!   Hi-Z level choice. Twin of `shaders/common/cull_math.glsl` (same names with a `cull_` prefix,
//!   same operation order, so that the GPU gives the same decisions).
//! - [`hiz`]: the Hi-Z pyramid (any size, MSAA) and the occlusion test. Twin of
//!   `shaders/common/hiz.glsl` (same names with a `hiz_` prefix).
//! - [`raycast`]: which instance each pixel sample sees, by casting primary rays through an
//!   `obvhs` BVH of the scene's world-space triangles.
//! - [`metrics`]: PSNR and mean absolute error of two RGBA8 images.
//! - [`image_error`]: the linear-light box downsample of a supersampled reference, and mean FLIP
//!   and PSNR of an image against it.
//!
//! # Conventions (shared with the shaders)
//!
//! - **Eye-relative inputs.** Positions are world position minus eye, as `f32`, exactly as the GPU
//!   gets them after subtracting the hi/lo split eye position (`instance_rel_eye` in
//!   `scene.glsl`). The view rotation is world→view (a [`glam::Mat3`], row *i* is view axis *i*
//!   in world coordinates); view space is right-handed and looks down −Z, so the distance of a
//!   point in front of the eye is `d = -z_view`.
//! - **Projection** ([`cull_math::CullView`]): perspective
//!   `ndc = (sx·x, −sy·y) / d` with `sx = f / aspect`, `sy = f = 1 / tan(fov_y / 2)`, reversed-Z
//!   depth `near / d` (1 at the near plane, 0 at infinity); orthographic `ndc = (sx·x, −sy·y)` with
//!   `sy = 2 / height`, `sx = sy / aspect`, depth `(far − d) / (far − near)`. The y flip makes
//!   Vulkan's NDC y (pointing down) give an upright image. These are exactly the entries of
//!   [`crate::scene::Camera::projection_matrix`].
//! - **Pixels.** Framebuffer coordinates `px = (ndc.x + 1)·W/2`, `py = (ndc.y + 1)·H/2`; pixel
//!   `(i, j)` is the square `[i, i+1) × [j, j+1)`, row 0 at the top. Rectangles are inclusive
//!   integer ranges `[x0, x1] × [y0, y1]` that cover every pixel whose area the bound's projection
//!   touches (closed squares, so touching an edge counts).
//! - **Depth.** Reversed-Z with an infinite far plane (perspective); `D32_SFLOAT`; the Hi-Z pyramid
//!   keeps the **minimum** (farthest) depth of each footprint; an object is occluded only when its
//!   nearest depth is **strictly** smaller than every texel it touches.
//! - **Near plane.** A bound any part of which may be closer than the near plane (or behind the
//!   eye, or around it) is visible and never projected.
//! - **Conservative.** Every approximation errs toward "visible": a visible object is never
//!   culled. The `f32` error allowances are documented on [`cull_math::REL_EPS`] and
//!   [`cull_math::PIXEL_EPS`] and proved by brute force in `tests/oracle_cull_math.rs`.

pub mod cull_math;
pub mod hiz;
pub mod image_error;
pub mod metrics;
pub mod raycast;
pub mod visibility;

pub use cull_math::{CullView, PixelRect, ScreenBounds};
pub use hiz::{HiZPyramid, HizVariant};
pub use image_error::ImageError;
pub use metrics::ImageDiff;
pub use raycast::{RaycastOracle, SamplePattern, VisibilityImage};
