//! `cullgraph render --hdr-out/--motion-out/--depth-out F.exr`: the graph's post-processing
//! outputs read back as `f32` (`Renderer::read_output_f32`) and written as 32-bit float OpenEXR
//! images. Every flag's output is checked against the graph before any frame is rendered.

use super::args::RenderArgs;
use super::paths;
use cullgraph::render::{OutputF32, Renderer};
use cullgraph::{Error, Result};
use std::path::{Path, PathBuf};

/// One requested image: its flag, the outputs that satisfy it (first found wins) and the file.
struct Request {
    flag: &'static str,
    outputs: &'static [&'static str],
    /// Where a graph with the output is found, for the error.
    found_in: &'static str,
    path: PathBuf,
}

fn requests(args: &RenderArgs) -> Vec<Request> {
    const POST: &str = "--graph builtin:post has it";
    let flags: [(&'static str, &'static [&'static str], &'static str, &Option<PathBuf>); 3] = [
        ("--hdr-out", &["hdr"], POST, &args.hdr_out),
        ("--motion-out", &["motion"], POST, &args.motion_out),
        ("--depth-out", &["depth_resolved", "depth"], POST, &args.depth_out),
    ];
    flags
        .into_iter()
        .filter_map(|(flag, outputs, found_in, path)| Some(Request { flag, outputs, found_in, path: path.clone()? }))
        .collect()
}

/// Refuses, before rendering, a file that cannot be written and an output the graph lacks.
pub fn check(args: &RenderArgs, renderer: &Renderer) -> Result<()> {
    let plan = renderer.plan();
    for request in requests(args) {
        paths::output_file(request.flag, &request.path)?;
        if output_of(renderer, &request).is_none() {
            let names: Vec<&str> = plan.outputs.iter().map(|&id| plan.resources[id].name.as_str()).collect();
            return Err(Error::Invalid(format!(
                "{} {}: graph '{}' ({}) has no output '{}' (its outputs: {}); {}",
                request.flag,
                request.path.display(),
                plan.name,
                plan.file,
                request.outputs.join("' or '"),
                names.join(", "),
                request.found_in,
            )));
        }
    }
    Ok(())
}

fn output_of(renderer: &Renderer, request: &Request) -> Option<&'static str> {
    let plan = renderer.plan();
    request.outputs.iter().copied().find(|name| plan.outputs.iter().any(|&id| plan.resources[id].name == *name))
}

/// Reads back and writes every requested output of the last frame.
pub fn write(args: &RenderArgs, renderer: &mut Renderer) -> Result<()> {
    for request in requests(args) {
        let Some(name) = output_of(renderer, &request) else { continue };
        let output = renderer.read_output_f32(name).map_err(|e| Error::Invalid(format!("{}: {e}", request.flag)))?;
        save_exr(&output, &request.path)?;
    }
    Ok(())
}

/// Writes `output` as a 32-bit float OpenEXR image: four channels as RGBA, two as R, G and
/// B = 0, one as R = G = B (the `image` crate writes RGB and RGBA).
fn save_exr(output: &OutputF32, path: &Path) -> Result<()> {
    let io = |source| Error::Io { path: path.display().to_string(), source };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let rgb: Vec<f32> = match output.channels {
        4 => Vec::new(),
        2 => output.data.chunks_exact(2).flat_map(|p| [p[0], p[1], 0.0]).collect(),
        _ => output.data.iter().flat_map(|&d| [d, d, d]).collect(),
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    let encoded = if output.channels == 4 {
        image::Rgba32FImage::from_raw(output.width, output.height, output.data.clone())
            .map(|i| i.write_to(&mut bytes, image::ImageFormat::OpenExr))
    } else {
        image::Rgb32FImage::from_raw(output.width, output.height, rgb)
            .map(|i| i.write_to(&mut bytes, image::ImageFormat::OpenExr))
    };
    match encoded {
        Some(Ok(())) => std::fs::write(path, bytes.into_inner()).map_err(io),
        Some(Err(e)) => Err(Error::Invalid(format!("{}: cannot encode the OpenEXR image: {e}", path.display()))),
        None => Err(Error::Invalid(format!("{}: output '{}' has the wrong size", path.display(), output.name))),
    }
}
