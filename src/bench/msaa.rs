//! MSAA benchmark: speed against error for every anti-aliasing method under identical shading.
//!
//! Each method renders each scene at each sample count and light count; a configuration reports
//! its median GPU milliseconds (frame, geometry, lighting), the bytes of its G-buffer-related
//! resources and, against a supersampled reference of the same frame, its mean FLIP and PSNR.
//! The compressed methods are then set against the per-sample and Z-prepass baselines, as
//! issue-style ratios (memory, lighting, frame, FLIP difference).

use super::measure_frames;
pub use super::PassTime;
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::oracle::image_error::image_error;
use crate::oracle::reference::{reference_render_size, render_reference};
use crate::passes::lighting_compressed::GbufferPassStats;
use crate::render::output::RgbaImage;
use crate::render::{GraphSpec, RenderSettings, Renderer};
use crate::scene::source::LoadOptions;
use crate::scene::{Camera, Scene, SceneSource};
use serde::{Deserialize, Serialize};

/// Methods with one sample per pixel: no AA, and FXAA on top of it.
pub const ONE_SAMPLE_METHODS: &[&str] = &["two_phase", "fxaa"];
/// Methods that take a sample count (`msaa` param).
pub const MSAA_METHODS: &[&str] =
    &["msaa_per_sample", "msaa_zprepass", "msaa_compressed", "msaa_compressed_claim", "visibility_buffer"];
/// The compressed methods, compared with the baselines in [`MsaaReport::markdown`].
const COMPRESSED_METHODS: &[&str] = &["msaa_compressed", "msaa_compressed_claim"];

/// Resources counted as the G-buffer's memory: its targets or buffers, the depth it is drawn
/// against, and the compressed methods' claim bytes.
pub const GBUFFER_RESOURCES: &[&str] = &[
    "albedo",
    "normal",
    "emissive_occlusion",
    "depth",
    "gbuffer",
    "gbuffer_pool",
    "head_samples",
    "sample_claim",
    "ids",
];

/// What to measure.
#[derive(Clone, Debug)]
pub struct MsaaBench {
    /// Scenes, with the name they are reported under.
    pub scenes: Vec<(String, SceneSource)>,
    /// Camera (eye, target) for every scene; `None`: each scene's own view.
    pub view: Option<(glam::DVec3, glam::DVec3)>,
    /// Methods (built-in graph names); those in [`ONE_SAMPLE_METHODS`] run once per scene and
    /// light count, the others at every sample count.
    pub methods: Vec<String>,
    /// Sample counts for the MSAA methods.
    pub samples: Vec<u32>,
    /// Point-light counts.
    pub lights: Vec<usize>,
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Frames rendered before measuring.
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
    /// Supersampling factor per axis of the reference (`None`: no image error).
    pub reference: Option<u32>,
}

/// One method in one configuration.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MsaaFigure {
    /// Scene name.
    pub scene: String,
    /// Point lights.
    pub lights: usize,
    /// Samples per pixel.
    pub samples: u32,
    /// Method (built-in graph).
    pub method: String,
    /// Median GPU milliseconds of the frame.
    pub frame_ms: f64,
    /// Of which the geometry passes (depth, G-buffer, visibility ids).
    pub geometry_ms: f64,
    /// Of which the lighting pass.
    pub lighting_ms: f64,
    /// Every pass.
    pub passes: Vec<PassTime>,
    /// Bytes of the G-buffer-related resources ([`GBUFFER_RESOURCES`]).
    pub gbuffer_bytes: u64,
    /// Compressed methods: pool blocks used and allocated, and samples lost to a full pool.
    pub pool: Option<PoolFigure>,
    /// Mean FLIP against the reference.
    pub mean_flip: Option<f64>,
    /// PSNR against the reference, dB (`None` also when identical).
    pub psnr_db: Option<f64>,
}

/// The compressed G-buffer's pool in the last measured frame.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PoolFigure {
    /// Blocks used.
    pub used: u32,
    /// Blocks allocated.
    pub blocks: u32,
    /// Samples whose fragments found the pool full (the head took their weight).
    pub overflow_samples: u32,
}

/// The whole run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MsaaReport {
    /// Device name.
    pub device: String,
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Samples per pixel of the reference (N x N), if any.
    pub reference_samples: Option<u32>,
    /// One row per scene, light count, sample count and method.
    pub rows: Vec<MsaaFigure>,
}

/// Runs the sweep. `progress` hears which configuration starts.
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &MsaaBench,
    progress: &dyn Fn(&str),
) -> crate::Result<MsaaReport> {
    if let Some(n) = bench.reference {
        reference_render_size(ctx, (bench.width, bench.height), n)?;
    }
    // Refuse what would fail hours in, before anything renders.
    if let Some(m) =
        bench.methods.iter().find(|m| !ONE_SAMPLE_METHODS.contains(&m.as_str()) && !MSAA_METHODS.contains(&m.as_str()))
    {
        return Err(crate::Error::Invalid(format!(
            "unknown MSAA bench method '{m}' (known: {}, {})",
            ONE_SAMPLE_METHODS.join(", "),
            MSAA_METHODS.join(", ")
        )));
    }
    if let Some(n) = bench.samples.iter().find(|n| ![2, 4, 8].contains(*n)) {
        return Err(crate::Error::Invalid(format!("MSAA bench sample count {n}: 2, 4 or 8")));
    }
    let mut rows = Vec::new();
    for (scene_name, source) in &bench.scenes {
        for &lights in &bench.lights {
            progress(&format!("{scene_name}, {lights} lights: loading"));
            let scene = std::sync::Arc::new(source.load(&LoadOptions { lights: Some(lights), ..Default::default() })?);
            let mut camera = scene.default_camera(bench.width as f32 / bench.height as f32);
            if let Some((eye, target)) = bench.view {
                camera.eye = eye;
                camera.target = target;
                camera.validate().map_err(|e| crate::Error::Invalid(format!("MSAA bench camera: {e}")))?;
            }
            // Every method first, their images kept, then one reference for all of them: the
            // reference's large render and the CPU's error would leave the GPU idle between
            // measurements, and a GPU that idles lowers its clocks.
            let mut measured = Vec::new();
            for method in &bench.methods {
                let sample_counts =
                    if ONE_SAMPLE_METHODS.contains(&method.as_str()) { vec![1] } else { bench.samples.clone() };
                for samples in sample_counts {
                    progress(&format!("{scene_name}, {lights} lights: {method} at {samples}x"));
                    let figure = measure(ctx, shaders, bench, &scene, &camera, method, samples)?;
                    measured.push((MsaaFigure { scene: scene_name.clone(), lights, ..figure.0 }, figure.1));
                }
            }
            let reference = match bench.reference {
                Some(n) => {
                    progress(&format!("{scene_name}, {lights} lights: the reference, {n}x{n} samples per pixel"));
                    let size = (bench.width, bench.height);
                    Some((n, render_reference(ctx, shaders, &scene, &camera, size, n, &[])?))
                }
                None => None,
            };
            for (mut figure, image) in measured {
                if let Some((n, reference)) = &reference {
                    let error = image_error(reference.as_raw(), image.as_raw(), bench.width, bench.height, n * n)?;
                    figure.mean_flip = Some(error.mean_flip);
                    figure.psnr_db = Some(error.psnr_db).filter(|p| p.is_finite());
                }
                rows.push(figure);
            }
        }
    }
    Ok(MsaaReport {
        device: ctx.caps().name.clone(),
        width: bench.width,
        height: bench.height,
        reference_samples: bench.reference.map(|n| n * n),
        rows,
    })
}

/// Renders `method` at `samples` per pixel: the warm-up, then `bench.frames` measured back to
/// back, as an application renders them ([`measure_frames`]), then one more read back. The figure's scene name, light count and image error are left for the caller.
fn measure(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &MsaaBench,
    scene: &std::sync::Arc<Scene>,
    camera: &Camera,
    method: &str,
    samples: u32,
) -> crate::Result<(MsaaFigure, RgbaImage)> {
    let mut spec = GraphSpec::builtin(method)?;
    if !ONE_SAMPLE_METHODS.contains(&method) {
        spec = spec.with_overrides([("msaa".to_string(), samples.to_string())]);
    }
    let settings = RenderSettings::new(bench.width, bench.height);
    let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), settings, &spec)?;
    let (_, passes, frame_ms) = measure_frames(ctx, &mut renderer, camera, bench.warmup, bench.frames)?;
    let (last, image) = renderer.render_to_image(camera)?;
    let gbuffer_bytes = renderer
        .runtime()
        .resource_bytes()
        .iter()
        .filter(|r| GBUFFER_RESOURCES.contains(&r.name.as_str()))
        .map(|r| r.bytes)
        .sum();
    let sum =
        |keep: &dyn Fn(&str) -> bool| passes.iter().filter(|p| keep(&p.pass)).map(|p| p.ms).fold(0.0, |a, b| a + b);
    let figure = MsaaFigure {
        scene: String::new(),
        lights: 0,
        samples,
        method: method.to_string(),
        frame_ms,
        geometry_ms: sum(&|p| ["draw_", "depth_", "gbuffer"].iter().any(|s| p.starts_with(s))),
        lighting_ms: sum(&|p| p == "lighting"),
        passes,
        gbuffer_bytes,
        pool: GbufferPassStats::of(&last).first().map(|g| PoolFigure {
            used: g.pool_used,
            blocks: g.pool_blocks,
            overflow_samples: g.overflow_samples,
        }),
        mean_flip: None,
        psnr_db: None,
    };
    Ok((figure, image))
}

impl MsaaReport {
    /// The row of `method` in a configuration.
    fn find(&self, scene: &str, lights: usize, samples: u32, method: &str) -> Option<&MsaaFigure> {
        self.rows.iter().find(|r| r.scene == scene && r.lights == lights && r.samples == samples && r.method == method)
    }

    /// Every configuration's figures, then the compressed methods against the per-sample and
    /// Z-prepass baselines of the same configuration.
    pub fn markdown(&self) -> String {
        let opt = |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
        let mut s = format!(
            "## MSAA: speed against error ({}, {}x{}{})\n\n",
            self.device,
            self.width,
            self.height,
            self.reference_samples.map_or(String::new(), |n| format!(", reference {n} samples per pixel"))
        );
        s += "| scene | lights | samples | method | frame ms | geometry ms | lighting ms | G-buffer MiB | pool used / blocks | overflow samples | mean FLIP | PSNR dB |\n";
        s += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &self.rows {
            let pool = r.pool.as_ref();
            s += &format!(
                "| {} | {} | {}x | {} | {:.3} | {:.3} | {:.3} | {:.1} | {} | {} | {} | {} |\n",
                r.scene,
                r.lights,
                r.samples,
                r.method,
                r.frame_ms,
                r.geometry_ms,
                r.lighting_ms,
                r.gbuffer_bytes as f64 / (1u64 << 20) as f64,
                pool.map_or("-".to_string(), |p| format!("{} / {}", p.used, p.blocks)),
                pool.map_or("-".to_string(), |p| p.overflow_samples.to_string()),
                opt(r.mean_flip, 4),
                opt(r.psnr_db, 2),
            );
        }
        let mut compared = String::new();
        for r in self.rows.iter().filter(|r| COMPRESSED_METHODS.contains(&r.method.as_str())) {
            let (Some(ps), Some(zp)) = (
                self.find(&r.scene, r.lights, r.samples, "msaa_per_sample"),
                self.find(&r.scene, r.lights, r.samples, "msaa_zprepass"),
            ) else {
                continue;
            };
            let ratio = |a: f64, b: f64| if b > 0.0 { format!("{:.2}", a / b) } else { "-".into() };
            compared += &format!(
                "| {} | {} | {}x | {} | {} | {} | {} | {} | {} |\n",
                r.scene,
                r.lights,
                r.samples,
                r.method,
                ratio(r.gbuffer_bytes as f64, ps.gbuffer_bytes as f64),
                ratio(r.lighting_ms, ps.lighting_ms),
                ratio(r.frame_ms, ps.frame_ms),
                ratio(r.frame_ms, zp.frame_ms),
                opt(r.mean_flip.zip(ps.mean_flip).map(|(a, b)| a - b), 4),
            );
        }
        if !compared.is_empty() {
            s += "\n| scene | lights | samples | compressed | memory / per-sample | lighting / per-sample | frame / per-sample | frame / Z-prepass | FLIP - per-sample |\n";
            s += "|---|---|---|---|---|---|---|---|---|\n";
            s += &compared;
        }
        s
    }
}
