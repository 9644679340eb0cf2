//! One bound per block of cull slots (`CULL_BLOCK`, 256), around the bounds of every slot in
//! it as the GPU reads them: the instance cull's test step tests it first, and a block wholly
//! outside the frustum, or wholly inside it and occluded, is decided without reading its slots'
//! records (`block_outcome` in `shaders/cull/instance_cull.comp`). Slots are in spatial order
//! within each draw group, so a block's bound is tight and most of a large scene's blocks are
//! decided this way.
//!
//! A block's outcome must be every one of its slots' own: the bound is the union of the slots'
//! decoded bounds, grown by far more than either test rounds, and the block's tests are stricter
//! than a slot's by a margin of their own (`BLOCK_EXTRA`). A changing world's bounds are those of
//! its slots at upload, and each slot update marks its block `BLOCK_TESTS_EVERY_SLOT`
//! (`shaders/world/scatter.comp`), so a block that ever changed is tested slot by slot; once
//! the world's scene grows it has none.

use super::cull_data::{GpuCullRecord, CULL_HUGE};
use crate::scene::FLAG_EMPTY_SLOT;
use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// A block's bound (48 bytes, three 16-byte words as `instance_cull.comp` reads them).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBlockBound {
    /// Center, hi part.
    pub center_hi: [f32; 3],
    /// Slots of the block that hold an instance (0: the block draws nothing).
    pub slots: u32,
    /// Center, lo part (what the hi part leaves of the exact center).
    pub center_lo: [f32; 3],
    /// [`BLOCK_TESTS_EVERY_SLOT`] or 0.
    pub flags: u32,
    /// Half extents, rounded up.
    pub half: [f32; 3],
    /// Unused.
    pub pad: u32,
}

// `BLOCK_BOUND_WORDS` and `BLOCK_BOUND_FLAGS_WORD` in `cull_common.glsl`, which the world's
// scatter writes the flag through.
const _: () =
    assert!(std::mem::size_of::<GpuBlockBound>() == 12 * 4 && std::mem::offset_of!(GpuBlockBound, flags) == 7 * 4);

/// Slots per block (`CULL_BLOCK` in `cull_common.glsl`).
pub const CULL_BLOCK: u32 = 256;

/// Set on a block that the test step never decides as a whole (`BLOCK_TESTS_EVERY_SLOT` in
/// `cull_common.glsl`): one of its slots has a bound that is kept without testing (huge or not
/// finite), its own bound does not fit, or a changing world's update changed one of its slots.
pub const BLOCK_TESTS_EVERY_SLOT: u32 = 1;

/// How much the union of the slots' boxes grows, relative to its extent and to the size of its
/// coordinates: far beyond the rounding of the eye-relative center and of the projection (a few
/// parts in 2^24 of either), so that no slot's own test sees its box reach beyond the block's.
const GROWTH_OF_EXTENT: f64 = 1.0 / 1024.0;
const GROWTH_OF_COORDINATES: f64 = 1.0 / 262_144.0;

/// The bound of a block whose slots have `records`.
pub fn block_bound(records: impl IntoIterator<Item = GpuCullRecord>) -> GpuBlockBound {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut slots = 0u32;
    // A slot that the test step keeps without testing (huge or unfinite) leaves the block to
    // be tested slot by slot; the block still counts every slot that holds an instance, since
    // a block of none is one the step may skip.
    let mut tests_every_slot = false;
    for record in records {
        if (record.group_flags >> 24) & FLAG_EMPTY_SLOT != 0 {
            continue;
        }
        slots += 1;
        if tests_every_slot || record.group_flags & CULL_HUGE != 0 {
            tests_every_slot = true;
            continue;
        }
        let (center_hi, center_lo, _, half) = record.unpack();
        if !(center_hi.is_finite() && center_lo.is_finite() && half.is_finite()) {
            tests_every_slot = true;
            continue;
        }
        let center = center_hi.as_dvec3() + center_lo.as_dvec3();
        lo = lo.min(center - half.as_dvec3());
        hi = hi.max(center + half.as_dvec3());
    }
    let never = GpuBlockBound { slots, flags: BLOCK_TESTS_EVERY_SLOT, ..Default::default() };
    if slots == 0 {
        return GpuBlockBound::default();
    }
    if tests_every_slot {
        return never;
    }
    let center = (lo + hi) * 0.5;
    let extent = (hi - lo) * 0.5;
    let growth = extent * GROWTH_OF_EXTENT
        + DVec3::splat((center.abs().max_element() + extent.max_element()) * GROWTH_OF_COORDINATES);
    let (center_hi, center_lo) = super::gpu_types::split_hi_lo(center);
    // What the two parts leave of the exact center grows the box too.
    let split_error = (center - (center_hi.as_dvec3() + center_lo.as_dvec3())).abs();
    let half = (extent + growth + split_error).to_array().map(f32_up);
    if half.iter().any(|h| !h.is_finite() || *h > 1.0e30) {
        return never;
    }
    GpuBlockBound { center_hi: center_hi.to_array(), slots, center_lo: center_lo.to_array(), flags: 0, half, pad: 0 }
}

/// The smallest f32 not below `x` (`x` at least 0).
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) >= x || !f.is_finite() {
        f
    } else {
        f32::from_bits(f.to_bits() + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use proptest::prelude::*;

    fn record(center: DVec3, half: Vec3, flags: u32) -> GpuCullRecord {
        let (hi, lo) = super::super::gpu_types::split_hi_lo(center);
        GpuCullRecord::new(hi, lo, half.length(), half, 0, flags)
    }

    #[test]
    fn a_block_contains_every_slots_bound_as_the_gpu_reads_it() {
        let records: Vec<_> = (0..256)
            .map(|i| {
                let t = i as f64;
                record(
                    DVec3::new(1.0e6 + t * 0.37, -t * 1.3, 5.0e5 - t),
                    Vec3::new(0.5, 2.0 + i as f32 * 0.01, 0.25),
                    0,
                )
            })
            .collect();
        let block = block_bound(records.iter().copied());
        assert_eq!((block.slots, block.flags), (256, 0));
        let center = Vec3::from_array(block.center_hi).as_dvec3() + Vec3::from_array(block.center_lo).as_dvec3();
        let half = Vec3::from_array(block.half).as_dvec3();
        for r in &records {
            let (hi, lo, _, h) = r.unpack();
            let c = hi.as_dvec3() + lo.as_dvec3();
            // Inside with room to spare: the growth, not the rounding, decides.
            let room = (center + half) - (c + h.as_dvec3());
            let room_low = (c - h.as_dvec3()) - (center - half);
            assert!(room.min_element() > 1.0e-3 && room_low.min_element() > 1.0e-3, "{room} {room_low}");
        }
    }

    #[test]
    fn empty_slots_are_left_out_and_huge_or_unfinite_ones_test_every_slot() {
        let near = record(DVec3::new(1.0, 2.0, 3.0), Vec3::splat(0.5), 0);
        let far_empty = record(DVec3::splat(1.0e5), Vec3::splat(0.5), FLAG_EMPTY_SLOT);
        let block = block_bound([near, far_empty]);
        assert_eq!(block.slots, 1);
        assert!(Vec3::from_array(block.half).max_element() < 0.51);
        assert_eq!(block_bound([far_empty]), GpuBlockBound::default());
        let huge = GpuCullRecord::new(Vec3::ZERO, Vec3::ZERO, 1.0e5, Vec3::splat(1.0e5), 0, 0);
        // Such a block still counts its slots: one of none is skipped as empty.
        let every_slot = |slots| GpuBlockBound { slots, flags: BLOCK_TESTS_EVERY_SLOT, ..Default::default() };
        assert_eq!(block_bound([near, huge]), every_slot(2));
        assert_eq!(block_bound([huge]), every_slot(1));
        assert_eq!(block_bound([far_empty, huge, near]), every_slot(2));
        let unfinite = record(DVec3::new(f64::NAN, 0.0, 0.0), Vec3::ONE, 0);
        assert_eq!(block_bound([unfinite, near]), every_slot(2));
    }

    /// A slot of a block as a property test draws it: empty, huge, unfinite or an ordinary box
    /// anywhere up to 10^7 units from the origin.
    fn any_slot() -> impl Strategy<Value = GpuCullRecord> {
        let coordinate = -1.0e7f64..1.0e7;
        let half = 0.0f32..2000.0;
        (0u8..10, (coordinate.clone(), coordinate.clone(), coordinate), (half.clone(), half.clone(), half)).prop_map(
            |(kind, (x, y, z), (hx, hy, hz))| {
                let center = DVec3::new(x, y, z);
                let half = Vec3::new(hx, hy, hz);
                match kind {
                    0 => record(center, half, FLAG_EMPTY_SLOT),
                    1 => GpuCullRecord::new(Vec3::ZERO, Vec3::ZERO, 1.0e5, Vec3::splat(1.0e5), 0, 0),
                    2 => record(DVec3::new(f64::INFINITY, y, z), half, 0),
                    _ => record(center, half, 0),
                }
            },
        )
    }

    proptest! {
        /// Whatever its slots, a block counts each one that holds an instance; it is tested
        /// slot by slot exactly when one of them is huge or unfinite, and otherwise its bound
        /// holds every slot's bound as the GPU reads it.
        #[test]
        fn a_block_counts_its_slots_and_holds_their_bounds(slots in proptest::collection::vec(any_slot(), 1..256)) {
            let block = block_bound(slots.iter().copied());
            let held: Vec<_> = slots.iter().filter(|r| (r.group_flags >> 24) & FLAG_EMPTY_SLOT == 0).collect();
            prop_assert_eq!(block.slots as usize, held.len());
            let untested = held.iter().any(|r| {
                let (hi, lo, _, half) = r.unpack();
                r.group_flags & CULL_HUGE != 0 || !(hi.is_finite() && lo.is_finite() && half.is_finite())
            });
            prop_assert_eq!(block.flags == BLOCK_TESTS_EVERY_SLOT, untested);
            if !untested && !held.is_empty() {
                let center = Vec3::from_array(block.center_hi).as_dvec3() + Vec3::from_array(block.center_lo).as_dvec3();
                let half = Vec3::from_array(block.half).as_dvec3();
                for r in held {
                    let (hi, lo, _, h) = r.unpack();
                    let c = hi.as_dvec3() + lo.as_dvec3();
                    prop_assert!((c + h.as_dvec3()).cmple(center + half).all() && (c - h.as_dvec3()).cmpge(center - half).all());
                }
            }
        }
    }
}
