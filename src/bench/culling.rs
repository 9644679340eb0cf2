//! Culling benchmark: the shipped culling graphs on city scenes of growing size, in the city's
//! street view (an occluded view), with the naive peer and copy bandwidth measured in the same run.

use super::peer::{copy_gbps, gbps, naive_frustum_ms};
use super::{median, median_per_pass};
use crate::gpu::{GpuContext, ShaderCompiler};
use crate::oracle::Verify;
use crate::passes::instance_cull::CullPassStats;
use crate::render::{GraphSpec, RenderSettings, Renderer};
use crate::scene::source::LoadOptions;
use crate::scene::SceneSource;
use serde::{Deserialize, Serialize};

/// Frames (at most) whose recording is timed with every pass recorded, after the timed ones.
const RECORDED_FRAMES: u32 = 20;

/// What to measure.
#[derive(Clone, Debug)]
pub struct CullingBench {
    /// City sizes (instances).
    pub instances: Vec<usize>,
    /// Output size.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Frames rendered before measuring (pipelines warm, history settled).
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
    /// Graphs (built-in names) to run.
    pub graphs: Vec<String>,
    /// Also check one frame per graph against exact visibility.
    pub verify: bool,
    /// Also time the steps of multi-dispatch passes (instance cull: test, compact).
    pub step_times: bool,
}

/// One pass of one graph.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassFigure {
    /// Pass name.
    pub pass: String,
    /// Median GPU milliseconds.
    pub ms: f64,
    /// Bytes the pass reads and writes by the estimates in [`cull_pass_bytes`] and
    /// [`hiz_pass_bytes`] (culling and Hi-Z passes only).
    pub bytes: Option<u64>,
    /// `bytes / ms`, GB/s.
    pub gbps: Option<f64>,
}

/// One graph on one scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GraphFigure {
    /// Graph name.
    pub graph: String,
    /// Median GPU milliseconds of the whole frame.
    pub frame_ms: f64,
    /// Median GPU milliseconds of all culling work (instance_cull and hiz_build passes).
    pub culling_ms: f64,
    /// Per pass.
    pub passes: Vec<PassFigure>,
    /// Instances drawn in the last measured frame.
    pub drawn: u32,
    /// Triangles drawn in the last measured frame.
    pub triangles: u64,
    /// Exact visibility of one more frame (with `verify`): visible, false negatives, false positives.
    pub visible: Option<u32>,
    /// Visible instances the scheme did not draw.
    pub false_negatives: Option<u32>,
    /// Invisible instances it drew.
    pub false_positives: Option<u32>,
    /// Share of the invisible instances it culled.
    pub invisible_culled: Option<f64>,
    /// Device bytes of the scene's buffers per instance ([`crate::passes::shared::GpuScene::bytes`]).
    #[serde(default)]
    pub gpu_scene_bytes_per_instance: f64,
    /// Device bytes of the graph's resources (targets, pyramid, culling history and lists),
    /// before transients share memory.
    #[serde(default)]
    pub gpu_graph_bytes: u64,
    /// Host memory the renderer kept per instance: the growth of the process's resident memory
    /// over making it (`None` where the system does not say).
    #[serde(default)]
    pub host_renderer_bytes_per_instance: Option<f64>,
    /// The most host memory per instance that making the renderer took at once (its copy of
    /// the scene and what uploading it needed): the peak of the process's resident memory over
    /// making it, less the memory before (`None` where the system does not say).
    #[serde(default)]
    pub host_renderer_peak_bytes_per_instance: Option<f64>,
    /// Median CPU milliseconds of recording a frame (the scene unchanged), frames replaying
    /// their slot's recording where they may (the renderer's default).
    #[serde(default)]
    pub cpu_record_ms: f64,
    /// The same with every pass recorded every frame ([`Renderer::set_frame_replay`] off),
    /// measured after the timed frames.
    #[serde(default)]
    pub cpu_record_every_pass_ms: f64,
}

/// One scene size.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneFigure {
    /// Instances.
    pub instances: usize,
    /// The naive frustum peer's median milliseconds.
    pub naive_peer_ms: f64,
    /// Its survivors.
    pub naive_peer_survivors: u32,
    /// Host memory per instance of the generated scene: the growth of the process's resident
    /// memory over making it (`None` where the system does not say).
    #[serde(default)]
    pub host_scene_bytes_per_instance: Option<f64>,
    /// Each graph.
    pub graphs: Vec<GraphFigure>,
}

/// The whole run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CullingReport {
    /// Device name.
    pub device: String,
    /// Output size.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Device-to-device copy bandwidth (read + write), GB/s.
    pub copy_gbps: f64,
    /// Per scene size.
    pub scenes: Vec<SceneFigure>,
}

/// Bytes an instance_cull pass moves (unique bytes; repeated reads that hit the cache are not
/// counted), from what its two steps read and write. Test: `tested` 32-byte records, last
/// frame's and this frame's visibility bits and the draw bits, a count per block, the
/// superblock records. Compact: the block counts, the draw bits, the superblock records, per
/// survivor its instance id read and written, and per group its count, record and command.
/// A late phase that writes the next frame's early draw list (`list`) also writes per group its
/// visible count's command. Not counted: that list's visible ids (visible slots are few in the
/// occluded views measured). Where the scene has block bounds, the pass reads the records of only
/// the blocks their bounds leave undecided (`src/passes/shared/cull_blocks.rs`): these are the
/// bytes a test of every slot moves, and the rate they give, the rate of that test.
pub fn cull_pass_bytes(slots: u64, tested: u64, drawn: u64, groups: u64, list: bool) -> u64 {
    let blocks = slots.div_ceil(256);
    let superblocks = blocks.div_ceil(64);
    let bits = slots.div_ceil(32) * 4;
    let test = tested * 32 + 3 * bits + blocks * 4 + superblocks * 32;
    let compact = blocks * 4 + bits + superblocks * 32 + drawn * 8 + groups * (4 + 32 + 20);
    let list_commands = if list { groups * (4 + 20) } else { 0 };
    test + compact + list_commands
}

/// Bytes a hiz_build pass moves: every depth sample read once (4 bytes) and every stored texel
/// of `mips` pyramid levels written once (4 bytes), for a `depth`-sized depth of `samples`
/// samples per pixel. Not counted: the tiles' merge buffer (a few KB).
pub fn hiz_pass_bytes(depth: glam::UVec2, samples: u32, mips: u32) -> u64 {
    let read = u64::from(depth.x) * u64::from(depth.y) * u64::from(samples) * 4;
    let written = crate::cull::hiz::level_offset(crate::cull::hiz::stored_size(depth), mips);
    read + u64::from(written) * 4
}

/// [`hiz_pass_bytes`] of a planned hiz_build pass, from the images bound to its slots.
fn planned_hiz_bytes(plan: &crate::graph::plan::CompiledGraph, pass: &crate::graph::plan::PlannedPass) -> Option<u64> {
    use crate::graph::plan::ResolvedKind;
    let image = |slot: &str| {
        let binding = pass.bindings.iter().find(|b| b.slot == slot)?;
        match &plan.resources[binding.resource].kind {
            ResolvedKind::Image { extent, mip_levels, samples, .. } => Some((*extent, *mip_levels, *samples)),
            ResolvedKind::Buffer { .. } => None,
        }
    };
    let (depth, _, samples) = image("depth")?;
    let (_, mips, _) = image("hiz")?;
    Some(hiz_pass_bytes(glam::UVec2::new(depth.width, depth.height), samples.as_raw(), mips))
}

/// Runs the benchmark.
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &CullingBench,
    progress: &dyn Fn(&str),
) -> crate::Result<CullingReport> {
    let copy_gbps = copy_gbps(ctx, shaders, 256 << 20, 9)?;
    let mut report = CullingReport {
        device: ctx.caps().name.clone(),
        width: bench.width,
        height: bench.height,
        copy_gbps,
        scenes: Vec::new(),
    };
    let aspect = bench.width as f32 / bench.height as f32;
    for &n in &bench.instances {
        progress(&format!("city with {n} instances"));
        let resident_before = super::resident_bytes();
        // Shared with every renderer made of it, as an engine that keeps its scene would.
        let scene = std::sync::Arc::new(
            SceneSource::Builtin("city".into()).load(&LoadOptions { instances: Some(n), ..Default::default() })?,
        );
        let per_instance = |before: Option<u64>| {
            let grown = super::resident_bytes()?.checked_sub(before?)?;
            Some(grown as f64 / n.max(1) as f64)
        };
        let host_scene_bytes_per_instance = per_instance(resident_before);
        let camera = scene.default_camera(aspect);
        let (naive_ms, naive_survivors) = naive_frustum_ms(ctx, shaders, &scene, &camera, aspect, 15)?;
        let groups = scene.meshes.len() as u64;
        let mut figure = SceneFigure {
            instances: n,
            naive_peer_ms: naive_ms,
            naive_peer_survivors: naive_survivors,
            host_scene_bytes_per_instance,
            graphs: Vec::new(),
        };
        for graph in &bench.graphs {
            progress(&format!("city with {n} instances: {graph}"));
            // A name of the shipped graphs, or a RON file (a variant to compare with them).
            let spec = match graph.ends_with(".ron") {
                true => GraphSpec::from_file(std::path::Path::new(graph))?,
                false => GraphSpec::builtin(graph)?,
            };
            let settings = RenderSettings::new(bench.width, bench.height);
            // What the renderer keeps beside the scene it shares is counted.
            let resident_before = super::resident_bytes();
            let peak_from = super::reset_peak_resident().then_some(resident_before).flatten();
            let mut renderer = Renderer::with_graph(ctx, shaders, scene.clone(), settings, &spec)?;
            let host_renderer_bytes_per_instance = per_instance(resident_before);
            let host_renderer_peak_bytes_per_instance = peak_from
                .zip(super::peak_resident_bytes())
                .map(|(before, peak)| peak.saturating_sub(before) as f64 / n.max(1) as f64);
            renderer.set_step_timing(bench.step_times);
            for _ in 0..bench.warmup {
                renderer.render(&camera)?;
            }
            let mut timings = Vec::new();
            let mut totals = Vec::new();
            let mut records = Vec::new();
            let mut last = None;
            for _ in 0..bench.frames {
                let stats = renderer.render(&camera)?;
                timings.push(stats.gpu_ms.clone());
                totals.push(stats.gpu_total_ms);
                records.push(stats.cpu_record_ms);
                last = Some(stats);
            }
            let last = last.unwrap_or_default();
            renderer.set_frame_replay(false);
            let mut every_pass = Vec::new();
            for _ in 0..bench.frames.min(RECORDED_FRAMES) {
                every_pass.push(renderer.render(&camera)?.cpu_record_ms);
            }
            renderer.set_frame_replay(true);
            let kinds: Vec<(String, String)> =
                renderer.plan().passes.iter().map(|p| (p.name.clone(), p.kind.clone())).collect();
            // Cull and Hi-Z passes only (a late phase's early draw list is reported under the draw pass).
            let planned =
                |pass: &str, kind: &str| renderer.plan().passes.iter().find(|p| p.name == pass && p.kind == kind);
            let cull_pass = |pass: &str| planned(pass, "instance_cull");
            let passes: Vec<PassFigure> = median_per_pass(&timings)
                .into_iter()
                .map(|(pass, ms)| {
                    let writes_list = |p: &crate::graph::plan::PlannedPass| {
                        p.bindings.iter().any(|b| b.slot == crate::passes::instance_cull::LIST_STATS_SLOT)
                    };
                    let bytes = cull_pass(&pass)
                        .zip(CullPassStats::of(&last).into_iter().find(|c| c.pass == pass))
                        .map(|(p, c)| {
                            cull_pass_bytes(n as u64, c.tested as u64, c.drawn as u64, groups, writes_list(p))
                        })
                        .or_else(|| planned(&pass, "hiz_build").and_then(|p| planned_hiz_bytes(renderer.plan(), p)));
                    PassFigure { gbps: bytes.map(|b| gbps(b, ms)), pass, ms, bytes }
                })
                .collect();
            let culling_ms = passes
                .iter()
                .filter(|p| {
                    kinds.iter().any(|(name, kind)| *name == p.pass && (kind == "instance_cull" || kind == "hiz_build"))
                })
                .map(|p| p.ms)
                // (A float sum starts at -0.0: a graph with no culling pass would print "-0.0000".)
                .fold(0.0, |a, b| a + b);
            let mut g = GraphFigure {
                graph: graph.clone(),
                frame_ms: median(&mut totals),
                culling_ms,
                passes,
                drawn: last.drawn,
                triangles: last.triangles,
                visible: None,
                false_negatives: None,
                false_positives: None,
                invisible_culled: None,
                gpu_scene_bytes_per_instance: renderer.gpu_scene().bytes() as f64 / n.max(1) as f64,
                gpu_graph_bytes: renderer.runtime().resource_bytes().iter().map(|b| b.bytes).sum(),
                host_renderer_bytes_per_instance,
                host_renderer_peak_bytes_per_instance,
                cpu_record_ms: median(&mut records),
                cpu_record_every_pass_ms: median(&mut every_pass),
            };
            if bench.verify {
                renderer.enable_verification(shaders)?;
                if let Some(v) = renderer.render(&camera)?.verify {
                    let invisible = (n as u64).saturating_sub(v.visible as u64);
                    g.visible = Some(v.visible);
                    g.false_negatives = Some(v.false_negatives);
                    g.false_positives = Some(v.false_positives);
                    g.invisible_culled = (invisible > 0).then(|| 1.0 - v.false_positives as f64 / invisible as f64);
                }
            }
            figure.graphs.push(g);
        }
        report.scenes.push(figure);
    }
    Ok(report)
}

impl CullingReport {
    /// A Markdown summary: per scene, each graph's frame and culling time, ratios to no culling
    /// and to the naive peer, drawn instances and invisible share culled; then the per-pass table.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Culling benchmark\n\nDevice: {}. Output {}x{}. Copy bandwidth measured in the same run: {:.0} GB/s (read + write).\n\n",
            self.device, self.width, self.height, self.copy_gbps
        );
        s.push_str("| instances | graph | frame ms | x no_cull | culling ms | culling / naive peer | drawn | triangles | visible | FN | invisible culled |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|---|\n");
        for scene in &self.scenes {
            let base = scene.graphs.iter().find(|g| g.graph == "no_cull").map(|g| g.frame_ms);
            for g in &scene.graphs {
                let opt = |v: Option<u32>| v.map_or("-".to_string(), |v| v.to_string());
                s.push_str(&format!(
                    "| {} | {} | {:.3} | {} | {:.4} | {} | {} | {} | {} | {} | {} |\n",
                    scene.instances,
                    g.graph,
                    g.frame_ms,
                    base.filter(|b| *b > 0.0).map_or("-".into(), |b| format!("{:.2}", g.frame_ms / b)),
                    g.culling_ms,
                    if g.culling_ms > 0.0 && scene.naive_peer_ms > 0.0 {
                        format!("{:.2}", g.culling_ms / scene.naive_peer_ms)
                    } else {
                        "-".into()
                    },
                    g.drawn,
                    g.triangles,
                    opt(g.visible),
                    opt(g.false_negatives),
                    g.invisible_culled.map_or("-".into(), |x| format!("{:.4}", x)),
                ));
            }
        }
        s.push_str("\n| instances | graph | GPU scene bytes per instance | GPU graph MB | host bytes per instance: scene, renderer (its peak while made) | record CPU ms | every pass recorded |\n|---|---|---|---|---|---|---|\n");
        for scene in &self.scenes {
            let host = |b: Option<f64>| b.map_or("-".to_string(), |b| format!("{b:.0}"));
            for g in &scene.graphs {
                s.push_str(&format!(
                    "| {} | {} | {:.1} | {:.1} | {}, {} ({}) | {:.4} | {:.4} |\n",
                    scene.instances,
                    g.graph,
                    g.gpu_scene_bytes_per_instance,
                    g.gpu_graph_bytes as f64 / 1e6,
                    host(scene.host_scene_bytes_per_instance),
                    host(g.host_renderer_bytes_per_instance),
                    host(g.host_renderer_peak_bytes_per_instance),
                    g.cpu_record_ms,
                    g.cpu_record_every_pass_ms,
                ));
            }
        }
        s.push_str("\n| instances | naive peer ms | graph | pass | ms | MB moved (every slot tested) | GB/s | share of copy bandwidth |\n|---|---|---|---|---|---|---|---|\n");
        for scene in &self.scenes {
            for g in &scene.graphs {
                for p in &g.passes {
                    s.push_str(&format!(
                        "| {} | {:.4} | {} | {} | {:.4} | {} | {} | {} |\n",
                        scene.instances,
                        scene.naive_peer_ms,
                        g.graph,
                        p.pass,
                        p.ms,
                        p.bytes.map_or("-".into(), |b| format!("{:.1}", b as f64 / 1e6)),
                        p.gbps.map_or("-".into(), |x| format!("{x:.0}")),
                        p.gbps.map_or("-".into(), |x| format!("{:.2}", x / self.copy_gbps.max(1e-9))),
                    ));
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hiz_bytes_are_the_depth_read_once_and_each_stored_texel_written_once() {
        // 5x3 depth at 4x: 60 samples read; stored levels 2x1 and 1x1 written.
        assert_eq!(hiz_pass_bytes(glam::UVec2::new(5, 3), 4, 2), 60 * 4 + 3 * 4);
        // 1920x1080: 8,294,400 bytes of depth; 11 levels from 960x540 down to 1x1.
        let texels: u64 = (0..11)
            .map(|k| {
                let s = crate::cull::hiz::level_size(glam::UVec2::new(960, 540), k);
                u64::from(s.x) * u64::from(s.y)
            })
            .sum();
        assert_eq!(hiz_pass_bytes(glam::UVec2::new(1920, 1080), 1, 11), 8_294_400 + texels * 4);
        assert!((690_000..700_000).contains(&texels), "{texels}");
    }
}
