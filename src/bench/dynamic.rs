//! The living world's update path: a city of `instances` instances rendered through two-phase
//! culling while `moved` of them move every frame (a small random shift, so they keep their draw
//! group) with insert and remove churn (one in a hundred of the moved count is added and as many
//! added earlier are removed), against the same city standing still.
//!
//! Reported per moved count: the frame's GPU time, the GPU time of the update's copies, the CPU
//! time of the world's moves, of its inserts and removes and of the renderer's sync (with the
//! threads they may spread over), the bytes uploaded, the late cull's
//! GPU time, and as references measured in the same run: a host-to-device copy of the same
//! bytes, rebuilding the renderer instead (CPU time and its first frame), and re-uploading every
//! slot's instance record and cull bound.

use super::median;
use crate::error::Result;
use crate::gpu::{Buffer, BufferDesc, GpuContext, GpuTimer, MemoryLocation, ShaderCompiler};
use crate::render::{FramePipeline, GraphSpec, RenderSettings, Renderer};
use crate::scene::source::LoadOptions;
use crate::scene::world::{InstanceHandle, World};
use crate::scene::{Camera, SceneSource};
use crate::stats::FrameStats;
use ash::vk;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct DynamicBench {
    /// City size.
    pub instances: usize,
    /// Instances moved per frame, one row each.
    pub moved: Vec<usize>,
    /// Output width.
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Frames before measuring.
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
}

/// One moved count.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct DynamicRow {
    /// Instances moved per frame.
    pub moved: usize,
    /// Instances inserted and removed per frame.
    pub churn: usize,
    /// Median GPU milliseconds of the frame.
    pub frame_ms: f64,
    /// Median GPU milliseconds of the update's copies.
    pub update_gpu_ms: f64,
    /// Median GPU milliseconds of the late cull pass.
    pub cull_ms: f64,
    /// Median CPU milliseconds of the world's moves (`World::set_transforms`).
    pub world_cpu_ms: f64,
    /// Median CPU milliseconds of the world's inserts and removes.
    pub churn_cpu_ms: f64,
    /// Median CPU milliseconds of `Renderer::sync`.
    pub sync_cpu_ms: f64,
    /// Median CPU milliseconds of recording the frame (its scatter of the updates included).
    #[serde(default)]
    pub record_cpu_ms: f64,
    /// Median bytes uploaded per frame.
    pub bytes: u64,
    /// A host-to-device copy of `bytes` (one region), GPU milliseconds.
    pub host_copy_ms: f64,
    /// Frames among the measured ones whose sync laid the world out anew.
    pub relayouts: u32,
}

/// The figures of one run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct DynamicReport {
    /// Device.
    pub device: String,
    /// Worker threads the world's bulk moves and the sync may spread over.
    pub threads: usize,
    /// City size.
    pub instances: usize,
    /// GPU slots of the laid-out city.
    pub slots: u32,
    /// Median GPU milliseconds of a frame of the city standing still.
    pub static_frame_ms: f64,
    /// Median GPU milliseconds of its late cull.
    pub static_cull_ms: f64,
    /// Per moved count.
    pub rows: Vec<DynamicRow>,
    /// CPU milliseconds to build the renderer anew (the change made by rebuilding).
    pub rebuild_cpu_ms: f64,
    /// GPU milliseconds of the rebuilt renderer's first frame (its full upload included).
    pub rebuild_first_frame_ms: f64,
    /// Bytes of every slot's instance record and cull bound (a whole re-upload).
    pub full_upload_bytes: u64,
    /// A host-to-device copy of those bytes, GPU milliseconds.
    pub full_upload_copy_ms: f64,
}

/// Median GPU milliseconds of a copy of `bytes` in one region from host-visible memory (the
/// kind the world's update lists live in) to device memory, after a few unmeasured copies (the
/// GPU may have idled, and clocked down, while the CPU prepared the frames before).
pub fn host_copy_ms(ctx: &GpuContext, bytes: u64, runs: u32) -> Result<f64> {
    let bytes = bytes.max(4);
    let desc = |name, usage, location| BufferDesc { name, size: bytes, usage, location };
    let src =
        Buffer::new(ctx, &desc("copy source (host)", vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu))?;
    let dst = Buffer::new(ctx, &desc("copy destination", vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuOnly))?;
    let mut timer = GpuTimer::new(ctx, 1)?;
    let mut times = Vec::new();
    const WARMUP: u32 = 4;
    for run in 0..runs.max(1) + WARMUP {
        ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "copy");
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes };
            // SAFETY: both buffers hold `bytes`; cmd recording.
            unsafe { ctx.device().cmd_copy_buffer(cmd, src.handle(), dst.handle(), &[region]) };
            timer.end(cmd);
            crate::gpu::GpuResult::Ok(())
        })?;
        if run >= WARMUP {
            times.extend(timer.results()?.first().map(|t| t.ms));
        }
    }
    Ok(median(&mut times))
}

/// The late cull pass's milliseconds in `stats`.
fn cull_ms(stats: &FrameStats) -> f64 {
    stats.gpu_ms.iter().find(|t| t.name == "cull_late").map_or(0.0, |t| t.ms)
}

/// Runs the benchmark.
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    bench: &DynamicBench,
    progress: &dyn Fn(&str),
) -> Result<DynamicReport> {
    progress(&format!("dynamic: city of {} instances", bench.instances));
    let options = LoadOptions { instances: Some(bench.instances), ..Default::default() };
    let scene = SceneSource::Builtin("city".into()).load(&options)?;
    let aspect = bench.width as f32 / bench.height as f32;
    let camera = scene.default_camera(aspect);
    let (mut world, handles) = World::new(scene)?;
    let settings = RenderSettings::new(bench.width, bench.height);
    let spec = GraphSpec::builtin("two_phase")?;
    let mut renderer = Renderer::from_world(ctx, shaders, &world, settings.clone(), &spec)?;
    let mut report = DynamicReport {
        device: ctx.caps().name.clone(),
        threads: crate::parallel::threads(),
        instances: bench.instances,
        slots: renderer.scene().instances.len() as u32,
        ..Default::default()
    };
    let still = frames(ctx, &mut renderer, &camera, bench.warmup, bench.frames, |_| Ok(()))?;
    report.static_frame_ms = median(&mut still.iter().map(|s| s.gpu_total_ms).collect::<Vec<_>>());
    report.static_cull_ms = median(&mut still.iter().map(cull_ms).collect::<Vec<_>>());

    let mut rng = SmallRng::seed_from_u64(1);
    let mut added: std::collections::VecDeque<InstanceHandle> = Default::default();
    for &moved in bench.moved.iter().filter(|&&m| m <= bench.instances) {
        progress(&format!("dynamic: {moved} moved per frame"));
        let churn = (moved / 100).max(1);
        // The instances that move are a fixed set, as an engine's dynamic objects are, drawn
        // without replacement (index 0 is the ground) and walked in handle order, as an engine
        // walks its own storage. Their new transforms are prepared off the timed path: the
        // engine has them anyway.
        let moved = moved.min(handles.len() - 1);
        let mut movers: Vec<InstanceHandle> =
            rand::seq::index::sample(&mut rng, handles.len() - 1, moved).into_iter().map(|i| handles[i + 1]).collect();
        movers.sort_unstable();
        let mut changes: Vec<_> = movers
            .iter()
            .map(|&h| world.instance(h).map(|i| (h, i.transform)))
            .collect::<std::result::Result<_, _>>()?;
        let mut world_ms = Vec::new();
        let mut churn_ms = Vec::new();
        let mut sync_ms = Vec::new();
        let measured = frames(ctx, &mut renderer, &camera, bench.warmup, bench.frames, |renderer| {
            for (_, t) in &mut changes {
                t.translation.x += rng.random_range(-0.05..0.05);
            }
            let start = Instant::now();
            world.set_transforms(&changes)?;
            world_ms.push(start.elapsed().as_secs_f64() * 1e3);
            let start = Instant::now();
            for _ in 0..churn {
                let mut copy = *world.instance(handles[rng.random_range(1..handles.len())])?;
                copy.transform.translation.z += 1.0;
                added.push_back(world.insert(copy)?);
            }
            while added.len() > 4 * churn {
                world.remove(added.pop_front().expect("not empty"))?;
            }
            churn_ms.push(start.elapsed().as_secs_f64() * 1e3);
            let update = renderer.sync(shaders, &world)?;
            world.trim_journal(renderer.synced_version().unwrap_or(0));
            sync_ms.push(update.cpu_ms);
            Ok(())
        })?;
        let updates: Vec<_> = measured.iter().filter_map(|s| s.update.clone()).collect();
        let mut bytes: Vec<f64> = updates.iter().map(|u| u.bytes_uploaded as f64).collect();
        let bytes = median(&mut bytes) as u64;
        report.rows.push(DynamicRow {
            moved,
            churn,
            frame_ms: median(&mut measured.iter().map(|s| s.gpu_total_ms).collect::<Vec<_>>()),
            update_gpu_ms: median(&mut updates.iter().map(|u| u.gpu_ms).collect::<Vec<_>>()),
            cull_ms: median(&mut measured.iter().map(cull_ms).collect::<Vec<_>>()),
            world_cpu_ms: median(&mut world_ms[world_ms.len().saturating_sub(measured.len())..].to_vec()),
            churn_cpu_ms: median(&mut churn_ms[churn_ms.len().saturating_sub(measured.len())..].to_vec()),
            sync_cpu_ms: median(&mut sync_ms[sync_ms.len().saturating_sub(measured.len())..].to_vec()),
            record_cpu_ms: median(&mut measured.iter().map(|s| s.cpu_record_ms).collect::<Vec<_>>()),
            bytes,
            host_copy_ms: host_copy_ms(ctx, bytes, 9)?,
            relayouts: updates.iter().filter(|u| u.relayout).count() as u32,
        });
    }

    progress("dynamic: rebuilding instead");
    let start = Instant::now();
    let mut rebuilt = Renderer::from_world(ctx, shaders, &world, settings, &spec)?;
    report.rebuild_cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    report.rebuild_first_frame_ms = rebuilt.render(&camera)?.gpu_total_ms;
    report.full_upload_bytes = rebuilt.scene().instances.len() as u64 * 96;
    report.full_upload_copy_ms = host_copy_ms(ctx, report.full_upload_bytes, 9)?;
    Ok(report)
}

/// Renders `warmup` then `frames` frames, pipelined, calling `change` before each; the
/// measured frames' figures.
fn frames(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    camera: &Camera,
    warmup: u32,
    frames: u32,
    mut change: impl FnMut(&mut Renderer) -> Result<()>,
) -> Result<Vec<FrameStats>> {
    let mut pipeline = FramePipeline::new(ctx)?;
    let mut out = Vec::new();
    let first = renderer.frames_recorded() + warmup as u64;
    for _ in 0..warmup + frames {
        change(renderer)?;
        out.extend(pipeline.submit(renderer, camera)?);
    }
    out.extend(pipeline.finish(renderer)?);
    out.retain(|s| s.frame >= first);
    Ok(out)
}

impl DynamicReport {
    /// The figures as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Dynamic world\n\nDevice: {}. builtin:city, {} instances in {} slots, two_phase. Standing still: frame {:.3} ms, late cull {:.3} ms.\n\n",
            self.device, self.instances, self.slots, self.static_frame_ms, self.static_cull_ms
        );
        s.push_str(&format!("CPU: the world's moves and the sync spread over up to {} threads.\n\n", self.threads));
        s.push_str("| moved / frame | churn | frame ms | update GPU ms | host copy of the same bytes ms | update / copy | bytes per moved | late cull ms | cull / still | world moves CPU ms | churn CPU ms | sync CPU ms | world ns per move | sync ns per change | world + sync ns per moved | record CPU ms | world + sync + record ns per moved | relayouts |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.rows {
            let changes = (r.moved + 2 * r.churn).max(1) as f64;
            let moved = r.moved.max(1) as f64;
            s.push_str(&format!(
                "| {} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.1} | {:.3} | {:.2} | {:.3} | {:.3} | {:.3} | {:.1} | {:.1} | {:.1} | {:.3} | {:.1} | {} |\n",
                r.moved,
                r.churn,
                r.frame_ms,
                r.update_gpu_ms,
                r.host_copy_ms,
                r.update_gpu_ms / r.host_copy_ms.max(1e-9),
                r.bytes as f64 / moved,
                r.cull_ms,
                r.cull_ms / self.static_cull_ms.max(1e-9),
                r.world_cpu_ms,
                r.churn_cpu_ms,
                r.sync_cpu_ms,
                r.world_cpu_ms * 1e6 / moved,
                r.sync_cpu_ms * 1e6 / changes,
                (r.world_cpu_ms + r.sync_cpu_ms) * 1e6 / moved,
                r.record_cpu_ms,
                (r.world_cpu_ms + r.sync_cpu_ms + r.record_cpu_ms) * 1e6 / moved,
                r.relayouts
            ));
        }
        s.push_str(&format!(
            "\nRebuilding the renderer instead: {:.1} ms of CPU, first frame {:.3} ms of GPU. Re-uploading every slot ({} bytes): host copy {:.3} ms.\n",
            self.rebuild_cpu_ms, self.rebuild_first_frame_ms, self.full_upload_bytes, self.full_upload_copy_ms
        ));
        s
    }
}
