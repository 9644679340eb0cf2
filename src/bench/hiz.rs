//! Hi-Z benchmark: the pyramid of a real depth buffer (the city, unculled), single dispatch
//! against one dispatch per mip, at several output sizes. The single dispatch is also timed with
//! truncated pyramids (1, 2 and 6 mips) so that its cost splits into reading the depth, the
//! in-tile levels and the levels above the tiles.

use super::median_per_pass;
use crate::gpu::{GpuContext, PassTiming, ShaderCompiler};
use crate::render::{GraphSpec, RenderSettings, Renderer};
use crate::scene::source::LoadOptions;
use crate::scene::SceneSource;
use serde::{Deserialize, Serialize};

/// The graph: draw the scene's depth, build its pyramid.
const GRAPH: &str = r#"Graph(
    name: "hiz_bench",
    params: {"method": "single"},
    resources: {
        "albedo": Image(format: R8G8B8A8_UNORM),
        "normal": Image(format: R32_UINT),  // octahedral normal 12 + 12 bits, roughness 8
        "depth": Image(format: D32_SFLOAT),
        "hiz": Image(format: R32_SFLOAT, size: Fixed("max(1, width / 2)", "max(1, height / 2)"), mips: MIPS),
    },
    passes: [
        Pass(name: "gbuffer", kind: "gbuffer", writes: {"albedo": "albedo", "normal": "normal", "depth": "depth"}),
        Pass(name: "hiz", kind: "hiz_build", reads: {"depth": "depth"}, writes: {"hiz": "hiz"}, settings: {"method": "method"}),
    ],
    outputs: ["hiz"],
)"#;

/// The timing name of a frame less its depth pass (not a pass name: those are the graph's).
const AFTER_DEPTH: &str = "frame less gbuffer";

/// One size and method.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HizFigure {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// `single` or `per_mip`.
    pub method: String,
    /// Stored mips built (`None`: the whole pyramid).
    #[serde(default)]
    pub mips: Option<u32>,
    /// Median GPU milliseconds of the pyramid.
    pub ms: f64,
    /// Median GPU milliseconds of the frame less the depth pass: the pyramid with the barrier
    /// before it, which the pass's own timestamps leave out.
    #[serde(default)]
    pub after_depth_ms: f64,
}

/// Measures both methods at each size (`frames` measured after `warmup`).
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    sizes: &[(u32, u32)],
    warmup: u32,
    frames: u32,
) -> crate::Result<Vec<HizFigure>> {
    let scene = std::sync::Arc::new(
        SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(2000), ..Default::default() })?,
    );
    let mut out = Vec::new();
    for &(width, height) in sizes {
        let camera = scene.default_camera(width as f32 / height as f32);
        // The whole pyramid by both methods, then truncated single-dispatch pyramids (those
        // shorter than the whole: a small depth has fewer levels).
        let chain = crate::passes::hiz_build::pyramid_mip_count(ash::vk::Extent2D { width, height });
        let truncated = [1, 2, 6].into_iter().filter(|&m| m < chain).map(|m| ("single", Some(m)));
        for (method, mips) in [("single", None), ("per_mip", None)].into_iter().chain(truncated) {
            let text = GRAPH.replace("MIPS", &mips.map_or("All".to_string(), |m: u32| m.to_string()));
            let spec = GraphSpec { text, file: "hiz_bench.ron".into(), ..GraphSpec::default_graph() }
                .with_overrides([("method".to_string(), method.to_string())]);
            let mut renderer =
                Renderer::with_graph(ctx, shaders, scene.clone(), RenderSettings::new(width, height), &spec)?;
            for _ in 0..warmup {
                renderer.render(&camera)?;
            }
            // Each frame's passes, plus "after depth": its whole less the depth pass.
            let timings = (0..frames)
                .map(|_| {
                    renderer.render(&camera).map(|s| {
                        let depth = s.gpu_ms.iter().find(|t| t.name == "gbuffer");
                        let after = PassTiming {
                            name: AFTER_DEPTH.into(),
                            start_ms: depth.map_or(0.0, |t| t.start_ms + t.ms),
                            ms: s.gpu_total_ms - depth.map_or(0.0, |t| t.ms),
                        };
                        s.gpu_ms.into_iter().chain([after]).collect::<Vec<_>>()
                    })
                })
                .collect::<crate::Result<Vec<_>>>()?;
            let medians = median_per_pass(&timings);
            let of = |pass: &str| medians.iter().find(|(p, _)| p == pass).map_or(0.0, |(_, ms)| *ms);
            let (ms, after_depth_ms) = (of("hiz"), of(AFTER_DEPTH));
            out.push(HizFigure { width, height, method: method.into(), mips, ms, after_depth_ms });
        }
    }
    Ok(out)
}

/// A Markdown table of the figures.
pub fn markdown(figures: &[HizFigure]) -> String {
    let mut s =
        String::from("# Hi-Z pyramid\n\n| size | method | mips | ms | frame - depth ms |\n|---|---|---|---|---|\n");
    for f in figures {
        let mips = f.mips.map_or("all".to_string(), |m| m.to_string());
        s.push_str(&format!(
            "| {}x{} | {} | {mips} | {:.4} | {:.4} |\n",
            f.width, f.height, f.method, f.ms, f.after_depth_ms
        ));
    }
    s
}
