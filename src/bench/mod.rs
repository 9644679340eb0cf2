//! `cullgraph bench`: speed measured with timestamp queries, in one run, so that every figure
//! can be read as a ratio to the others on the same device (never asserted in tests).
//!
//! - [`culling`](crate::bench::culling): per-pass GPU time of each culling graph over city scenes of growing size,
//!   frame time against no culling in an occluded street view, the share of invisible instances
//!   each scheme culls (exact visibility as the oracle), and the bytes each pass moves against
//!   the device's measured copy bandwidth and a naive atomic-append frustum peer.
//! - [`dynamic`](crate::bench::dynamic): the living world's update path (instances moved, inserted and removed every
//!   frame) against standing still, rebuilding, and a plain host-to-device copy.
//! - [`hiz`](crate::bench::hiz): the Hi-Z pyramid, single dispatch against one dispatch per mip, at several sizes.
//! - [`msaa`](crate::bench::msaa): speed against error of every anti-aliasing method (GPU ms, G-buffer memory, mean
//!   FLIP and PSNR against a supersampled reference), the compressed G-buffer against its
//!   baselines.
//! - [`lod`](crate::bench::lod): levels of detail, speed against error: triangles, frame and
//!   per-pass time, and image error against full detail and a supersampled reference, at each
//!   threshold.
//! - [`plot`](crate::bench::plot): SVG plots of the culling and MSAA figures.
//! - [`views`](crate::bench::views): many views over one world in one frame, what each view
//!   costs beside the shared scene, and resizing a view; with [`multiview`](crate::bench::multiview),
//!   two VR eyes drawn in one multiview pass against a pass per eye.

pub mod culling;
pub mod dynamic;
pub mod hiz;
pub mod lod;
pub mod msaa;
pub mod multiview;
pub mod peer;
pub mod plot;
pub mod shadows;
pub mod views;

use crate::gpu::{GpuContext, PassTiming};
use crate::render::{FramePipeline, Renderer};
use crate::scene::Camera;
use crate::stats::FrameStats;

/// GPU time of one pass.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct PassTime {
    /// Pass name.
    pub pass: String,
    /// Median milliseconds.
    pub ms: f64,
}

/// How long frames run before any is measured, at least: a GPU that idled (while the CPU loaded
/// a scene or computed image errors) takes a few hundred milliseconds to raise its clocks again,
/// and a frame count alone can end before that: frames measured at the lowered clocks run
/// several times slower than the same frames warm.
const MIN_WARMUP: std::time::Duration = std::time::Duration::from_millis(500);

/// Renders `camera` with `renderer` as an application does, frames in flight: at least
/// `warmup` frames and half a second, then `frames` (at least one) measured back to back.
/// Returns the measured frames' stats and, per pass, their median milliseconds, with the
/// median frame milliseconds.
pub fn measure_frames(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    camera: &Camera,
    warmup: u32,
    frames: u32,
) -> crate::Result<(Vec<FrameStats>, Vec<PassTime>, f64)> {
    let mut pipeline = FramePipeline::new(ctx)?;
    let started = std::time::Instant::now();
    let mut warmed = 0u64;
    while warmed < warmup as u64 || started.elapsed() < MIN_WARMUP {
        pipeline.submit(renderer, camera)?;
        warmed += 1;
    }
    let mut measured = Vec::new();
    for _ in 0..frames.max(1) {
        measured.extend(pipeline.submit(renderer, camera)?);
    }
    measured.extend(pipeline.finish(renderer)?);
    measured.retain(|s| s.frame >= warmed);
    let timings: Vec<_> = measured.iter().map(|s| s.gpu_ms.clone()).collect();
    let passes = median_per_pass(&timings).into_iter().map(|(pass, ms)| PassTime { pass, ms }).collect();
    let mut totals: Vec<f64> = measured.iter().map(|s| s.gpu_total_ms).collect();
    Ok((measured, passes, median(&mut totals)))
}

/// The median of `values` (0 for none).
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(|a, b| a.total_cmp(b));
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// Median milliseconds per pass name over frames (in first-seen pass order).
pub fn median_per_pass(frames: &[Vec<PassTiming>]) -> Vec<(String, f64)> {
    let mut names: Vec<String> = Vec::new();
    for t in frames.iter().flatten() {
        if !names.contains(&t.name) {
            names.push(t.name.clone());
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mut v: Vec<f64> = frames.iter().flatten().filter(|t| t.name == name).map(|t| t.ms).collect();
            (name, median(&mut v))
        })
        .collect()
}

/// The process's resident memory in bytes (Linux: `VmRSS` of `/proc/self/status`; `None`
/// elsewhere), for host memory per instance.
pub fn resident_bytes() -> Option<u64> {
    status_bytes("VmRSS:")
}

/// The most resident memory the process has held since [`reset_peak_resident`] (Linux:
/// `VmHWM`; `None` elsewhere).
pub fn peak_resident_bytes() -> Option<u64> {
    status_bytes("VmHWM:")
}

/// Starts a new peak of [`peak_resident_bytes`] at the present resident memory (Linux: 5
/// written to `/proc/self/clear_refs`); false where the system does not allow it.
pub fn reset_peak_resident() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The figure of `/proc/self/status` line `key`, in bytes.
fn status_bytes(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
        let t = |n: &str, ms| PassTiming { name: n.into(), start_ms: 0.0, ms };
        let m = median_per_pass(&[vec![t("a", 1.0), t("b", 5.0)], vec![t("a", 3.0), t("b", 7.0)], vec![t("a", 2.0)]]);
        assert_eq!(m, vec![("a".to_string(), 2.0), ("b".to_string(), 6.0)]);
    }
}
