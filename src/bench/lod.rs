//! Levels of detail: speed against error. Each scene renders through two-phase culling at each
//! level-of-detail threshold; a configuration reports the triangles drawn, the instances drawn at
//! each level, its median GPU milliseconds (frame and per pass), and its mean FLIP and PSNR
//! against the same frame at full detail (threshold 0) and against a supersampled reference.
//!
//! One sample per pixel aliases detail smaller than a pixel, and a coarser level aliases it
//! differently: their difference is then mostly two patterns of aliasing, not the level's error.
//! So the error of the levels themselves is also measured supersampled: the frame rendered at
//! the reference's size with the threshold scaled alike (so that every instance takes the
//! level it takes at the output size), box-filtered down, against the reference, which is full
//! detail at that size.
//! The instance cull pass's cost is reported per 10^6 instances, so that the cost of choosing
//! levels can be read beside the triangles it saves.
//!
//! Each threshold runs with cluster culling off and on (`two_phase_clusters`): the triangles
//! then count only the clusters drawn, and the cluster passes' cost is reported per 10^6
//! clusters tested, beside the instance cull's per 10^6 instances of the same run.

use super::{measure_frames, PassTime};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::oracle::image_error::{downsample_box_srgb, image_error};
use crate::oracle::reference::{reference_render_size, render_reference};
use crate::passes::cluster_cull::{ClusterPassStats, GROUP as CLUSTER_GROUP};
use crate::passes::instance_cull::CullPassStats;
use crate::render::output::{rgba_from_bytes, RgbaImage};
use crate::render::{GraphSpec, RenderSettings, Renderer};
use crate::scene::source::LoadOptions;
use crate::scene::{Camera, Scene, SceneSource};
use serde::{Deserialize, Serialize};

/// The thresholds swept when none are given, in pixels.
pub const DEFAULT_THRESHOLDS: &[f64] = &[0.0, 0.5, 1.0, 2.0, 4.0];

/// The graph every configuration renders through (its `lod_threshold` parameter is swept),
/// and its variant with cluster culling.
const GRAPH: &str = "two_phase";
const CLUSTERED_GRAPH: &str = "two_phase_clusters";

/// The pass whose time is reported per 10^6 instances.
const CULL_PASS: &str = "cull_late";

/// What to measure.
#[derive(Clone, Debug)]
pub struct LodBench {
    /// Scenes, with the name they are reported under and their instance count (`None`: the
    /// scene's default).
    pub scenes: Vec<(String, SceneSource, Option<usize>)>,
    /// Thresholds in pixels (0: full detail, the baseline every other is compared with).
    pub thresholds: Vec<f64>,
    /// Cluster culling off, on, or both (each threshold runs with each).
    pub clusters: Vec<bool>,
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Frames rendered before measuring.
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
    /// Supersampling factor per axis of the reference (`None`: no error against a reference).
    pub reference: Option<u32>,
}

/// One scene at one threshold.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LodFigure {
    /// Scene name.
    pub scene: String,
    /// Instances in the scene.
    pub instances: u32,
    /// Threshold, pixels.
    pub threshold: f64,
    /// Whether cluster culling ran.
    #[serde(default)]
    pub clusters: bool,
    /// Triangles drawn in the last measured frame (with cluster culling, of the clusters
    /// drawn).
    pub triangles: u64,
    /// Clusters the cluster passes tested in that frame.
    #[serde(default)]
    pub clusters_tested: u64,
    /// Clusters they drew.
    #[serde(default)]
    pub clusters_drawn: u64,
    /// The cluster passes' median milliseconds per 10^6 clusters tested.
    #[serde(default)]
    pub cluster_ms_per_million: Option<f64>,
    /// Instances drawn at each level (over the frame's draw lists), from the full mesh on.
    pub level_instances: Vec<u32>,
    /// Median GPU milliseconds of the frame.
    pub frame_ms: f64,
    /// The instance cull pass's median milliseconds per 10^6 instances.
    pub cull_ms_per_million: f64,
    /// Every pass.
    pub passes: Vec<PassTime>,
    /// Mean FLIP against the same frame at full detail.
    pub flip_vs_full: Option<f64>,
    /// PSNR against the same frame at full detail, dB (`None` when identical).
    pub psnr_vs_full_db: Option<f64>,
    /// Mean FLIP against the supersampled reference.
    pub flip_vs_reference: Option<f64>,
    /// PSNR against the reference, dB.
    pub psnr_vs_reference_db: Option<f64>,
    /// Mean FLIP of the same levels supersampled like the reference, against it: the levels'
    /// own error against full detail, without aliasing (0 at threshold 0).
    pub flip_vs_full_supersampled: Option<f64>,
}

/// The whole run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LodReport {
    /// Device name.
    pub device: String,
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Samples per pixel of the reference (N x N), if any.
    pub reference_samples: Option<u32>,
    /// One row per scene and threshold.
    pub rows: Vec<LodFigure>,
}

/// Runs the sweep. `progress` hears which configuration starts.
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &LodBench,
    progress: &dyn Fn(&str),
) -> crate::Result<LodReport> {
    if let Some(n) = bench.reference {
        reference_render_size(ctx, (bench.width, bench.height), n)?;
    }
    let most = crate::passes::instance_cull::MAX_LOD_THRESHOLD;
    if let Some(bad) = bench.thresholds.iter().find(|t| !(0.0..=most).contains(*t)) {
        return Err(crate::Error::Invalid(format!("level-of-detail threshold {bad}: from 0 to {most} pixels")));
    }
    // Threshold 0 first: the image every other is compared with.
    let mut thresholds = vec![0.0];
    thresholds.extend(bench.thresholds.iter().copied().filter(|&t| t > 0.0));
    // Clusters off first, at threshold 0: full detail, drawn whole.
    let mut cluster_modes = Vec::new();
    for on in [false, true] {
        if bench.clusters.contains(&on) || (!on && bench.clusters.is_empty()) {
            cluster_modes.push(on);
        }
    }
    let mut rows = Vec::new();
    for (name, source, instances) in &bench.scenes {
        progress(&format!("{name}: loading"));
        let scene = std::sync::Arc::new(source.load(&LoadOptions { instances: *instances, ..Default::default() })?);
        let camera = scene.default_camera(bench.width as f32 / bench.height as f32);
        let mut measured = Vec::new();
        for &threshold in &thresholds {
            for &clusters in &cluster_modes {
                let with = if clusters { ", clusters on" } else { "" };
                progress(&format!("{name}: threshold {threshold} px{with}"));
                measured.push(measure(ctx, shaders, bench, &scene, &camera, threshold, clusters)?);
            }
        }
        // Cluster culling leaves the image as it is: the levels' own error is measured once
        // per threshold, without it.
        let mut supersampled = Vec::new();
        if let Some(n) = bench.reference {
            for &threshold in &thresholds {
                progress(&format!("{name}: threshold {threshold} px, {n}x{n} samples per pixel"));
                supersampled.push(render_supersampled(ctx, shaders, bench, &scene, &camera, threshold, n)?);
            }
        }
        let reference = match bench.reference {
            Some(n) => {
                progress(&format!("{name}: the reference, {n}x{n} samples per pixel"));
                Some((n, render_reference(ctx, shaders, &scene, &camera, (bench.width, bench.height), n, &[])?))
            }
            None => None,
        };
        let full = measured[0].1.clone();
        for (index, (mut figure, image)) in measured.into_iter().enumerate() {
            let error = image_error(full.as_raw(), image.as_raw(), bench.width, bench.height, 1)?;
            figure.flip_vs_full = Some(error.mean_flip);
            figure.psnr_vs_full_db = Some(error.psnr_db).filter(|p| p.is_finite());
            if let Some((n, reference)) = &reference {
                let error = image_error(reference.as_raw(), image.as_raw(), bench.width, bench.height, n * n)?;
                figure.flip_vs_reference = Some(error.mean_flip);
                figure.psnr_vs_reference_db = Some(error.psnr_db).filter(|p| p.is_finite());
                let levels = &supersampled[index / cluster_modes.len()];
                let error = image_error(reference.as_raw(), levels.as_raw(), bench.width, bench.height, n * n)?;
                figure.flip_vs_full_supersampled = Some(error.mean_flip);
            }
            rows.push(LodFigure { scene: name.clone(), ..figure });
        }
    }
    Ok(LodReport {
        device: ctx.caps().name.clone(),
        width: bench.width,
        height: bench.height,
        reference_samples: bench.reference.map(|n| n * n),
        rows,
    })
}

/// A renderer of `scene` through [`GRAPH`] (or, with `clusters`, [`CLUSTERED_GRAPH`]) at
/// `threshold` and `size`.
fn renderer_at(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &std::sync::Arc<Scene>,
    threshold: f64,
    clusters: bool,
    (width, height): (u32, u32),
) -> crate::Result<Renderer> {
    let graph = if clusters { CLUSTERED_GRAPH } else { GRAPH };
    let spec = GraphSpec::builtin(graph)?.with_overrides([("lod_threshold".to_string(), format!("{threshold:?}"))]);
    Renderer::with_graph(ctx, shaders, scene.clone(), RenderSettings::new(width, height), &spec)
}

/// Renders `scene` at `threshold`: the warm-up, then `bench.frames` measured back to back
/// ([`measure_frames`]), then one more read back. The scene name and image errors are left for the caller.
fn measure(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &LodBench,
    scene: &std::sync::Arc<Scene>,
    camera: &Camera,
    threshold: f64,
    clusters: bool,
) -> crate::Result<(LodFigure, RgbaImage)> {
    let mut renderer = renderer_at(ctx, shaders, scene, threshold, clusters, (bench.width, bench.height))?;
    // Two-phase culling: at least two frames, so that the early draw has a list.
    let (_, passes, frame_ms) = measure_frames(ctx, &mut renderer, camera, bench.warmup.max(2), bench.frames)?;
    let (last, image) = renderer.render_to_image(camera)?;
    let cull_ms = passes.iter().find(|p| p.pass == CULL_PASS).map_or(0.0, |p| p.ms);
    let level_instances = CullPassStats::level_totals(&last);
    let cluster_passes = last.entries::<ClusterPassStats>(CLUSTER_GROUP);
    let clusters_tested: u64 = cluster_passes.iter().map(|p| p.tested as u64).sum();
    let cluster_ms: f64 = passes.iter().filter(|p| cluster_passes.iter().any(|c| c.pass == p.pass)).map(|p| p.ms).sum();
    let figure = LodFigure {
        scene: String::new(),
        instances: last.instances,
        threshold,
        clusters,
        triangles: last.triangles.saturating_sub(ClusterPassStats::triangles_dropped(&last)),
        clusters_tested,
        clusters_drawn: cluster_passes.iter().map(|p| p.drawn as u64).sum(),
        cluster_ms_per_million: (clusters_tested > 0).then(|| cluster_ms * 1.0e6 / clusters_tested as f64),
        level_instances,
        frame_ms,
        cull_ms_per_million: cull_ms * 1.0e6 / last.instances.max(1) as f64,
        passes,
        flip_vs_full: None,
        psnr_vs_full_db: None,
        flip_vs_reference: None,
        psnr_vs_reference_db: None,
        flip_vs_full_supersampled: None,
    };
    Ok((figure, image))
}

/// `scene` at `threshold` rendered as the reference is, at `n` times the output size per axis
/// without jitter, the threshold scaled by `n` so that each instance takes the level it takes at
/// the output size, and box-filtered down to the output size.
#[allow(clippy::too_many_arguments)]
fn render_supersampled(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &LodBench,
    scene: &std::sync::Arc<Scene>,
    camera: &Camera,
    threshold: f64,
    n: u32,
) -> crate::Result<RgbaImage> {
    let size = reference_render_size(ctx, (bench.width, bench.height), n)?;
    let mut renderer = renderer_at(ctx, shaders, scene, threshold * n as f64, false, size)?;
    let unjittered = Camera { jitter: glam::Vec2::ZERO, ..camera.clone() };
    // Two-phase culling: the frame after the first draws what the first found visible.
    renderer.render(&unjittered)?;
    let (_, big) = renderer.render_to_image(&unjittered)?;
    drop(renderer);
    rgba_from_bytes(bench.width, bench.height, downsample_box_srgb(big.as_raw(), bench.width, bench.height, n)?)
}

impl LodReport {
    /// Every configuration's figures, with its triangles and frame time as shares of the same
    /// scene at full detail.
    pub fn markdown(&self) -> String {
        let opt = |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
        let mut s = format!(
            "## Levels of detail: speed against error ({}, {}x{}{}, graph {GRAPH}, with cluster culling {CLUSTERED_GRAPH})\n\n",
            self.device,
            self.width,
            self.height,
            self.reference_samples.map_or(String::new(), |n| format!(", reference {n} samples per pixel"))
        );
        s += "| scene | instances | threshold px | clusters | triangles | / full | instances per level | frame ms | / full | cull ms per 10^6 instances | clusters drawn / tested | cluster ms per 10^6 clusters | FLIP vs full | PSNR vs full dB | FLIP vs full, supersampled | FLIP vs reference | PSNR vs reference dB |\n";
        s += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &self.rows {
            let full = self.rows.iter().find(|f| f.scene == r.scene && f.threshold == 0.0 && !f.clusters);
            let share = |a: f64, b: Option<f64>| b.filter(|b| *b > 0.0).map_or("-".into(), |b| format!("{:.3}", a / b));
            s += &format!(
                "| {} | {} | {} | {} | {} | {} | {} | {:.3} | {} | {:.4} | {} | {} | {} | {} | {} | {} | {} |\n",
                r.scene,
                r.instances,
                r.threshold,
                if r.clusters { "on" } else { "off" },
                r.triangles,
                share(r.triangles as f64, full.map(|f| f.triangles as f64)),
                r.level_instances.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" / "),
                r.frame_ms,
                share(r.frame_ms, full.map(|f| f.frame_ms)),
                r.cull_ms_per_million,
                if r.clusters { format!("{} / {}", r.clusters_drawn, r.clusters_tested) } else { "-".into() },
                opt(r.cluster_ms_per_million, 4),
                opt(r.flip_vs_full, 5),
                opt(r.psnr_vs_full_db, 2),
                opt(r.flip_vs_full_supersampled, 5),
                opt(r.flip_vs_reference, 5),
                opt(r.psnr_vs_reference_db, 2),
            );
        }
        s
    }
}
