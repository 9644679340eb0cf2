//! The sun's shadows on the city: the frame and every pass with shadows off, on with every
//! caster drawn into every cascade, and on with caster culling (the cascades' culls in the
//! camera's dispatches, then one view at a time); the maps drawn every frame, and kept while
//! nothing changed, with the camera still and walking; the maps' memory; and the error of the
//! shadowed image against a supersampled reference with shadow maps of that many times the
//! resolution.

use super::{median, median_per_pass};
use crate::error::Result;
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::oracle::reference::image_reference_error;
use crate::render::output::rgba_from_bytes;
use crate::render::{GraphSpec, RenderSettings, Renderer, ShadowSettings};
use crate::scene::source::LoadOptions;
use crate::scene::{Camera, SceneSource};
use serde::{Deserialize, Serialize};

/// What to measure.
#[derive(Clone, Debug)]
pub struct ShadowsBench {
    /// City size.
    pub instances: usize,
    /// Output size.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Cascades.
    pub cascades: u32,
    /// Texels per side of a cascade's map.
    pub resolution: u32,
    /// Frames before measuring.
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
    /// Supersampling per axis of the reference (0: no image error).
    pub reference: u32,
}

/// One configuration.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ShadowsRow {
    /// What it is.
    pub config: String,
    /// Median GPU milliseconds of the frame (the camera's scope, which covers its cascades).
    pub frame_ms: f64,
    /// The camera's passes, median GPU milliseconds each.
    pub camera_passes: Vec<(String, f64)>,
    /// Median GPU milliseconds of the camera's instance culls (with caster culling together,
    /// the dispatches it shares with its cascades).
    pub camera_cull_ms: f64,
    /// Each cascade's passes (`c<k>/<pass>`) and each light face's (`f<k>/<pass>`), median GPU
    /// milliseconds each.
    pub cascade_passes: Vec<(String, f64)>,
    /// Median GPU milliseconds of the cascades' and faces' passes other than their culls: the
    /// depth draws and pyramids.
    pub shadow_draw_ms: f64,
    /// The same with the cascades' culls where they were dispatched on their own (one view at
    /// a time); culled together they are in `camera_cull_ms`.
    pub shadow_ms: f64,
    /// Instances each cascade drew in the last frame.
    pub drawn: Vec<u32>,
    /// Cascades drawn per frame, on average.
    pub cascades_drawn: f64,
    /// Spot and point light faces drawn per frame, on average.
    pub faces_drawn: f64,
    /// Median CPU milliseconds of recording the frame (frames replaying kept commands where
    /// they may, unless the configuration says every pass is recorded).
    #[serde(default)]
    pub record_cpu_ms: f64,
}

/// The figures of one run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ShadowsReport {
    /// Device.
    pub device: String,
    /// City size.
    pub instances: usize,
    /// Output size.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Cascades.
    pub cascades: u32,
    /// Texels per side of a cascade's map.
    pub resolution: u32,
    /// Spot and point lights that may cast shadows.
    pub local_lights: u32,
    /// Texels per side of a light face's map.
    pub local_resolution: u32,
    /// Device bytes of the shadow maps.
    pub shadow_map_bytes: u64,
    /// The configurations.
    pub rows: Vec<ShadowsRow>,
    /// Supersampling per axis of the reference (0: none measured).
    pub reference: u32,
    /// Mean FLIP of the image without shadows against the reference without shadows.
    pub flip_off: f64,
    /// Mean FLIP of the image with shadows against the reference with shadows (maps of
    /// `reference` times the resolution).
    pub flip_on: f64,
    /// PSNR (dB) of the same.
    pub psnr_on: f64,
}

/// The street camera of the views bench, the first of its split-screen cameras.
fn street_camera(scene: &crate::scene::Scene) -> Camera {
    super::views::camera(scene, 0, 1)
}

/// One configuration of the suite: its name, the shadows, whether views are culled together,
/// maps kept while unchanged, the camera walking, and frames replayed.
struct Config(&'static str, Option<ShadowSettings>, bool, bool, bool, bool);

/// Runs the suite.
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &ShadowsBench,
    progress: &dyn Fn(&str),
) -> Result<ShadowsReport> {
    progress(&format!("shadows: city of {} instances", bench.instances));
    let scene = std::sync::Arc::new(
        SceneSource::Builtin("city".into())
            .load(&LoadOptions { instances: Some(bench.instances), ..Default::default() })?,
    );
    let camera = street_camera(&scene);
    let size = RenderSettings::new(bench.width, bench.height);
    let settings = |caster_culling| ShadowSettings {
        cascades: bench.cascades,
        resolution: bench.resolution,
        caster_culling,
        ..Default::default()
    };
    let mut report = ShadowsReport {
        device: ctx.caps().name.clone(),
        instances: bench.instances,
        width: bench.width,
        height: bench.height,
        cascades: bench.cascades,
        resolution: bench.resolution,
        local_lights: ShadowSettings::default().local_lights,
        local_resolution: ShadowSettings::default().local_resolution,
        reference: bench.reference,
        ..Default::default()
    };
    let on = |culling| Some(settings(culling));
    let configs = [
        Config("off", None, true, false, false, true),
        Config("on, every caster drawn", on(false), true, false, false, true),
        Config("on, casters culled", on(true), true, false, false, true),
        Config("on, casters culled, every pass recorded", on(true), true, false, false, false),
        Config("on, casters culled one view at a time", on(true), false, false, false, true),
        Config("on, casters culled, maps kept, camera still", on(true), true, true, false, true),
        Config("off, camera walking", None, true, false, true, true),
        Config("on, casters culled, maps kept, camera walking", on(true), true, true, true, true),
    ];
    let spec = GraphSpec::default_graph();
    let mut images = Vec::new();
    for Config(name, shadows, together, kept, walking, replay) in configs {
        progress(&format!("shadows: {name}"));
        let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), size.clone(), &spec)?;
        renderer.set_views_culled_together(together);
        renderer.set_frame_replay(replay);
        renderer.set_shadows(shaders, shadows.clone())?;
        renderer.set_shadow_maps_kept(kept);
        let cull_names: Vec<String> =
            renderer.plan().passes.iter().filter(|p| p.kind == "instance_cull").map(|p| p.name.clone()).collect();
        let (mut frame, mut camera_cull, mut draw, mut total) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut record = Vec::new();
        let (mut camera_timings, mut cascade_timings) = (Vec::new(), Vec::new());
        let (mut drawn, mut cascades_drawn, mut faces_drawn) = (Vec::new(), 0usize, 0usize);
        for f in 0..bench.warmup + bench.frames {
            // Walking: 1.5 units a second at 60 frames a second, along the view.
            let step = (camera.target - camera.eye).normalize() * (1.5 / 60.0) * f as f64;
            let at = if walking {
                Camera { eye: camera.eye + step, target: camera.target + step, ..camera.clone() }
            } else {
                camera.clone()
            };
            let stats = renderer.render(&at)?;
            if f < bench.warmup {
                continue;
            }
            frame.push(stats.gpu_total_ms);
            record.push(stats.cpu_record_ms);
            camera_cull.push(stats.gpu_ms.iter().filter(|t| cull_names.contains(&t.name)).map(|t| t.ms).sum::<f64>());
            let is_cull = |name: &str| name == "cull_late";
            let mut draw_ms = 0.0;
            let mut shadow_ms = 0.0;
            let mut named = Vec::new();
            let views =
                stats.shadow_cascades.iter().map(|c| ('c', c)).chain(stats.shadow_faces.iter().map(|f| ('f', f)));
            for (kind, c) in views {
                for t in &c.gpu_ms {
                    if !is_cull(&t.name) {
                        draw_ms += t.ms;
                    }
                    if !together || !is_cull(&t.name) {
                        shadow_ms += t.ms;
                    }
                    named.push(crate::gpu::PassTiming { name: format!("{kind}{}/{}", c.index, t.name), ..t.clone() });
                }
            }
            draw.push(draw_ms);
            total.push(shadow_ms);
            cascade_timings.push(named);
            camera_timings.push(stats.gpu_ms.clone());
            cascades_drawn += stats.shadow_cascades.len();
            faces_drawn += stats.shadow_faces.len();
            drawn = stats.shadow_cascades.iter().map(|c| c.drawn).collect();
        }
        if shadows.is_some() {
            report.shadow_map_bytes = renderer.shadow_map_bytes();
        }
        if bench.reference > 0
            && together
            && replay
            && !kept
            && (shadows.is_none() || shadows.as_ref().is_some_and(|s| s.caster_culling))
        {
            let (_, bytes) = renderer.render_to_rgba8(&camera)?;
            images.push((shadows.clone(), rgba_from_bytes(bench.width, bench.height, bytes)?));
        }
        report.rows.push(ShadowsRow {
            config: name.into(),
            frame_ms: median(&mut frame),
            camera_passes: median_per_pass(&camera_timings),
            camera_cull_ms: median(&mut camera_cull),
            cascade_passes: median_per_pass(&cascade_timings),
            shadow_draw_ms: median(&mut draw),
            shadow_ms: median(&mut total),
            drawn,
            cascades_drawn: cascades_drawn as f64 / bench.frames.max(1) as f64,
            faces_drawn: faces_drawn as f64 / bench.frames.max(1) as f64,
            record_cpu_ms: median(&mut record),
        });
    }
    for (shadows, image) in images {
        progress("shadows: the reference");
        let error =
            image_reference_error(ctx, shaders, &scene, &camera, &image, bench.reference, &[], shadows.as_ref())?;
        match shadows {
            Some(_) => (report.flip_on, report.psnr_on) = (error.mean_flip, error.psnr_db),
            None => report.flip_off = error.mean_flip,
        }
    }
    Ok(report)
}

impl ShadowsReport {
    /// The report as Markdown.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "## Shadows\n\nCity of {} instances at {}x{} on {}, the street camera with {} sun cascades of {}² and \
             its {} most important lights' faces of {}² ({:.1} MB of maps).\n\n\
             | shadows | frame GPU ms | camera cull ms | shadow draws and pyramids ms | shadow passes ms | cascades, light faces drawn per frame | drawn per cascade | record CPU ms |\n\
             |---|---|---|---|---|---|---|---|\n",
            self.instances,
            self.width,
            self.height,
            self.device,
            self.cascades,
            self.resolution,
            self.local_lights,
            self.local_resolution,
            self.shadow_map_bytes as f64 / 1e6
        );
        for r in &self.rows {
            md += &format!(
                "| {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.1}, {:.1} | {:?} | {:.4} |\n",
                r.config,
                r.frame_ms,
                r.camera_cull_ms,
                r.shadow_draw_ms,
                r.shadow_ms,
                r.cascades_drawn,
                r.faces_drawn,
                r.drawn,
                r.record_cpu_ms
            );
        }
        if self.reference > 0 {
            md += &format!(
                "\nAgainst a {n}x{n} supersampled reference (shadow maps of {n}x the resolution): mean FLIP {:.4} with \
                 shadows (PSNR {:.2} dB), {:.4} without.\n",
                self.flip_on,
                self.psnr_on,
                self.flip_off,
                n = self.reference
            );
        }
        md
    }
}
