//! Command-line interface: argument definitions and dispatch.

mod args;
mod bench;
mod fuzz;
mod graph;
mod memory;
mod paths;
mod post_out;
mod render;
mod view;
mod views;
mod watch;

use clap::Parser;
use std::process::ExitCode;

/// Parses arguments, runs the command and turns errors into a message and exit code 1.
pub fn main() -> ExitCode {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into());
    tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).init();
    let cli = args::Cli::parse();
    let result = match cli.command {
        args::Command::Graph(g) => return graph::run(&g),
        args::Command::Render(r) => render::run(&r),
        args::Command::View(v) => view::run(&v),
        args::Command::Devices => list_devices(),
        args::Command::Bench(b) => bench::run(&b),
        args::Command::Fuzz(f) => fuzz::run(&f),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            let mut source = std::error::Error::source(&e);
            while let Some(s) = source {
                eprintln!("  caused by: {s}");
                source = s.source();
            }
            ExitCode::FAILURE
        }
    }
}

fn list_devices() -> cullgraph::Result<()> {
    for d in cullgraph::gpu::context::list_devices()? {
        if d.api_version >= ash::vk::API_VERSION_1_3 {
            println!("{d}; {}", d.capabilities());
        } else {
            println!("{d}; cullgraph needs Vulkan 1.3");
        }
    }
    Ok(())
}
