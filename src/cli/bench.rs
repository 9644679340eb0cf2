//! `cullgraph bench`: runs the benchmarks and writes JSON and Markdown next to each other.

use super::args::BenchArgs;
use cullgraph::bench::{culling, hiz};
use cullgraph::gpu::{ContextOptions, DeviceSelector, GpuContext, ShaderCompiler, ShaderRoot};
use cullgraph::{Error, Result};

/// Runs the command.
pub fn run(args: &BenchArgs) -> Result<()> {
    let ctx = GpuContext::new(&ContextOptions {
        device: DeviceSelector::or_from_env(args.device.as_deref().map(|d| d.parse().unwrap_or_default())),
        validation: false,
        app_name: "cullgraph bench".into(),
    })?;
    let shaders = ShaderCompiler::new(ShaderRoot::from_env())?;
    let io = |path: &std::path::Path, source| Error::Io { path: path.display().to_string(), source };
    std::fs::create_dir_all(&args.out).map_err(|e| io(&args.out, e))?;
    let progress = |what: &str| eprintln!("bench: {what}");
    let (width, height) = args.size;
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
    progress("hi-z pyramid");
    let pyramid = hiz::run(&ctx, &shaders, &args.hiz_sizes, args.warmup, args.frames)?;
    let json = serde_json::json!({ "culling": report, "hiz": pyramid });
    let markdown = format!("{}\n{}", report.markdown(), hiz::markdown(&pyramid));
    let write = |name: &str, text: &str| {
        let path = args.out.join(name);
        std::fs::write(&path, text).map_err(|e| io(&path, e))
    };
    write("bench.json", &serde_json::to_string_pretty(&json).unwrap_or_default())?;
    write("bench.md", &markdown)?;
    println!("{markdown}");
    Ok(())
}
