//! `cullgraph graph check|plan|dot`: validate a render graph, print its compiled plan, export it
//! as graphviz. Graph errors are printed one per line as `file:line:col: message` with exit
//! status 1.

use super::args::{GraphArgs, GraphCheckArgs, GraphCommand, GraphFrameArgs};
use cullgraph::gpu::{ContextOptions, DeviceSelector, GpuContext, ShaderCompiler, ShaderRoot};
use cullgraph::graph::{self, CompiledGraph, DeviceEnv, Environment, GraphErrors, NoDevice};
use cullgraph::passes::builtin_kinds;
use cullgraph::passes::shared::frame_inputs;
use cullgraph::render::graph_spec::shown_image_error;
use std::path::Path;
use std::process::ExitCode;

/// Runs a `graph` subcommand.
pub fn run(args: &GraphArgs) -> ExitCode {
    let result = match &args.command {
        GraphCommand::Check(a) => check(a),
        GraphCommand::Plan(a) => compiled(&a.file, &a.params, &a.frame).map(|plan| {
            println!("{plan}");
        }),
        GraphCommand::Dot(a) => {
            dot_output(a.out.as_deref()).and_then(|_| compiled(&a.file, &a.params, &a.frame)).and_then(|plan| {
                let dot = graph::to_dot(&plan);
                match &a.out {
                    None => {
                        print!("{dot}");
                        Ok(())
                    }
                    Some(path) => dot_output(Some(path))
                        .and_then(|_| {
                            std::fs::write(path, dot).map_err(|e| Failure::Other(format!("{}: {e}", path.display())))
                        })
                        .map(|_| eprintln!("wrote {}", path.display())),
                }
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Graph(errors)) => {
            for e in errors.iter() {
                eprintln!("{e}");
            }
            ExitCode::FAILURE
        }
        Err(Failure::Other(message)) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

enum Failure {
    /// Errors in the graph, each with its position.
    Graph(GraphErrors),
    /// Anything else (no shader compiler, scene failed to load, cannot write).
    Other(String),
}

impl From<GraphErrors> for Failure {
    fn from(e: GraphErrors) -> Self {
        Failure::Graph(e)
    }
}

/// Refuses a `graph dot -o` target that cannot be written as a file.
fn dot_output(path: Option<&Path>) -> Result<(), Failure> {
    path.map_or(Ok(()), |p| super::paths::output_file("-o", p).map_err(|e| Failure::Other(e.to_string())))
}

/// The scene that sizes a graph, generated when the machine holds it.
fn scene(args: &super::args::SceneArgs) -> Result<cullgraph::scene::Scene, Failure> {
    let room = super::memory::Room::host();
    args.check_memory(&room, super::memory::Use::Generate).map_err(|e| Failure::Other(e.to_string()))?;
    args.load().map_err(|e| Failure::Other(e.to_string()))
}

fn shader_root() -> ShaderRoot {
    ShaderRoot::from_env()
}

/// Loads `file` against the real device when Vulkan is available (formats are then checked
/// against it, and compiling checks sizes against its limits), otherwise without one.
fn load(file: &Path, params: &[(String, String)], device: Option<&str>) -> Result<graph::ValidatedGraph, Failure> {
    let options = ContextOptions {
        device: DeviceSelector::or_from_env(device.map(|d| d.parse().unwrap_or_default())),
        validation: false,
        app_name: "cullgraph graph".into(),
        ..Default::default()
    };
    Ok(match GpuContext::new(&options) {
        Ok(ctx) => {
            let shaders = ShaderCompiler::new(shader_root()).map_err(|e| Failure::Other(e.to_string()))?;
            let env = DeviceEnv::new(&ctx, &shaders);
            graph::load_file(file, params, &env, &builtin_kinds())?
        }
        Err(e) => {
            eprintln!("note: no Vulkan device ({e}); formats and sizes are not checked against a device");
            let env = NoDevice::new(shader_root()).map_err(|e| Failure::Other(e.to_string()))?;
            graph::load_file(file, params, &env as &dyn Environment, &builtin_kinds())?
        }
    })
}

/// Validates `file`; with a size, also compiles it for that size and scene.
fn check(args: &GraphCheckArgs) -> Result<(), Failure> {
    let graph = load(&args.file, &args.params, args.device.as_deref())?;
    let compiled = match args.size {
        Some((width, height)) => {
            let scene = scene(&args.scene)?;
            let inputs =
                frame_inputs(&graph.kinds, &scene, width, height).map_err(|e| Failure::Other(e.to_string()))?;
            let plan = graph::compile(&graph, &inputs)?;
            // What the renderer requires of a compiled graph, checked as it would be.
            shown_image_error(&plan, width, height)?;
            format!(", compiles at {width}x{height}")
        }
        None => String::new(),
    };
    println!(
        "{}: ok ({} passes, {} resources{compiled})",
        args.file.display(),
        graph.passes.len(),
        graph.resources.len()
    );
    Ok(())
}

/// Loads (against the device when there is one) and compiles for the requested size and scene.
fn compiled(file: &Path, params: &[(String, String)], frame: &GraphFrameArgs) -> Result<CompiledGraph, Failure> {
    let graph = load(file, params, frame.device.as_deref())?;
    let env = NoDevice::new(shader_root()).map_err(|e| Failure::Other(e.to_string()))?;
    let scene = scene(&frame.scene)?;
    let (width, height) = frame.size;
    let inputs = frame_inputs(&graph.kinds, &scene, width, height).map_err(|e| Failure::Other(e.to_string()))?;
    let started = std::time::Instant::now();
    let plan = graph::compile(&graph, &inputs)?;
    let compile_time = started.elapsed();
    // Reload the same file to time loading and validation alone (the first load above also
    // warmed the file cache and the shader compiler).
    let started = std::time::Instant::now();
    let reloaded = graph::load_file(file, params, &env, &builtin_kinds())?;
    let load_time = started.elapsed();
    drop(reloaded);
    eprintln!(
        "load and validate: {:.3} ms, compile: {:.3} ms ({} passes)",
        load_time.as_secs_f64() * 1e3,
        compile_time.as_secs_f64() * 1e3,
        plan.passes.len()
    );
    Ok(plan)
}
