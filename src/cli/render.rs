//! `cullgraph render`: load a scene, render frames headlessly, write the image and stats.

use super::args::RenderArgs;
use cullgraph::gpu::{ContextOptions, DeviceSelector, GpuContext, ShaderCompiler, ShaderRoot};
use cullgraph::render::output::save_png;
use cullgraph::render::{RenderSettings, Renderer};
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, Projection, SceneSource};
use cullgraph::stats::RunStats;
use cullgraph::{Error, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// Runs the command.
pub fn run(args: &RenderArgs) -> Result<()> {
    let (width, height) = args.size;
    let source: SceneSource = args.scene.parse()?;
    let options = LoadOptions { instances: args.instances, kinds: args.kinds, lights: args.lights, seed: args.seed };
    let spinner = progress(None, "loading scene");
    let scene = source.load(&options)?;
    spinner.finish_and_clear();

    let camera = camera_from_args(args, scene.default_camera(width as f32 / height as f32))?;
    let ctx = GpuContext::new(&ContextOptions {
        device: DeviceSelector::or_from_env(args.device.as_deref().map(|d| d.parse().unwrap_or_default())),
        validation: args.validation || ContextOptions::default().validation,
        app_name: "cullgraph".into(),
    })?;
    let root = match &args.shader_dir {
        Some(dir) => ShaderRoot::Directory(dir.clone()),
        None => ShaderRoot::from_env(),
    };
    let shaders = ShaderCompiler::new(root)?;
    let mut stats = RunStats {
        device: ctx.caps().name.clone(),
        scene: scene.name.clone(),
        width,
        height,
        instances: scene.instances.len() as u32,
        meshes: scene.meshes.len() as u32,
        frames: Vec::new(),
    };
    let mut renderer =
        Renderer::new(&ctx, &shaders, scene, RenderSettings { width, height, debug_view: args.debug_view })?;

    let bar = progress(Some(args.frames as u64), "rendering");
    for frame in 0..args.frames {
        let last = frame + 1 == args.frames;
        let frame_stats = if last {
            let (frame_stats, image) = renderer.render_to_image(&camera)?;
            save_png(&image, &args.out)?;
            frame_stats
        } else {
            renderer.render(&camera)?
        };
        stats.frames.push(frame_stats);
        bar.inc(1);
    }
    bar.finish_and_clear();
    drop(renderer);
    let validation_messages = ctx.validation_log().count();

    if let Some(path) = &args.stats {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| Error::Io { path: dir.display().to_string(), source })?;
        }
        std::fs::write(path, stats.to_json())
            .map_err(|source| Error::Io { path: path.display().to_string(), source })?;
    }
    let last = stats.frames.last().cloned().unwrap_or_default();
    println!(
        "{}: {}x{} on {}, {} instances, {} draws, {} triangles, GPU {:.3} ms -> {}",
        stats.scene,
        width,
        height,
        stats.device,
        last.instances,
        last.draws,
        last.triangles,
        last.gpu_total_ms,
        args.out.display()
    );
    if validation_messages > 0 {
        return Err(Error::Invalid(format!("the validation layer reported {validation_messages} message(s)")));
    }
    Ok(())
}

fn camera_from_args(args: &RenderArgs, default: Camera) -> Result<Camera> {
    let mut camera = default;
    if let Some(eye) = args.eye {
        camera.eye = eye;
    }
    if let Some(target) = args.target {
        camera.target = target;
    }
    if let Some(fov) = args.fov {
        camera.projection = Projection::Perspective { fov_y_deg: fov };
    }
    if let Some(near) = args.near {
        camera.near = near;
    }
    camera.validate().map_err(|e| Error::Invalid(format!("camera: {e}")))?;
    Ok(camera)
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
