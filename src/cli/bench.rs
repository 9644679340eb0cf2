//! `cullgraph bench`: runs the benchmarks and writes JSON, Markdown and SVG plots next to each other.

use super::args::BenchArgs;
use cullgraph::bench::{culling, hiz, msaa, plot};
use cullgraph::gpu::{ContextOptions, DeviceSelector, GpuContext, ShaderCompiler, ShaderRoot};
use cullgraph::scene::SceneSource;
use cullgraph::{Error, Result};

/// The suites `--suites` takes.
const SUITES: &[&str] = &["culling", "hiz", "msaa"];

/// Runs the command.
pub fn run(args: &BenchArgs) -> Result<()> {
    if let Some(unknown) = args.suites.iter().find(|s| !SUITES.contains(&s.as_str())) {
        return Err(Error::Invalid(format!("--suites: unknown suite '{unknown}' (known: {})", SUITES.join(", "))));
    }
    let suite = |name: &str| args.suites.iter().any(|s| s == name);
    let msaa_scenes = args
        .msaa_scenes
        .iter()
        .map(|s| -> Result<(String, SceneSource)> {
            let source: SceneSource = s.parse()?;
            let name = match &source {
                SceneSource::Builtin(name) => name.clone(),
                SceneSource::File(path) => path.file_stem().map_or(s.clone(), |n| n.to_string_lossy().into_owned()),
            };
            Ok((name, source))
        })
        .collect::<Result<Vec<_>>>()?;
    let ctx = GpuContext::new(&ContextOptions {
        device: DeviceSelector::or_from_env(args.device.as_deref().map(|d| d.parse().unwrap_or_default())),
        // Off unless CULLGRAPH_VALIDATION=1: the layers would slow what is timed.
        validation: ContextOptions::default().validation,
        app_name: "cullgraph bench".into(),
    })?;
    let shaders = ShaderCompiler::new(ShaderRoot::from_env())?;
    let io = |path: &std::path::Path, source| Error::Io { path: path.display().to_string(), source };
    std::fs::create_dir_all(&args.out).map_err(|e| io(&args.out, e))?;
    let write = |name: &str, text: &str| {
        let path = args.out.join(name);
        std::fs::write(&path, text).map_err(|e| io(&path, e))
    };
    let progress = |what: &str| eprintln!("bench: {what}");
    let (width, height) = args.size;
    let mut json = serde_json::Map::new();
    let mut markdown = Vec::new();
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
        write("culling.svg", &plot::culling_svg(&report)?)?;
        markdown.push(report.markdown());
        json.insert("culling".into(), serde_json::to_value(&report).unwrap_or_default());
    }
    if suite("hiz") {
        progress("hi-z pyramid");
        let pyramid = hiz::run(&ctx, &shaders, &args.hiz_sizes, args.warmup, args.frames)?;
        markdown.push(hiz::markdown(&pyramid));
        json.insert("hiz".into(), serde_json::to_value(&pyramid).unwrap_or_default());
    }
    if suite("msaa") {
        let report = msaa::run(
            &ctx,
            &shaders,
            &msaa::MsaaBench {
                scenes: msaa_scenes,
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
        if let Some(svg) = plot::msaa_svg(&report)? {
            write("msaa.svg", &svg)?;
        }
        markdown.push(report.markdown());
        json.insert("msaa".into(), serde_json::to_value(&report).unwrap_or_default());
    }
    let markdown = markdown.join("\n");
    write("bench.json", &serde_json::to_string_pretty(&json).unwrap_or_default())?;
    write("bench.md", &markdown)?;
    println!("{markdown}");
    match ctx.validation_log().count() {
        0 => Ok(()),
        n => Err(Error::Invalid(format!("the validation layer reported {n} message(s)"))),
    }
}
