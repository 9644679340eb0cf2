//! Dispatches of workgroups counted in a line, laid out over x and y where x alone cannot hold
//! them: `maxComputeWorkGroupCount[0]` is 65535 on some devices (lavapipe, Intel), which one
//! workgroup per 256 instances reaches at 2^24 instances. Shaders find their place in the line
//! with `line_workgroup()` (`shaders/common/line_dispatch.glsl`) and leave the workgroups past
//! its end at once.

use ash::vk;
use std::sync::atomic::{AtomicU32, Ordering};

/// A lower width than the device's, for tests: 0 keeps the device's.
static WIDTH_FOR_TESTS: AtomicU32 = AtomicU32::new(0);

/// Lays every following line dispatch of this process out at most `width` workgroups wide (0:
/// the device's limit again), so that tests cover the two-dimensional layout on small scenes.
/// Results do not depend on it.
#[doc(hidden)]
pub fn set_width_for_tests(width: u32) {
    WIDTH_FOR_TESTS.store(width, Ordering::Relaxed);
}

/// The grid (x, y) for `groups` workgroups in a line: one row when it fits the device's width,
/// else rows as even as the width allows. `groups` 0 dispatches one workgroup (shaders handle
/// an empty line).
pub fn grid(groups: u32, limits: &vk::PhysicalDeviceLimits) -> (u32, u32) {
    let device = limits.max_compute_work_group_count[0].max(1);
    let width = match WIDTH_FOR_TESTS.load(Ordering::Relaxed) {
        0 => device,
        w => w.min(device),
    };
    let groups = groups.max(1);
    let rows = groups.div_ceil(width);
    (groups.div_ceil(rows), rows)
}

/// Records a dispatch of `groups` workgroups in a line (`grid`).
///
/// # Safety
/// `cmd` is recording, with a compute pipeline and everything it reads bound.
pub unsafe fn cmd_dispatch_line(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    limits: &vk::PhysicalDeviceLimits,
    groups: u32,
) {
    let (x, y) = grid(groups, limits);
    // SAFETY: the caller's contract.
    unsafe { device.cmd_dispatch(cmd, x, y, 1) };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(width: u32) -> vk::PhysicalDeviceLimits {
        vk::PhysicalDeviceLimits { max_compute_work_group_count: [width, 65535, 65535], ..Default::default() }
    }

    #[test]
    fn a_line_that_fits_is_one_row() {
        assert_eq!(grid(1000, &limits(65535)), (1000, 1));
        assert_eq!(grid(0, &limits(65535)), (1, 1));
    }

    #[test]
    fn a_longer_line_takes_even_rows_within_the_width() {
        // 10^8 instances, one workgroup per 256.
        let groups = 100_000_000u32.div_ceil(256);
        let (x, y) = grid(groups, &limits(65535));
        assert!(x <= 65535 && x * y >= groups && x * (y - 1) < groups, "{x} x {y}");
        assert_eq!(grid(65536, &limits(65535)), (32768, 2));
    }
}
