//! `cullgraph bench`: runs the benchmarks and writes JSON, Markdown and SVG plots next to each other.

use super::args::BenchArgs;
use super::memory::{Need, Room, SceneSize, Use};
use cullgraph::bench::{culling, dynamic, hiz, lod, msaa, plot, shadows, views};
use cullgraph::gpu::{ContextOptions, DeviceSelector, GpuContext, ShaderCompiler, ShaderRoot};
use cullgraph::scene::SceneSource;
use cullgraph::{Error, Result};

/// Instances moved per frame in the `dynamic` suite when `--moved` is not given (those up to the
/// city's size).
const DEFAULT_MOVED: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];

/// The suites `--suites` takes.
const SUITES: &[&str] = &["culling", "hiz", "msaa", "dynamic", "views", "shadows", "lod"];

/// Runs the command.
pub fn run(args: &BenchArgs) -> Result<()> {
    if let Some(unknown) = args.suites.iter().find(|s| !SUITES.contains(&s.as_str())) {
        return Err(Error::Invalid(format!("--suites: unknown suite '{unknown}' (known: {})", SUITES.join(", "))));
    }
    let suite = |name: &str| args.suites.iter().any(|s| s == name);
    super::paths::output_dir("--out", &args.out)?;
    let largest = args.instances.iter().copied().max().unwrap_or(1_000_000);
    if let Some(moved) = args.moved.iter().find(|&&m| m > largest).filter(|_| suite("dynamic")) {
        return Err(Error::Invalid(format!(
            "--moved {moved}: more than the largest city's {largest} instances (--instances)"
        )));
    }
    let moved = match args.moved.is_empty() {
        true => DEFAULT_MOVED.iter().copied().filter(|&m| m <= largest).collect(),
        false => args.moved.clone(),
    };
    let msaa_scenes = args
        .msaa_scenes
        .iter()
        .map(|s| -> Result<(String, SceneSource)> {
            let source: SceneSource = s.parse()?;
            let name = match &source {
                SceneSource::Builtin(name) => name.clone(),
                SceneSource::File(path) => {
                    // Before the suites before it have run for minutes.
                    if !path.is_file() {
                        return Err(Error::Invalid(format!("--msaa-scenes: no file '{}'", path.display())));
                    }
                    path.file_stem().map_or(s.clone(), |n| n.to_string_lossy().into_owned())
                }
            };
            Ok((name, source))
        })
        .collect::<Result<Vec<_>>>()?;
    let lod_scenes = args
        .lod_scenes
        .iter()
        .map(|s| -> Result<(String, SceneSource, Option<usize>)> {
            // NAME or NAME@INSTANCES.
            let (scene, instances) = match s.rsplit_once('@') {
                Some((scene, n)) => (
                    scene,
                    Some(n.parse::<usize>().map_err(|_| {
                        Error::Invalid(format!("--lod-scenes: '{n}' in '{s}' is not an instance count"))
                    })?),
                ),
                None => (s.as_str(), None),
            };
            let source: SceneSource = scene.parse()?;
            if let SceneSource::File(path) = &source {
                if !path.is_file() {
                    return Err(Error::Invalid(format!("--lod-scenes: no file '{}'", path.display())));
                }
            }
            Ok((s.clone(), source, instances))
        })
        .collect::<Result<Vec<_>>>()?;
    let ctx = GpuContext::new(&ContextOptions {
        device: DeviceSelector::or_from_env(args.device.as_deref().map(|d| d.parse().unwrap_or_default())),
        // Off unless CULLGRAPH_VALIDATION=1: the layers would slow what is timed.
        validation: ContextOptions::default().validation,
        app_name: "cullgraph bench".into(),
        ..Default::default()
    })?;
    let room = Room::with_device(&ctx);
    let city = |instances: usize| SceneSize { instances: instances as u64, kinds: 0, lights: 32 };
    let pixels = args.size.0 as u64 * args.size.1 as u64;
    for (on, usage) in
        [(suite("culling") || suite("views") || suite("shadows"), Use::Render), (suite("dynamic"), Use::Animate)]
    {
        if on {
            room.check("--instances", &largest.to_string(), Need::of(city(largest), usage) + Need::image(pixels))?;
        }
    }
    let mut shaders = ShaderCompiler::new(ShaderRoot::from_env())?;
    if args.alpha_test {
        shaders = shaders.with_global_defines(&[("ALPHA_TEST_ONLY", "1")]);
    }
    let io = |path: &std::path::Path, source| Error::Io { path: path.display().to_string(), source };
    std::fs::create_dir_all(&args.out).map_err(|e| io(&args.out, e))?;
    let write = |name: &str, text: &str| {
        let path = args.out.join(name);
        std::fs::write(&path, text).map_err(|e| io(&path, e))
    };
    let progress = |what: &str| eprintln!("bench: {what}");
    let (width, height) = args.size;
    // Each suite's results are written as soon as it finishes, so that a later failure (or an
    // interrupted sweep) keeps them. A plot that cannot be drawn is reported, not fatal.
    let mut json = serde_json::Map::new();
    let mut markdown = Vec::new();
    let mut finish_suite = |name: &str, value: serde_json::Value, text: String| -> Result<()> {
        json.insert(name.into(), value);
        markdown.push(text);
        write("bench.json", &serde_json::to_string_pretty(&json).unwrap_or_default())?;
        write("bench.md", &markdown.join("\n"))
    };
    let plot = |name: &str, svg: Result<Option<String>>| -> Result<()> {
        let path = args.out.join(name);
        match svg {
            Ok(Some(svg)) => write(name, &svg),
            Ok(None) => std::fs::remove_file(&path).or_else(|e| {
                if e.kind() == std::io::ErrorKind::NotFound {
                    Ok(())
                } else {
                    Err(io(&path, e))
                }
            }),
            Err(e) => {
                eprintln!("bench: {name} not drawn: {e}");
                Ok(())
            }
        }
    };
    if suite("culling") {
        let report = culling::run(
            &ctx,
            &shaders,
            &culling::CullingBench {
                instances: args.instances.clone(),
                width,
                height,
                warmup: args.warmup,
                frames: args.frames,
                graphs: args.graphs.clone(),
                verify: args.verify,
                step_times: args.step_times,
            },
            &progress,
        )?;
        finish_suite("culling", serde_json::to_value(&report).unwrap_or_default(), report.markdown())?;
        plot("culling.svg", plot::culling_svg(&report).map(Some))?;
    }
    if suite("shadows") {
        let report = shadows::run(
            &ctx,
            &shaders,
            &shadows::ShadowsBench {
                instances: largest,
                width,
                height,
                cascades: args.shadow_cascades,
                resolution: args.shadow_resolution,
                warmup: args.warmup,
                frames: args.frames,
                reference: args.reference,
            },
            &progress,
        )?;
        finish_suite("shadows", serde_json::to_value(&report).unwrap_or_default(), report.markdown())?;
    }
    if suite("views") {
        let report = views::run(
            &ctx,
            &shaders,
            &views::ViewsBench {
                instances: largest,
                width,
                height,
                views: args.view_counts.clone(),
                lod_threshold: args.views_lod_threshold,
                warmup: args.warmup,
                frames: args.frames,
                verify: args.verify,
            },
            &progress,
        )?;
        finish_suite("views", serde_json::to_value(&report).unwrap_or_default(), report.markdown())?;
    }
    if suite("hiz") {
        progress("hi-z pyramid");
        let pyramid = hiz::run(&ctx, &shaders, &args.hiz_sizes, args.warmup, args.frames)?;
        finish_suite("hiz", serde_json::to_value(&pyramid).unwrap_or_default(), hiz::markdown(&pyramid))?;
    }
    if suite("msaa") {
        let report = msaa::run(
            &ctx,
            &shaders,
            &msaa::MsaaBench {
                scenes: msaa_scenes,
                view: args.msaa_eye.zip(args.msaa_target),
                methods: args.msaa_methods.clone(),
                samples: args.msaa_samples.clone(),
                lights: args.msaa_lights.clone(),
                width,
                height,
                warmup: args.warmup,
                frames: args.frames,
                reference: (args.reference > 0).then_some(args.reference),
            },
            &progress,
        )?;
        finish_suite("msaa", serde_json::to_value(&report).unwrap_or_default(), report.markdown())?;
        plot("msaa.svg", plot::msaa_svg(&report))?;
    }
    if suite("lod") {
        let report = lod::run(
            &ctx,
            &shaders,
            &lod::LodBench {
                scenes: lod_scenes,
                thresholds: args.lod_thresholds.clone(),
                clusters: args.lod_clusters.clone(),
                width,
                height,
                warmup: args.warmup,
                frames: args.frames,
                reference: (args.reference > 0).then_some(args.reference),
            },
            &progress,
        )?;
        finish_suite("lod", serde_json::to_value(&report).unwrap_or_default(), report.markdown())?;
        plot("lod.svg", plot::lod_svg(&report))?;
    }
    if suite("dynamic") {
        let bench = dynamic::DynamicBench {
            instances: args.instances.iter().copied().max().unwrap_or(1_000_000),
            moved,
            width,
            height,
            warmup: args.warmup,
            frames: args.frames,
        };
        let report = dynamic::run(&ctx, &shaders, &bench, &progress)?;
        finish_suite("dynamic", serde_json::to_value(&report).unwrap_or_default(), report.markdown())?;
    }
    println!("{}", markdown.join("\n"));
    match ctx.validation_log().count() {
        0 => Ok(()),
        n => Err(Error::Invalid(format!("the validation layer reported {n} message(s)"))),
    }
}
