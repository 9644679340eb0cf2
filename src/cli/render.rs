//! `cullgraph render`: load a scene, render frames headlessly through a render graph, write the
//! image and stats; with `--watch`, keep rendering and hot-reload the graph and its shaders.

use super::args::{ProjectionArg, RenderArgs};
use super::memory::{Need, Room, Use};
use super::paths;
use super::views;
use super::watch::FileWatch;
use cullgraph::gpu::{GpuContext, ShaderCompiler};
use cullgraph::oracle::reference::{image_reference_error, reference_render_size};
use cullgraph::oracle::Verify;
use cullgraph::render::output::save_png;
use cullgraph::render::{FramePipeline, GraphSpec, RenderSettings, Renderer};
use cullgraph::scene::{Camera, Projection};
use cullgraph::stats::{FrameStats, RunStats};
use cullgraph::{Error, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Runs the command.
pub fn run(args: &RenderArgs) -> Result<()> {
    // With --view, the first view is the renderer's main view.
    let (width, height) = args.views.first().map_or(args.size, |v| views::view_size(args, v));
    // What cannot work is refused before the scene is generated and the frames rendered.
    paths::output_file("--out", &args.out)?;
    if let Some(stats) = &args.stats {
        paths::output_file("--stats", stats)?;
    }
    args.gpu.check()?;
    let spec = graph_spec(args)?;
    let ctx = GpuContext::new(&args.gpu.context_options("cullgraph"))?;
    let usage = if args.animate { Use::Animate } else { Use::Render };
    let room = Room::with_device(&ctx);
    let scene_need = args.scene.check_memory(&room, usage)?;
    // The image (every view's, at the largest size a resize asks for), and the reference's at
    // N x N times its pixels.
    let largest = args.resizes.iter().map(|((w, h), _)| *w as u64 * *h as u64).max().unwrap_or(0);
    let view_pixels: u64 = match args.views.is_empty() {
        true => (width as u64 * height as u64).max(largest),
        false => args.views.iter().map(|v| view_pixels_of(args, v).max(largest)).sum(),
    };
    let pixels = view_pixels + width as u64 * height as u64 * args.reference.map_or(0, |n| n as u64 * n as u64);
    let size = match args.reference {
        Some(n) => format!("{width}x{height} with --reference {n}"),
        None => format!("{width}x{height}"),
    };
    room.check("--size", &size, scene_need + Need::image(pixels))?;
    let spinner = progress(None, "loading scene");
    let mut scene = args.scene.load()?;
    spinner.finish_and_clear();
    if let Some(towards) = args.sun {
        // The sun's direction is the way its light travels.
        scene.sun = cullgraph::scene::DirectionalLight { direction: -towards, ..Default::default() };
    }

    let mut camera = camera_from_args(args, scene.default_camera(width as f32 / height as f32), &scene)?;
    if let Some(offset) = args.world_offset {
        scene.translate(offset);
        camera.eye += offset;
        camera.target += offset;
    }
    let view_cameras =
        args.views.iter().map(|v| views::view_camera(args, &scene, v)).collect::<Result<Vec<Camera>>>()?;
    let shaders = args.gpu.shaders()?;
    if let Some(n) = args.reference {
        // Refuse a reference the device cannot render before rendering anything.
        reference_render_size(&ctx, (width, height), n)?;
    }
    let mut stats = RunStats {
        device: ctx.caps().name.clone(),
        scene: scene.name.clone(),
        width,
        height,
        instances: scene.instances.len() as u32,
        meshes: scene.meshes.len() as u32,
        ..Default::default()
    };
    let settings = RenderSettings::new(width, height);
    let (mut animation, mut renderer) = if args.animate || args.stream.is_some() {
        let animation = Animation::new(args, scene)?;
        let renderer = Renderer::from_world(&ctx, &shaders, &animation.world, settings, &spec)?;
        (Some(animation), renderer)
    } else {
        (None, Renderer::with_graph(&ctx, &shaders, scene, settings, &spec)?)
    };
    if args.verify {
        renderer.enable_verification(&shaders)?;
    }
    renderer.set_shadows(&shaders, shadow_settings(args))?;
    stats.graph = renderer.plan().name.clone();
    super::post_out::check(args, &renderer)?;
    if args.watch {
        watch(args, &mut renderer, &shaders, spec, &camera)?;
        return validation_verdict(&ctx);
    }
    renderer.set_step_timing(args.step_times);
    if args.pool_adapt {
        renderer.enable_adaptation();
    }

    if !args.views.is_empty() {
        return run_views(args, renderer, &shaders, &spec, &view_cameras, stats, animation, &ctx);
    }

    let bar = progress(Some(args.frames as u64), "rendering");
    let mut last_frame = None;
    // Every frame's figures are kept only for `--stats`, which writes them all; otherwise a long
    // run keeps the last frame's and the verification totals, so its memory stays flat.
    let keep_frames = args.stats.is_some();
    let mut last_stats = FrameStats::default();
    let mut verified = VerifyTotals::default();
    // Without --verify (which checks each frame once it has executed), frames do not wait for
    // each other: their figures come back a few frames late. The last frame is read back whole.
    let mut pipeline = (!args.verify).then(|| FramePipeline::new(&ctx)).transpose()?;
    let mut take = |frame_stats: FrameStats, renderer: &mut Renderer| -> Result<()> {
        let frame = frame_stats.frame;
        if let Some(v) = frame_stats.verify.as_ref().filter(|v| v.false_negatives > 0) {
            eprintln!("frame {frame}: {} visible instance(s) culled, e.g. {:?}", v.false_negatives, v.missed);
        }
        for change in renderer.adapt(&shaders, &frame_stats)? {
            let what = format!("{}.{} = {}", change.pass, change.setting, change.value);
            bar.println(format!("frame {frame}: the graph re-planned with {what}"));
        }
        if let Some(v) = &frame_stats.verify {
            verified.add(v);
        }
        if keep_frames {
            stats.frames.push(frame_stats.clone());
        }
        last_stats = frame_stats;
        Ok(())
    };
    for frame in 0..args.frames {
        if let Some((w, h)) = views::size_at(&args.resizes, frame) {
            renderer.resize(&shaders, w, h)?;
        }
        let mut camera = args.camera_path.camera_at(&camera, frame);
        if let Some(jitter) = args.jitter {
            camera.jitter = jitter.at(frame);
        }
        if let Some(animation) = animation.as_mut() {
            animation.step(&mut renderer, &shaders)?;
        }
        if frame + 1 == args.frames {
            for earlier in pipeline.as_mut().map_or(Ok(Vec::new()), |p| p.finish(&renderer))? {
                take(earlier, &mut renderer)?;
            }
            let (frame_stats, image) = renderer.render_to_image(&camera)?;
            paths::output_file("--out", &args.out)?;
            save_png(&image, &args.out)?;
            super::post_out::write(args, &mut renderer)?;
            last_frame = Some((camera, image));
            take(frame_stats, &mut renderer)?;
        } else if let Some(pipeline) = pipeline.as_mut() {
            if let Some(earlier) = pipeline.submit(&mut renderer, &camera)? {
                take(earlier, &mut renderer)?;
            }
        } else {
            let frame_stats = renderer.render(&camera)?;
            take(frame_stats, &mut renderer)?;
        }
        bar.inc(1);
        profiling::finish_frame!();
    }
    drop(pipeline);
    bar.finish_and_clear();
    if let Some(summary) = animation.as_ref().and_then(Animation::summary) {
        println!("{summary}");
    }
    note_memory(&mut stats, &renderer);
    let scene = args.reference.is_some().then(|| match &animation {
        Some(animation) => std::sync::Arc::new(animation.world.live_scene()),
        None => renderer.shared_scene(),
    });
    drop(renderer);
    if let (Some(n), Some(scene), Some((camera, image))) = (args.reference, scene, &last_frame) {
        let spinner = progress(None, "rendering the reference");
        let shadows = shadow_settings(args);
        let error = image_reference_error(&ctx, &shaders, &scene, camera, image, n, &spec.overrides, shadows.as_ref())?;
        spinner.finish_and_clear();
        stats.reference = Some(error);
    }
    if let Some(path) = &args.stats {
        paths::output_file("--stats", path)?;
        write_file(path, stats.to_json().as_bytes())?;
    }
    let last = last_stats;
    println!(
        "{} through '{}': {}x{} on {}, {} instances, {} drawn ({} frustum-culled, {} occlusion-culled), {} draws, {} triangles, GPU {:.3} ms -> {}",
        stats.scene,
        stats.graph,
        width,
        height,
        stats.device,
        last.instances,
        last.drawn,
        last.frustum_culled,
        last.occlusion_culled,
        last.draws,
        last.triangles,
        last.gpu_total_ms,
        args.out.display()
    );
    let clusters =
        last.entries::<cullgraph::passes::cluster_cull::ClusterPassStats>(cullgraph::passes::cluster_cull::GROUP);
    if !clusters.is_empty() {
        let (tested, drawn) = clusters.iter().fold((0u64, 0u64), |t, c| (t.0 + c.tested as u64, t.1 + c.drawn as u64));
        let dropped = cullgraph::passes::cluster_cull::ClusterPassStats::triangles_dropped(&last);
        println!(
            "clusters: {drawn} of {tested} drawn, {} triangles after cluster culling",
            last.triangles.saturating_sub(dropped)
        );
    }
    if let Some(r) = &stats.reference {
        println!(
            "reference ({} samples per pixel): mean FLIP {:.4}, PSNR {:.2} dB",
            r.samples_per_pixel, r.mean_flip, r.psnr_db
        );
    }
    if args.verify {
        verified.report("frame(s)")?;
    }
    validation_verdict(&ctx)
}

/// The main view's graph memory as planned for the last frame (`--pool-adapt` may have
/// re-planned it) and the scene's textures.
fn note_memory(stats: &mut RunStats, renderer: &Renderer) {
    let memory = renderer.runtime().memory();
    stats.transient_bytes = memory.bytes_with_aliasing;
    stats.transient_bytes_without_aliasing = memory.bytes_without_aliasing;
    stats.resources = renderer.runtime().resource_bytes();
    stats.texture_bytes = renderer.gpu_scene().textures.bytes();
}

/// The pixels of one `--view`.
fn view_pixels_of(args: &RenderArgs, view: &views::ViewArg) -> u64 {
    let (w, h) = views::view_size(args, view);
    w as u64 * h as u64
}

/// The rest of [`run`] with several views: render them, write each view's image, print each
/// view's figures and the stats.
#[allow(clippy::too_many_arguments)]
fn run_views(
    args: &RenderArgs,
    mut renderer: Renderer,
    shaders: &ShaderCompiler,
    spec: &GraphSpec,
    cameras: &[Camera],
    mut stats: RunStats,
    mut animation: Option<Animation>,
    ctx: &GpuContext,
) -> Result<()> {
    let bar = progress(None, "rendering views");
    let mut verified = VerifyTotals::default();
    let step = |r: &mut Renderer| match animation.as_mut() {
        Some(animation) => animation.step(r, shaders),
        None => Ok(()),
    };
    let seen = |s: &FrameStats| {
        if let Some(v) = &s.verify {
            verified.add(v);
        }
    };
    views::render_views(args, &mut renderer, shaders, spec, cameras, &mut stats, step, seen)?;
    bar.finish_and_clear();
    note_memory(&mut stats, &renderer);
    drop(renderer);
    if let Some(path) = &args.stats {
        paths::output_file("--stats", path)?;
        write_file(path, stats.to_json().as_bytes())?;
    }
    for view in &stats.views {
        let Some(last) = view.frames.last() else { continue };
        println!(
            "view {} of {} through '{}': {}x{}, {} instances, {} drawn ({} frustum-culled, {} occlusion-culled), {} draws, GPU {:.3} ms -> {}",
            view.view,
            stats.scene,
            stats.graph,
            view.width,
            view.height,
            last.instances,
            last.drawn,
            last.frustum_culled,
            last.occlusion_culled,
            last.draws,
            last.gpu_total_ms,
            view.image
        );
    }
    if args.verify {
        verified.report("view-frame(s)")?;
    }
    validation_verdict(ctx)
}

/// An error when the validation layer reported anything during the run (with `--validation`).
fn validation_verdict(ctx: &GpuContext) -> Result<()> {
    let messages = ctx.validation_log().count();
    if messages > 0 {
        return Err(Error::Invalid(format!("the validation layer reported {messages} message(s)")));
    }
    Ok(())
}

/// The sums of the verified frames' figures.
#[derive(Clone, Copy, Default)]
struct VerifyTotals {
    frames: u32,
    visible: u64,
    missed: u64,
    extra: u64,
    /// Cluster culling, checked cluster by cluster: visible cluster-frames and those missed.
    clusters_visible: u64,
    clusters_missed: u64,
    clusters_checked: bool,
}

impl VerifyTotals {
    /// Prints the totals of the `frames` checked (named `what`); an error if anything visible
    /// was culled.
    fn report(self, what: &str) -> Result<()> {
        let Self { frames, visible, missed, extra, .. } = self;
        println!(
            "verify: {frames} {what}, {visible} visible instance-frames, {missed} false negatives, {extra} false positives"
        );
        if self.clusters_checked {
            let (visible, missed) = (self.clusters_visible, self.clusters_missed);
            println!("verify: clusters: {visible} visible cluster-frames, {missed} false negatives");
        }
        if missed > 0 {
            return Err(Error::Invalid(format!("culling removed {missed} visible instance-frame(s)")));
        }
        if self.clusters_missed > 0 {
            let missed = self.clusters_missed;
            return Err(Error::Invalid(format!("cluster culling removed {missed} visible cluster-frame(s)")));
        }
        Ok(())
    }

    fn add(&mut self, v: &cullgraph::stats::VerifyStats) {
        self.frames += 1;
        self.visible += v.visible as u64;
        self.missed += v.false_negatives as u64;
        self.extra += v.false_positives as u64;
        if let Some(c) = &v.clusters {
            self.clusters_checked = true;
            self.clusters_visible += c.visible as u64;
            self.clusters_missed += c.false_negatives as u64;
        }
    }
}

/// The graph to run: `--graph FILE`, the built-in default or (`--overlay`) the built-in overlay
/// graph, with `--param`, `--overlay-view` and `--debug-view`.
fn graph_spec(args: &RenderArgs) -> Result<GraphSpec> {
    let overlay = args.overlay || args.overlay_view.is_some();
    let spec = match (&args.graph, args.no_cull) {
        _ if args.clusters => clustered_graph(args.graph.as_deref(), args.no_cull || overlay)?,
        (Some(arg), _) => GraphSpec::from_arg(arg)?,
        (None, true) => GraphSpec::builtin("no_cull")?,
        (None, false) if overlay => GraphSpec::builtin("overlay")?,
        (None, false) => GraphSpec::default_graph(),
    };
    let mut overrides = args.params.clone();
    if let Some(view) = &args.overlay_view {
        overrides.insert(0, ("overlay_view".into(), view.clone()));
    }
    if let Some(view) = &args.debug_view {
        overrides.push(("debug_view".into(), view.clone()));
    }
    if let Some(px) = args.lod_threshold {
        overrides.push(("lod_threshold".into(), format!("{px:?}")));
    }
    Ok(spec.with_overrides(overrides))
}

/// `--clusters on`: the cluster variant of the built-in graph `graph` names (`NAME_clusters`;
/// the default graph's is `two_phase_clusters`). A graph file places its own `cluster_cull`
/// passes.
fn clustered_graph(graph: Option<&str>, other: bool) -> Result<GraphSpec> {
    let refuse = |what: &str| {
        Error::Invalid(format!(
            "--clusters on: {what} has no cluster variant; the built-in two_phase, frustum and occluder_prepass graphs have one (or insert cluster_cull passes in a graph file, as graph/two_phase_clusters.ron does)"
        ))
    };
    if other {
        return Err(refuse("--no-cull or the overlay graph"));
    }
    let name = match graph {
        None => "two_phase",
        Some(arg) => match arg.strip_prefix("builtin:") {
            Some("default") => "two_phase",
            Some(name) => name,
            None => return Err(refuse(&format!("graph file '{arg}'"))),
        },
    };
    let variant = format!("{name}_clusters");
    let kinds = cullgraph::passes::builtin_kinds();
    if kinds.graph(&variant).is_none() {
        return Err(refuse(&format!("builtin:{name}")));
    }
    GraphSpec::builtin(&variant)
}

/// `--watch`: render, then poll the graph file and shaders; rebuild on change, keeping the last
/// good graph when the new one has errors.
fn watch(
    args: &RenderArgs,
    renderer: &mut Renderer,
    shaders: &ShaderCompiler,
    mut spec: GraphSpec,
    camera: &Camera,
) -> Result<()> {
    let deadline = watch_deadline(args.watch_for);
    let render_once = |renderer: &mut Renderer| -> Result<()> {
        let (stats, image) = renderer.render_to_image(camera)?;
        paths::output_file("--out", &args.out)?;
        save_png(&image, &args.out)?;
        println!("rendered '{}' in {:.3} GPU ms -> {}", renderer.plan().name, stats.gpu_total_ms, args.out.display());
        Ok(())
    };
    render_once(renderer)?;
    let mut files = FileWatch::new(watched_paths(args.graph.as_deref(), renderer, shaders));
    println!("watching {} file(s); Ctrl-C stops", files.paths().count());
    while deadline.is_none_or(|d| Instant::now() < d) {
        std::thread::sleep(Duration::from_millis(200));
        if !files.changed() {
            continue;
        }
        shaders.clear_cache();
        let reloaded = match args.graph.as_deref().filter(|g| !g.starts_with("builtin:")) {
            Some(path) => {
                GraphSpec::from_file(std::path::Path::new(path)).map(|s| s.with_overrides(spec.overrides.clone()))
            }
            None => Ok(spec.clone()),
        }
        .and_then(|new_spec| renderer.reload_graph(shaders, &new_spec).map(|_| new_spec));
        match reloaded {
            Ok(new_spec) => {
                // A graph that loads and compiles can still fail when its first frame is
                // recorded (a pass refusing what is bound to it): then the last good one returns.
                match render_once(renderer) {
                    Ok(()) => {
                        spec = new_spec;
                        println!("reloaded '{}'", spec.file);
                    }
                    Err(e) => {
                        eprintln!("error: {e}");
                        renderer.revert_reload()?;
                        eprintln!("(back to the last good graph)");
                        render_once(renderer)?;
                    }
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                eprintln!("(still running the last good graph)");
                render_once(renderer)?;
            }
        }
        // Headers a changed shader now includes.
        files.watch_also(watched_paths(args.graph.as_deref(), renderer, shaders));
    }
    Ok(())
}

/// The graph file, the files it extends, and every file on disk its shaders were compiled
/// from: user shaders, the headers they include, and the shader library when it comes from a
/// directory. (Built-in graphs and embedded shaders cannot change while the program runs.)
pub(super) fn watched_paths(graph: Option<&str>, renderer: &Renderer, shaders: &ShaderCompiler) -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = graph.iter().filter(|g| !g.starts_with("builtin:")).map(PathBuf::from).collect();
    let library = &renderer.plan().kinds;
    let bases = renderer.plan().files.iter().skip(1).filter(|f| !library.graphs().any(|g| g.file == f.as_str()));
    paths.extend(bases.map(PathBuf::from));
    paths.extend(shaders.files_read());
    paths
}

fn write_file(path: &std::path::Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| Error::Io { path: dir.display().to_string(), source })?;
    }
    std::fs::write(path, bytes).map_err(|source| Error::Io { path: path.display().to_string(), source })
}

fn camera_from_args(args: &RenderArgs, default: Camera, scene: &cullgraph::scene::Scene) -> Result<Camera> {
    let mut camera = args.camera.apply(default);
    apply_lens(args, &mut camera, args.camera.fov, scene)?;
    camera.validate().map_err(|e| Error::Invalid(format!("camera: {e}")))?;
    Ok(camera)
}

/// `--projection` (with the field of view `fov`) and the first frame's `--jitter` on `camera`.
pub(super) fn apply_lens(
    args: &RenderArgs,
    camera: &mut Camera,
    fov: Option<f32>,
    scene: &cullgraph::scene::Scene,
) -> Result<()> {
    if let Some(projection) = args.projection {
        camera.projection = projection_from_arg(projection, camera, fov, scene);
        camera
            .projection
            .validate(camera.near)
            .map_err(|e| Error::Invalid(format!("--projection {projection}: {e}")))?;
    }
    if let Some(jitter) = args.jitter {
        camera.jitter = jitter.at(0);
    }
    Ok(())
}

/// The projection `--projection` names, with the field of view of `--fov` or of the camera (60°
/// when it has none), and an orthographic far plane just past the farthest corner of the scene.
fn projection_from_arg(
    arg: ProjectionArg,
    camera: &Camera,
    fov: Option<f32>,
    scene: &cullgraph::scene::Scene,
) -> Projection {
    let fov_y_deg = fov.unwrap_or(match camera.projection {
        Projection::Perspective { fov_y_deg } | Projection::PerspectiveFar { fov_y_deg, .. } => fov_y_deg,
        _ => 60.0,
    });
    match arg {
        ProjectionArg::Infinite => Projection::Perspective { fov_y_deg },
        ProjectionArg::Far(far) => Projection::PerspectiveFar { fov_y_deg, far },
        ProjectionArg::Ortho(height) => {
            let reach = scene.world_bounds().map_or(1.0, |(min, max)| {
                (0..8)
                    .map(|i| {
                        let corner = glam::DVec3::new(
                            if i & 1 == 0 { min.x } else { max.x },
                            if i & 2 == 0 { min.y } else { max.y },
                            if i & 4 == 0 { min.z } else { max.z },
                        );
                        (corner - camera.eye).length()
                    })
                    .fold(0.0, f64::max)
            });
            Projection::Orthographic { height, far: (reach * 1.01 + camera.near as f64 + 1.0) as f32 }
        }
        ProjectionArg::OffCenter([left_deg, right_deg, up_deg, down_deg]) => {
            Projection::OffCenter { left_deg, right_deg, up_deg, down_deg, far: f32::INFINITY }
        }
    }
}

/// A progress bar (or spinner when `len` is None), drawn only on a terminal and outside CI.
fn progress(len: Option<u64>, message: &'static str) -> ProgressBar {
    let bar = match len {
        Some(n) => ProgressBar::new(n).with_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames ({per_sec})")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        ),
        None => ProgressBar::new_spinner(),
    };
    if !std::io::stderr().is_terminal() || std::env::var_os("CI").is_some() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.with_message(message)
}

/// When `--watch-for SECONDS` ends, from now (the flag's parser keeps it finite, from 0 to a
/// day); without it, never.
fn watch_deadline(seconds: Option<f64>) -> Option<Instant> {
    let duration = Duration::try_from_secs_f64(seconds?.clamp(0.0, super::args::MAX_SECONDS)).unwrap_or_default();
    Some(Instant::now() + duration)
}

/// `--animate` and `--stream`: a live world, changed once a frame.
struct Animation {
    world: cullgraph::scene::world::World,
    driver: Driver,
    /// CPU milliseconds of each played frame of a clip (sampling, posing and the sync).
    clip_ms: Vec<f64>,
}

/// What changes the world each frame.
enum Driver {
    /// `--animate`: the city's traffic.
    Traffic(cullgraph::scene::procedural::traffic::Traffic),
    /// `--stream N`: the scene's pieces, `next` the one the next frame adds (the first is in
    /// the world from the start, and frame 0 draws it alone).
    Stream { merge: Box<cullgraph::scene::merge::SceneMerge>, pieces: Vec<Vec<usize>>, next: usize, frame: u32 },
    /// `--animate` of a scene with animations: its first clip at [`Animation::CLIP_RATE`]
    /// frames a second, every animated instance moved and posed each frame (`handles` by scene
    /// instance).
    Clip {
        animation: std::sync::Arc<cullgraph::scene::animation::SceneAnimation>,
        handles: Vec<cullgraph::scene::world::InstanceHandle>,
        frame: u32,
    },
}

impl Animation {
    /// Seconds of traffic per frame.
    const STEP: f64 = 1.0 / 30.0;
    /// Frames a second of a played clip.
    const CLIP_RATE: f64 = 60.0;

    fn new(args: &RenderArgs, scene: cullgraph::scene::Scene) -> Result<Self> {
        if let Some(n) = args.stream {
            return Self::stream(scene, n as usize);
        }
        if let Some(animation) = scene.animation.clone() {
            let (world, handles) = cullgraph::scene::world::World::new(scene)?;
            return Ok(Self { world, driver: Driver::Clip { animation, handles, frame: 0 }, clip_ms: Vec::new() });
        }
        if scene.name != "builtin:city" {
            return Err(cullgraph::Error::Invalid(format!(
                "--animate plays a scene's glTF animations or drives traffic through builtin:city; {} has no animation",
                scene.name
            )));
        }
        let instances = scene.instances.len();
        let (mut world, _) = cullgraph::scene::world::World::new(scene)?;
        let vehicles = (instances / 50).max(20);
        let churn = vehicles as f64 / 20.0;
        let traffic = cullgraph::scene::procedural::traffic::Traffic::new(
            &mut world,
            instances,
            vehicles,
            churn,
            args.scene.seed,
        )?;
        Ok(Self { world, driver: Driver::Traffic(traffic), clip_ms: Vec::new() })
    }

    /// A world holding the first of `n` pieces of `scene` (its sun and camera too), the others
    /// to come.
    fn stream(scene: cullgraph::scene::Scene, n: usize) -> Result<Self> {
        use cullgraph::scene::merge::SceneMerge;
        let empty = cullgraph::scene::Scene {
            name: scene.name.clone(),
            sun: scene.sun,
            camera: scene.camera.clone(),
            ..Default::default()
        };
        let (mut world, _) = cullgraph::scene::world::World::new(empty)?;
        let mut merge = SceneMerge::new(scene, cullgraph::scene::Transform::default())?;
        let pieces = merge.pieces(n);
        let first = merge.add(&mut world, &pieces[0])?;
        println!(
            "piece 1/{}: {} instances, {} meshes, {} materials, {} textures",
            pieces.len(),
            first.instances.len(),
            first.meshes,
            first.materials,
            first.textures
        );
        Ok(Self {
            world,
            driver: Driver::Stream { merge: Box::new(merge), pieces, next: 1, frame: 0 },
            clip_ms: Vec::new(),
        })
    }

    /// What playing a clip cost a frame on the CPU: the median over the frames after the
    /// first (which makes every posed copy), with the instances posed.
    fn summary(&self) -> Option<String> {
        let Driver::Clip { animation, .. } = &self.driver else { return None };
        let mut ms: Vec<f64> = self.clip_ms.iter().skip(1).copied().collect();
        ms.sort_by(f64::total_cmp);
        let median = ms.get(ms.len() / 2)?;
        let posed = self.world.posed().count();
        Some(format!(
            "animation: {} animated instances, {posed} posed; {median:.2} ms CPU a frame (median: sampling the clip, posing, syncing)",
            animation.instances().len()
        ))
    }

    fn step(&mut self, renderer: &mut Renderer, shaders: &ShaderCompiler) -> Result<()> {
        match &mut self.driver {
            Driver::Traffic(traffic) => {
                traffic.step(&mut self.world, Self::STEP)?;
                renderer.sync(shaders, &self.world)?;
            }
            Driver::Clip { animation, handles, frame } => {
                let start = std::time::Instant::now();
                *frame += 1;
                let poses = animation.pose(0, *frame as f64 / Self::CLIP_RATE);
                let moves: Vec<_> =
                    poses.iter().filter_map(|p| handles.get(p.instance as usize).map(|&h| (h, p.transform))).collect();
                self.world.set_transforms(&moves)?;
                for pose in poses.iter().filter(|p| !p.joints.is_empty() || !p.morph_weights.is_empty()) {
                    let Some(&handle) = handles.get(pose.instance as usize) else { continue };
                    // Only a mesh with influences or targets deforms (a skin on a plain mesh moves nothing).
                    let source = match self.world.pose(handle)? {
                        Some(posed) => posed.source,
                        None => self.world.instance(handle)?.mesh,
                    };
                    if self.world.scene().meshes[source as usize].deform.is_some() {
                        self.world.set_pose(handle, &pose.joints, &pose.morph_weights)?;
                    }
                }
                renderer.sync(shaders, &self.world)?;
                self.clip_ms.push(start.elapsed().as_secs_f64() * 1e3);
            }
            Driver::Stream { merge, pieces, next, frame } => {
                *frame += 1;
                if *next == pieces.len() && *frame > 1 {
                    *next += 1;
                    register_probe(&mut self.world, renderer, shaders)?;
                }
                let Some(piece) = pieces.get(*next).filter(|_| *frame > 1) else { return Ok(()) };
                let added = merge.add(&mut self.world, piece)?;
                let sync = renderer.sync(shaders, &self.world)?;
                *next += 1;
                println!(
                    "piece {}/{}: {} instances, {} meshes, {} materials, {} textures; sync {:.2} ms CPU, {:.1} MB uploaded{}",
                    *next,
                    pieces.len(),
                    added.instances.len(),
                    added.meshes,
                    added.materials,
                    added.textures,
                    sync.cpu_ms,
                    sync.bytes_uploaded as f64 / 1e6,
                    if sync.relayout { ", laid out anew" } else { "" }
                );
            }
        }
        // The only renderer of this world has applied everything.
        self.world.trim_journal(renderer.synced_version().unwrap_or(0));
        Ok(())
    }
}

/// After the last piece of `--stream`: one mesh, material and texture registered into the
/// full world, with an instance of them out of view, to show what a registration costs a world
/// that size.
fn register_probe(
    world: &mut cullgraph::scene::world::World,
    renderer: &mut Renderer,
    shaders: &ShaderCompiler,
) -> Result<()> {
    use cullgraph::scene::{Instance, Material, MeshData, Texture, TextureRef, Transform};
    let mut cube = MeshData::default();
    for i in 0..8u32 {
        cube.positions.push(glam::Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32));
    }
    cube.indices = vec![
        0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5,
    ];
    let mesh = world.add_mesh("stream probe", &cube)?;
    let texture = world.add_texture(Texture::solid("stream probe", [200, 120, 40, 255]))?;
    let mut material = Material { name: "stream probe".into(), ..Default::default() };
    material.textures[0] = Some(TextureRef::new(texture));
    let material = world.add_material(material)?;
    // Far below the scene: out of view, so that the frames after it show what the plain
    // render of the scene shows.
    let transform = Transform { translation: glam::DVec3::new(0.0, -1.0e5, 0.0), ..Default::default() };
    world.insert(Instance { transform, mesh, material, flags: 0 })?;
    let sync = renderer.sync(shaders, world)?;
    println!(
        "registration into {} instances: 1 mesh, 1 material, 1 texture, 1 instance; sync {:.2} ms CPU, {:.3} MB uploaded{}",
        world.live_instances() - 1,
        sync.cpu_ms,
        sync.bytes_uploaded as f64 / 1e6,
        if sync.relayout { ", laid out anew" } else { "" }
    );
    Ok(())
}

/// The shadows `--shadows`, `--cascades` and `--no-caster-cull` ask for; `--lod-threshold`
/// gives the casters the camera's levels of detail.
pub fn shadow_settings(args: &RenderArgs) -> Option<cullgraph::render::ShadowSettings> {
    args.shadows.then(|| cullgraph::render::ShadowSettings {
        cascades: args.cascades,
        caster_culling: !args.no_caster_cull,
        lod_threshold: args.lod_threshold.unwrap_or(0.0),
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_watch_duration_gives_a_deadline_within_a_day() {
        assert!(watch_deadline(None).is_none());
        let day = Instant::now() + Duration::from_secs(86_401);
        for huge in [1e300, f64::INFINITY, f64::MAX] {
            assert!(watch_deadline(Some(huge)).is_some_and(|d| d < day), "{huge}");
        }
        for now in [0.0, -5.0, f64::NAN, f64::NEG_INFINITY] {
            assert!(watch_deadline(Some(now)).is_some_and(|d| d <= Instant::now()), "{now}");
        }
        assert!(watch_deadline(Some(60.0)).is_some_and(|d| d > Instant::now()));
    }
}
