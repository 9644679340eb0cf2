//! The supersampled reference of a frame, and the error of any graph's image against it.
//!
//! The reference renders the same scene from the same camera through `builtin:no_cull` (no AA,
//! no culling, the same shading as every graph) at `N·width x N·height`, then box-filters it down
//! to `width x height` in linear light: `N x N` samples per pixel (N = 4 by default, 16 samples).
//! Only the camera makes one frame differ from another in these graphs (no time input), so a
//! fresh renderer's first frame is the same frame.

use super::image_error::{downsample_box_srgb, image_error, ImageError};
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::render::output::{rgba_from_bytes, RgbaImage};
use crate::render::{GraphSpec, RenderSettings, Renderer, ShadowSettings};
use crate::scene::{Camera, Scene};
use std::sync::Arc;

/// Default supersampling factor per axis (`--reference` without a value): 4 x 4 = 16 samples.
pub const DEFAULT_REFERENCE_SCALE: u32 = 4;

/// Params of `graph/no_cull.ron` that a tested graph's overrides pass on to the reference (the
/// same exposure and debug view shade both alike).
const SHARED_PARAMS: &[&str] = &["exposure", "debug_view"];

/// Renders the reference of `camera`'s view of `scene` at `width x height` with `n x n` samples
/// per pixel. The scene is shared: the renderers made here take it without a copy. `overrides` are the tested graph's param overrides; those `no_cull` also has
/// (`exposure`, `debug_view`) apply to the reference too.
///
/// Fails (without rendering) when `n` is 0 or `n·width` or `n·height` exceeds the device's
/// `maxImageDimension2D`.
pub fn render_reference(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Arc<Scene>,
    camera: &Camera,
    size: (u32, u32),
    n: u32,
    overrides: &[(String, String)],
) -> Result<RgbaImage> {
    render_reference_shadowed(ctx, shaders, scene, camera, size, n, overrides, None)
}

/// [`render_reference`] with the sun's shadows drawn as `shadows` says (every caster drawn:
/// the reference culls nothing). For the reference of a shadowed image, give it maps of `n`
/// times the image's resolution, so that its shadow edges are resolved as finely as its pixels.
#[allow(clippy::too_many_arguments)]
pub fn render_reference_shadowed(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Arc<Scene>,
    camera: &Camera,
    (width, height): (u32, u32),
    n: u32,
    overrides: &[(String, String)],
    shadows: Option<&ShadowSettings>,
) -> Result<RgbaImage> {
    let (big_w, big_h) = reference_render_size(ctx, (width, height), n)?;
    let shared = overrides.iter().filter(|(name, _)| SHARED_PARAMS.contains(&name.as_str())).cloned();
    let spec = GraphSpec::builtin("no_cull")?.with_overrides(shared);
    let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), RenderSettings::new(big_w, big_h), &spec)?;
    let every_caster = shadows.map(|s| ShadowSettings { caster_culling: false, ..s.clone() });
    renderer.set_shadows(shaders, every_caster)?;
    // The reference is the scene's true coverage, so unjittered: a sub-pixel jitter is a
    // sampling choice of the image under test, whose error against the truth is what is measured.
    let unjittered = Camera { jitter: glam::Vec2::ZERO, ..camera.clone() };
    let (_, big) = renderer.render_to_image(&unjittered)?;
    drop(renderer);
    rgba_from_bytes(width, height, downsample_box_srgb(big.as_raw(), width, height, n)?)
}

/// Error of `image` (a render of `camera`'s view of `scene`, with the sun's shadows as `shadows`
/// says) against the `n x n` reference. `overrides` as for [`render_reference`]; a shadowed
/// image is compared with a reference whose shadow maps have `n` times the resolution.
#[allow(clippy::too_many_arguments)]
pub fn image_reference_error(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Arc<Scene>,
    camera: &Camera,
    image: &RgbaImage,
    n: u32,
    overrides: &[(String, String)],
    shadows: Option<&ShadowSettings>,
) -> Result<ImageError> {
    let size = image.dimensions();
    let finer = shadows.map(|s| ShadowSettings { resolution: s.resolution.saturating_mul(n), ..s.clone() });
    let reference = render_reference_shadowed(ctx, shaders, scene, camera, size, n, overrides, finer.as_ref())?;
    image_error(reference.as_raw(), image.as_raw(), size.0, size.1, n.saturating_mul(n))
}

/// Renders one frame of `spec` at `size` and returns its error against the `n x n` reference of
/// the same scene and camera (the graph's first output must be the lit RGBA8 image).
pub fn reference_error(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Arc<Scene>,
    camera: &Camera,
    spec: &GraphSpec,
    (width, height): (u32, u32),
    n: u32,
) -> Result<ImageError> {
    reference_render_size(ctx, (width, height), n)?;
    let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), RenderSettings::new(width, height), spec)?;
    let (_, image) = renderer.render_to_image(camera)?;
    drop(renderer);
    image_reference_error(ctx, shaders, scene, camera, &image, n, &spec.overrides, None)
}

/// The reference's render size, `n·width x n·height`, checked against the device's
/// `maxImageDimension2D` (an error that says so, and that `n` must be positive, otherwise).
pub fn reference_render_size(ctx: &GpuContext, (width, height): (u32, u32), n: u32) -> Result<(u32, u32)> {
    if n == 0 {
        return Err(Error::Invalid("the reference needs at least 1 x 1 samples per pixel, not 0".into()));
    }
    if width == 0 || height == 0 {
        return Err(Error::Invalid(format!("output size {width}x{height} is empty")));
    }
    let max = ctx.caps().limits.max_image_dimension2_d;
    match (width.checked_mul(n), height.checked_mul(n)) {
        (Some(w), Some(h)) if w <= max && h <= max => Ok((w, h)),
        _ => Err(Error::Invalid(format!(
            "a {n}x{n} supersampled reference of {width}x{height} needs a {}x{} render, over this device's \
             maxImageDimension2D of {max}; use a smaller reference factor or output size",
            width as u64 * n as u64,
            height as u64 * n as u64
        ))),
    }
}
