//! Many views over one world: a city rendered through 1, 2, 4, 8 and 16 views in one frame
//! (four split-screen cameras at street level, a quarter of the output each, then orthographic
//! views from above, as shadow maps see the city, square and as tall as the output), each view
//! culled by its own graph; a street camera with the sun cascades fitted to it
//! ([`crate::scene::cascades`]); what each view costs beside the
//! shared scene; and resizing a view (CPU time, its next frame, and that nothing is uploaded).

use super::median;
use crate::error::Result;
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::oracle::Verify;
use crate::render::{GraphSpec, RenderSettings, Renderer, ViewId};
use crate::scene::source::LoadOptions;
use crate::scene::{Camera, Projection, Scene, SceneSource};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct ViewsBench {
    /// City size.
    pub instances: usize,
    /// Size of the first view and of the resize (the split-screen views are a quarter of it).
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// View counts, one row each.
    pub views: Vec<usize>,
    /// Levels of detail at this threshold in pixels (0: full detail).
    pub lod_threshold: f64,
    /// Frames before measuring.
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
    /// Also check one frame of each row against exact visibility, culled together and one view
    /// at a time.
    pub verify: bool,
}

/// One view count.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ViewsRow {
    /// Views rendered each frame.
    pub views: usize,
    /// Median GPU milliseconds of culling every view, the views culled together (one test and
    /// one compact dispatch per phase for up to 16 views): the longest view's cull scope, each
    /// of which covers the shared dispatches.
    pub cull_ms: f64,
    /// The same with each view culled in dispatches of its own: the sum of the views' scopes.
    pub cull_separate_ms: f64,
    /// Of `cull_ms`, measured in frames of their own with step timing on: the median GPU
    /// milliseconds of the test dispatches (every view decided) and of the compact dispatches
    /// (every view's survivors placed and commands written).
    pub cull_test_ms: f64,
    /// See `cull_test_ms`.
    pub cull_compact_ms: f64,
    /// Median GPU milliseconds of the whole frame (every view), culled together.
    pub frame_ms: f64,
    /// Median CPU milliseconds of recording a frame of every view culled together (frames
    /// replaying their kept commands where they may).
    #[serde(default)]
    pub record_cpu_ms: f64,
    /// The same with every pass recorded every frame.
    #[serde(default)]
    pub record_cpu_every_pass_ms: f64,
    /// Instance-cull passes per view.
    pub cull_passes: usize,
    /// Device bytes of every view's graph resources together (the scene is shared).
    pub view_bytes: u64,
    /// Instances drawn per view in the last frame.
    pub drawn: Vec<u32>,
    /// With `verify`: per view, the share of the instances it cannot see that it culled, its
    /// views culled together.
    pub invisible_culled: Vec<f64>,
    /// The same, each view culled on its own.
    pub invisible_culled_alone: Vec<f64>,
    /// With `verify`: false negatives of every view in both frames together (0: none).
    pub false_negatives: u32,
}

/// The figures of one run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ViewsReport {
    /// Device.
    pub device: String,
    /// City size.
    pub instances: usize,
    /// The graphs' level-of-detail threshold in pixels (0: full detail).
    #[serde(default)]
    pub lod_threshold: f64,
    /// Device bytes of the scene all views share (geometry, instances, bounds, textures).
    pub scene_bytes: u64,
    /// One row per view count.
    pub rows: Vec<ViewsRow>,
    /// Median CPU milliseconds of resizing the main view between `width`x`height` and
    /// three quarters of it.
    pub resize_cpu_ms: f64,
    /// Of `resize_cpu_ms`, the median CPU milliseconds of loading and compiling the graph for
    /// the new size alone.
    pub resize_compile_ms: f64,
    /// Median GPU milliseconds of the frame right after a resize.
    pub resized_frame_ms: f64,
    /// Median GPU milliseconds of a frame without a resize.
    pub steady_frame_ms: f64,
    /// Pipelines made by the resizes (0: every pipeline was shared).
    pub resize_pipelines: u64,
    /// Whether the scene's buffers stayed the same through the resizes (nothing uploaded).
    pub scene_kept: bool,
    /// Two VR eyes (the first street camera's, `width` x `height` each) drawn with multiview
    /// against a pass per eye.
    #[serde(default)]
    pub multiview: Option<super::multiview::MultiviewReport>,
    /// The first street camera at `width` x `height` with the sun's cascades fitted to it.
    #[serde(default)]
    pub cascades: Option<CascadesRow>,
}

/// A camera and the sun cascades fitted to it ([`crate::scene::cascades`]), each cascade a
/// square view as tall as the output, culled with the camera.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct CascadesRow {
    /// Cascades.
    pub cascades: usize,
    /// Median GPU milliseconds of culling the camera alone.
    pub camera_alone_ms: f64,
    /// Culling the camera and every cascade together (one test and one compact dispatch per
    /// phase): the longest view's cull scope.
    pub together_ms: f64,
    /// The same, each view in dispatches of its own: the sum of the views' scopes.
    pub separate_ms: f64,
    /// Instances drawn by the camera, then each cascade, in the last frame.
    pub drawn: Vec<u32>,
}

/// The `i`-th camera of a frame of `n` views: four split-screen street cameras looking inward
/// from the city's corners, then orthographic views from above over a grid of tiles that covers
/// the city.
pub fn camera(scene: &Scene, i: usize, n: usize) -> Camera {
    let (min, max) = scene.world_bounds().unwrap_or((DVec3::splat(-1.0), DVec3::splat(1.0)));
    let center = (min + max) * 0.5;
    if i < 4 {
        let corner = DVec3::new(if i & 1 == 0 { min.x } else { max.x }, 2.0, if i & 2 == 0 { min.z } else { max.z });
        return Camera {
            eye: corner + (center - corner) * 0.05,
            target: DVec3::new(center.x, 1.5, center.z),
            ..Default::default()
        };
    }
    let tile = i - 4;
    let grid = ((n.saturating_sub(4)) as f64).sqrt().ceil().max(1.0) as usize;
    let (tx, tz) = ((tile % grid) as f64, (tile / grid) as f64);
    let size = (max - min) / grid as f64;
    let at = DVec3::new(min.x + (tx + 0.5) * size.x, center.y, min.z + (tz + 0.5) * size.z.max(1e-3));
    let height = (max.y - min.y).max(1.0) + 10.0;
    Camera {
        eye: at + DVec3::new(0.0, height, 0.0),
        target: at,
        up: glam::Vec3::Z,
        projection: Projection::Orthographic { height: size.x.max(size.z) as f32, far: (2.0 * height) as f32 },
        near: 1.0,
        ..Default::default()
    }
}

/// Runs the suite.
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &ViewsBench,
    progress: &dyn Fn(&str),
) -> Result<ViewsReport> {
    progress(&format!("views: city of {} instances", bench.instances));
    let scene = std::sync::Arc::new(
        SceneSource::Builtin("city".into())
            .load(&LoadOptions { instances: Some(bench.instances), ..Default::default() })?,
    );
    let (w, h) = (bench.width, bench.height);
    let quarter = RenderSettings::new((w / 2).max(1), (h / 2).max(1));
    let spec = match bench.lod_threshold > 0.0 {
        true => GraphSpec::default_graph()
            .with_overrides([("lod_threshold".to_string(), format!("{:?}", bench.lod_threshold))]),
        false => GraphSpec::default_graph(),
    };
    let mut report = ViewsReport {
        device: ctx.caps().name.clone(),
        instances: bench.instances,
        lod_threshold: bench.lod_threshold,
        ..Default::default()
    };
    for &n in &bench.views {
        progress(&format!("views: {n} view(s)"));
        let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), quarter.clone(), &spec)?;
        renderer.set_step_timing(false);
        let mut ids = vec![ViewId::MAIN];
        for i in 1..n {
            // Shadow-like views are square, as tall as the output.
            let settings = if i < 4 { quarter.clone() } else { RenderSettings::new(h, h) };
            ids.push(renderer.add_view(shaders, settings, &spec)?);
        }
        let cameras: Vec<Camera> = (0..n).map(|i| camera(&scene, i, n)).collect();
        let frame: Vec<(ViewId, &Camera)> = ids.iter().copied().zip(&cameras).collect();
        // Every view runs the same graph: its instance-cull passes by name.
        let cull_names: Vec<String> =
            renderer.plan().passes.iter().filter(|p| p.kind == "instance_cull").map(|p| p.name.clone()).collect();
        let (mut cull, mut separate, mut total) = (Vec::new(), Vec::new(), Vec::new());
        let (mut record, mut record_every_pass) = (Vec::new(), Vec::new());
        let mut drawn = Vec::new();
        for together in [true, false] {
            renderer.set_views_culled_together(together);
            for f in 0..bench.warmup + bench.frames {
                let stats = renderer.render_views(&frame)?;
                if f < bench.warmup {
                    continue;
                }
                let per_view = stats
                    .iter()
                    .map(|s| s.gpu_ms.iter().filter(|t| cull_names.contains(&t.name)).map(|t| t.ms).sum::<f64>());
                if together {
                    record.push(stats[0].cpu_record_ms);
                    cull.push(per_view.fold(0.0, f64::max));
                    total.push(stats.iter().map(|s| s.gpu_total_ms).fold(0.0, f64::max));
                    drawn = stats.iter().map(|s| s.drawn).collect();
                } else {
                    separate.push(per_view.sum::<f64>());
                }
            }
        }
        renderer.set_views_culled_together(true);
        renderer.set_frame_replay(false);
        for _ in 0..bench.frames {
            record_every_pass.push(renderer.render_views(&frame)?[0].cpu_record_ms);
        }
        renderer.set_frame_replay(true);
        // The steps of the shared dispatches, timed in the lead view's scopes.
        let (mut test, mut compact) = (Vec::new(), Vec::new());
        renderer.set_views_culled_together(true);
        renderer.set_step_timing(true);
        for f in 0..bench.warmup + bench.frames {
            let stats = renderer.render_views(&frame)?;
            if f < bench.warmup {
                continue;
            }
            let step = |suffix: &str| {
                stats[0]
                    .gpu_ms
                    .iter()
                    .filter(|t| cull_names.iter().any(|c| t.name == format!("{c}/{suffix}")))
                    .map(|t| t.ms)
                    .sum::<f64>()
            };
            test.push(step("test"));
            compact.push(step("compact"));
        }
        let (mut invisible_culled, mut invisible_culled_alone, mut false_negatives) = (Vec::new(), Vec::new(), 0);
        if bench.verify {
            renderer.set_step_timing(false);
            renderer.enable_verification(shaders)?;
            for together in [true, false] {
                renderer.set_views_culled_together(together);
                let shares = if together { &mut invisible_culled } else { &mut invisible_culled_alone };
                for stats in renderer.render_views(&frame)? {
                    let Some(v) = stats.verify else { continue };
                    let invisible = (bench.instances as u64).saturating_sub(v.visible as u64);
                    shares.push(if invisible == 0 { 1.0 } else { 1.0 - v.false_positives as f64 / invisible as f64 });
                    false_negatives += v.false_negatives;
                }
            }
        }
        let cull_passes = cull_names.len() * n;
        let view_bytes = ids
            .iter()
            .map(|&id| renderer.view_runtime(id).map(|r| r.resource_bytes().iter().map(|b| b.bytes).sum::<u64>()))
            .sum::<Result<u64>>()?;
        report.scene_bytes = renderer.gpu_scene().bytes();
        report.rows.push(ViewsRow {
            views: n,
            cull_ms: median(&mut cull),
            cull_separate_ms: median(&mut separate),
            cull_test_ms: median(&mut test),
            cull_compact_ms: median(&mut compact),
            frame_ms: median(&mut total),
            record_cpu_ms: median(&mut record),
            record_cpu_every_pass_ms: median(&mut record_every_pass),
            cull_passes,
            view_bytes,
            drawn,
            invisible_culled,
            invisible_culled_alone,
            false_negatives,
        });
    }

    report.cascades = Some(cascades(ctx, shaders, &scene, bench, &spec, progress)?);

    let stereo = super::multiview::MultiviewBench { width: w, height: h, warmup: bench.warmup, frames: bench.frames };
    report.multiview = Some(super::multiview::run(ctx, shaders, &scene, &camera(&scene, 0, 1), &stereo, progress)?);

    progress(&format!("views: resizing {w}x{h}"));
    let camera = scene.default_camera(w as f32 / h as f32);
    let mut renderer = Renderer::with_graph(ctx, shaders, scene, RenderSettings::new(w, h), &spec)?;
    for _ in 0..bench.warmup.max(1) {
        renderer.render(&camera)?;
    }
    let instances = renderer.gpu_scene().instances.handle();
    let pipelines = ctx.pipelines_made();
    let (mut cpu, mut resized, mut steady, mut compile) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for f in 0..bench.frames.max(2) {
        let (rw, rh) = if f % 2 == 0 { ((w * 3 / 4).max(1), (h * 3 / 4).max(1)) } else { (w, h) };
        let start = Instant::now();
        renderer.resize(shaders, rw, rh)?;
        cpu.push(start.elapsed().as_secs_f64() * 1e3);
        let inputs = crate::graph::FrameInputs::with_quantities(rw, rh, renderer.plan_inputs().quantities.clone());
        let start = Instant::now();
        spec.compile_for(ctx, shaders, &inputs)?;
        compile.push(start.elapsed().as_secs_f64() * 1e3);
        resized.push(renderer.render(&camera)?.gpu_total_ms);
        steady.push(renderer.render(&camera)?.gpu_total_ms);
    }
    report.resize_cpu_ms = median(&mut cpu);
    report.resize_compile_ms = median(&mut compile);
    report.resized_frame_ms = median(&mut resized);
    report.steady_frame_ms = median(&mut steady);
    report.resize_pipelines = ctx.pipelines_made() - pipelines;
    report.scene_kept = renderer.gpu_scene().instances.handle() == instances;
    Ok(report)
}

/// Culls the first street camera alone, then with the sun's cascades fitted to it, together
/// and one view at a time.
fn cascades(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &std::sync::Arc<Scene>,
    bench: &ViewsBench,
    spec: &GraphSpec,
    progress: &dyn Fn(&str),
) -> Result<CascadesRow> {
    use crate::scene::cascades::{fit_cascades, CascadeSettings};
    let (w, h) = (bench.width, bench.height);
    let view = camera(scene, 0, 1);
    let settings = CascadeSettings { resolution: h, ..Default::default() };
    progress(&format!("views: a camera and {} sun cascades", settings.count));
    let fitted =
        fit_cascades(&view, w as f32 / h as f32, scene.sun.direction, &settings).map_err(crate::Error::Invalid)?;
    let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), RenderSettings::new(w, h), spec)?;
    renderer.set_step_timing(false);
    let mut ids = vec![ViewId::MAIN];
    for _ in &fitted {
        ids.push(renderer.add_view(shaders, RenderSettings::new(h, h), spec)?);
    }
    let cameras: Vec<Camera> = std::iter::once(view).chain(fitted.iter().map(|c| c.camera.clone())).collect();
    let cull_names: Vec<String> =
        renderer.plan().passes.iter().filter(|p| p.kind == "instance_cull").map(|p| p.name.clone()).collect();
    let cull_of = |s: &crate::stats::FrameStats| {
        s.gpu_ms.iter().filter(|t| cull_names.contains(&t.name)).map(|t| t.ms).sum::<f64>()
    };
    let mut row = CascadesRow { cascades: fitted.len(), ..Default::default() };
    let mut alone = Vec::new();
    for f in 0..bench.warmup + bench.frames {
        let stats = renderer.render_views(&[(ViewId::MAIN, &cameras[0])])?;
        if f >= bench.warmup {
            alone.push(cull_of(&stats[0]));
        }
    }
    let frame: Vec<(ViewId, &Camera)> = ids.iter().copied().zip(&cameras).collect();
    for together in [true, false] {
        renderer.set_views_culled_together(together);
        let mut times = Vec::new();
        for f in 0..bench.warmup + bench.frames {
            let stats = renderer.render_views(&frame)?;
            if f < bench.warmup {
                continue;
            }
            let per_view = stats.iter().map(cull_of);
            times.push(if together { per_view.fold(0.0, f64::max) } else { per_view.sum() });
            row.drawn = stats.iter().map(|s| s.drawn).collect();
        }
        if together {
            row.together_ms = median(&mut times);
        } else {
            row.separate_ms = median(&mut times);
        }
    }
    row.camera_alone_ms = median(&mut alone);
    Ok(row)
}

impl ViewsReport {
    /// The report as Markdown.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "## Views\n\nCity of {} instances on {}; the scene ({:.1} MB) is shared by every view; levels of detail at {} px.\n\n\
             | views | cull GPU ms, together | of which test, compact | cull GPU ms, one view at a time | ratio | frame GPU ms | record CPU ms (every pass recorded) | view resources MB | drawn per view |\n\
             |---|---|---|---|---|---|---|---|---|\n",
            self.instances,
            self.device,
            self.scene_bytes as f64 / 1e6,
            self.lod_threshold
        );
        for r in &self.rows {
            md += &format!(
                "| {} | {:.3} | {:.3}, {:.3} | {:.3} | {:.2} | {:.3} | {:.4} ({:.4}) | {:.1} | {:?} |\n",
                r.views,
                r.cull_ms,
                r.cull_test_ms,
                r.cull_compact_ms,
                r.cull_separate_ms,
                r.cull_separate_ms / r.cull_ms.max(1e-9),
                r.frame_ms,
                r.record_cpu_ms,
                r.record_cpu_every_pass_ms,
                r.view_bytes as f64 / 1e6,
                r.drawn
            );
        }
        for r in self.rows.iter().filter(|r| !r.invisible_culled.is_empty()) {
            let shares = |s: &[f64]| s.iter().map(|x| format!("{:.1}", 100.0 * x)).collect::<Vec<_>>().join(", ");
            md += &format!(
                "\n{} views, share of each view's invisible instances culled (%): together [{}], one at a time [{}]; false negatives {}.\n",
                r.views,
                shares(&r.invisible_culled),
                shares(&r.invisible_culled_alone),
                r.false_negatives
            );
        }
        md += &format!(
            "\nResize: {:.2} ms CPU ({:.2} ms of it compiling the graph), next frame {:.3} GPU ms (steady {:.3}), {} pipelines made, scene {}.\n",
            self.resize_cpu_ms,
            self.resize_compile_ms,
            self.resized_frame_ms,
            self.steady_frame_ms,
            self.resize_pipelines,
            if self.scene_kept { "kept" } else { "uploaded again" }
        );
        if let Some(c) = &self.cascades {
            md += &format!(
                "\nA street camera and {} sun cascades: culling the camera alone {:.3} GPU ms, with the cascades together {:.3} ({:.2}x), one view at a time {:.3}; drawn {:?}.\n",
                c.cascades,
                c.camera_alone_ms,
                c.together_ms,
                c.together_ms / c.camera_alone_ms.max(1e-9),
                c.separate_ms,
                c.drawn
            );
        }
        if let Some(multiview) = &self.multiview {
            md += &multiview.markdown();
        }
        md
    }
}
