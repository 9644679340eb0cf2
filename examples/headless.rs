//! Headless frame: load a scene, render one frame with cullgraph's own Vulkan device, save a PNG.
//!
//! `cargo run --release --example headless -- [builtin:city|PATH.glb] [out.png]`

use cullgraph::prelude::*;
use cullgraph::render::output::save_png;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let source: SceneSource = args.next().unwrap_or_else(|| "builtin:city".into()).parse()?;
    let out = args.next().unwrap_or_else(|| "out/headless.png".into());

    let scene = source.load(&LoadOptions::default())?;
    let settings = RenderSettings::new(960, 540);
    let camera = scene.default_camera(settings.width as f32 / settings.height as f32);

    let ctx = GpuContext::new(&ContextOptions::default())?;
    let shaders = ShaderCompiler::new(ShaderRoot::Embedded)?;
    let mut renderer = Renderer::new(&ctx, &shaders, scene, settings)?;
    let (stats, image) = renderer.render_to_image(&camera)?;
    save_png(&image, out.as_ref())?;
    println!("{} draws, {} triangles, {:.3} GPU ms -> {out}", stats.draws, stats.triangles, stats.gpu_total_ms);
    Ok(())
}
