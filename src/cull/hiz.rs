//! The Hi-Z pyramid (CPU reference) and the Hi-Z occlusion test.
//!
//! Twin of `shaders/common/hiz.glsl` (same names with a `hiz_` prefix) and of
//! `cull_hiz_occluded` in `shaders/common/cull_math.glsl`.
//!
//! # Layout and reduction
//!
//! - Level 0 has the depth buffer's size `W × H`; for an MSAA depth buffer each texel is the
//!   minimum over the pixel's samples first (the farthest sample: reversed-Z).
//! - Level `k + 1` is `max(1, size_k >> 1)` per axis, down to 1×1: `⌊log₂ max(W, H)⌋ + 1` levels.
//! - Texel `x` of level `k + 1` is the minimum of source texels `2x, 2x + 1`, and also `2x + 2`
//!   when `x` is the last texel and `size_k` is odd (the column that halving drops is folded into
//!   the edge texel); when `size_k = 1` the footprint is texel 0 alone. Same in y, so footprints
//!   are 2×2, 2×3, 3×2, 3×3 (and 1×n, n×1 on unit axes).
//! - Consequence (proved by the tests here): level-0 pixel `p` is covered at level `k` by exactly
//!   one texel, `min(p >> k, size_k − 1)` ([`texel_of_pixel`]), and that texel's value is ≤ the
//!   depth of every pixel it covers. The occlusion test therefore reads integer texel
//!   coordinates; no sampler, no normalized coordinates.
//! - The flat layout ([`HiZPyramid::to_flat`]) stores the levels one after another, each row-major;
//!   level `k` starts at [`level_offset`].
//!
//! # The stored pyramid
//!
//! The GPU pyramid (the `hiz` image of the `hiz_build` pass) starts at chain level
//! [`FIRST_STORED_LEVEL`] = 1, half the depth's size ([`stored_size`]): stored mip `m` holds
//! level `m + 1` ([`HiZPyramid::stored_level`]), up to [`stored_mip_count`] mips. Level 0 would
//! cost as much memory traffic as the depth itself, and the occlusion test only needs it for
//! bounds under 2 pixels. A 1×1 depth has no level 1: its stored pyramid is one 1×1 texel, the
//! minimum of the depth (level 0, which is then also the last level). GLSL: `HIZ_FIRST_LEVEL`,
//! `hiz_stored_mip_count`, `hiz_stored_mip` in `shaders/common/hiz.glsl`.

use super::math::{hiz_level, PixelRect};
use glam::UVec2;

/// Which Hi-Z level the occlusion test reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HizVariant {
    /// `L = ⌈log₂ max(w, h)⌉`: at most 2×2 texels.
    Coarse,
    /// `max(L − 1, 0)`: at most 3×3 texels; culls at least as much as `Coarse`.
    Finer,
}

/// Size of `level` for a pyramid whose level 0 is `base`: `max(1, base >> level)` per axis.
/// GLSL: `hiz_level_size`.
pub fn level_size(base: UVec2, level: u32) -> UVec2 {
    (base >> level.min(31)).max(UVec2::ONE)
}

/// Number of levels down to 1×1: `⌊log₂ max(w, h)⌋ + 1`. GLSL: `hiz_level_count`.
pub fn level_count(base: UVec2) -> u32 {
    32 - base.x.max(base.y).max(1).leading_zeros()
}

/// The first chain level that the GPU pyramid stores (in its mip 0). GLSL: `HIZ_FIRST_LEVEL`.
pub const FIRST_STORED_LEVEL: u32 = 1;

/// Size of the stored pyramid's mip 0 (chain level 1) over a depth of size `base`:
/// `max(1, base >> 1)` per axis (1×1 for a 1×1 depth).
pub fn stored_size(base: UVec2) -> UVec2 {
    level_size(base, FIRST_STORED_LEVEL)
}

/// Mips of a full stored pyramid over a depth of size `base`: `level_count(base) − 1`, at least 1
/// (a 1×1 depth stores its single texel). Also `level_count(stored_size(base))`.
/// GLSL: `hiz_stored_mip_count`.
pub fn stored_mip_count(base: UVec2) -> u32 {
    level_count(base).saturating_sub(FIRST_STORED_LEVEL).max(1)
}

/// First texel of `level` in the flat layout. GLSL: `hiz_level_offset`.
pub fn level_offset(base: UVec2, level: u32) -> u32 {
    (0..level).map(|k| level_size(base, k)).map(|s| s.x * s.y).sum()
}

/// The texel of a level of size `size` that covers level-0 pixel `pixel`:
/// `min(pixel >> level, size − 1)`. GLSL: `hiz_texel_of_pixel`.
pub fn texel_of_pixel(pixel: UVec2, level: u32, size: UVec2) -> UVec2 {
    (pixel >> level.min(31)).min(size - UVec2::ONE)
}

/// Source texels one destination texel `dst` reduces along an axis `src` texels long:
/// 1 when `src = 1`, 3 for the last texel of an odd source, else 2. GLSL: `hiz_footprint_count`.
pub fn footprint_count(dst: u32, src: u32) -> u32 {
    if src <= 1 {
        return 1;
    }
    if dst == (src >> 1) - 1 && src & 1 == 1 {
        3
    } else {
        2
    }
}

/// Footprint of destination texel `dst` in a source level of size `src_size`: `(first, count)`
/// per axis. GLSL: `hiz_footprint`.
pub fn footprint(dst: UVec2, src_size: UVec2) -> (UVec2, UVec2) {
    (dst * 2, UVec2::new(footprint_count(dst.x, src_size.x), footprint_count(dst.y, src_size.y)))
}

/// One level: `width × height` texels, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct HiZLevel {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Depths, row-major.
    pub texels: Vec<f32>,
}

impl HiZLevel {
    /// Texel `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> f32 {
        self.texels[(y * self.width + x) as usize]
    }
}

/// A min (reversed-Z: farthest depth) pyramid over a depth buffer of any size.
#[derive(Clone, Debug, PartialEq)]
pub struct HiZPyramid {
    levels: Vec<HiZLevel>,
}

impl HiZPyramid {
    /// The pyramid of a `width × height` depth buffer (row-major, `depth.len() == width·height`).
    ///
    /// # Panics
    /// If a size is 0 or the buffer has the wrong length.
    pub fn from_depth(width: u32, height: u32, depth: &[f32]) -> Self {
        Self::from_msaa_depth(width, height, 1, depth)
    }

    /// The pyramid of an MSAA depth buffer with `samples` samples per pixel, stored pixel by
    /// pixel (`depth[(y·width + x)·samples + s]`): level 0 is the minimum across each pixel's
    /// samples.
    ///
    /// # Panics
    /// If a size or `samples` is 0 or the buffer has the wrong length.
    pub fn from_msaa_depth(width: u32, height: u32, samples: u32, depth: &[f32]) -> Self {
        assert!(width > 0 && height > 0 && samples > 0, "empty depth buffer");
        assert_eq!(depth.len(), (width * height * samples) as usize, "depth buffer size");
        let base: Vec<f32> =
            depth.chunks_exact(samples as usize).map(|s| s.iter().copied().fold(f32::INFINITY, f32::min)).collect();
        let mut levels = vec![HiZLevel { width, height, texels: base }];
        let base_size = UVec2::new(width, height);
        for k in 1..level_count(base_size) {
            let src = levels.last().expect("level 0 exists");
            let size = level_size(base_size, k);
            let mut texels = Vec::with_capacity((size.x * size.y) as usize);
            for y in 0..size.y {
                for x in 0..size.x {
                    let (first, count) = footprint(UVec2::new(x, y), UVec2::new(src.width, src.height));
                    let mut v = f32::INFINITY;
                    for sy in first.y..first.y + count.y {
                        for sx in first.x..first.x + count.x {
                            v = v.min(src.get(sx, sy));
                        }
                    }
                    texels.push(v);
                }
            }
            levels.push(HiZLevel { width: size.x, height: size.y, texels });
        }
        Self { levels }
    }

    /// Level 0 size.
    pub fn base_size(&self) -> UVec2 {
        UVec2::new(self.levels[0].width, self.levels[0].height)
    }

    /// Number of levels.
    pub fn level_count(&self) -> u32 {
        self.levels.len() as u32
    }

    /// Level `k`.
    pub fn level(&self, k: u32) -> &HiZLevel {
        &self.levels[k as usize]
    }

    /// Texel `(x, y)` of level `k`.
    pub fn texel(&self, k: u32, x: u32, y: u32) -> f32 {
        self.levels[k as usize].get(x, y)
    }

    /// Stored mip `mip` of the GPU pyramid: chain level `mip + 1`, or level 0 (the whole
    /// pyramid) for a 1×1 depth, which has no level 1.
    ///
    /// # Panics
    /// If `mip >= stored_mip_count(base)`.
    pub fn stored_level(&self, mip: u32) -> &HiZLevel {
        assert!(mip < stored_mip_count(self.base_size()), "stored mip {mip} out of range");
        &self.levels[((mip + FIRST_STORED_LEVEL) as usize).min(self.levels.len() - 1)]
    }

    /// All levels one after another (each row-major) and the offset of each level.
    pub fn to_flat(&self) -> (Vec<f32>, Vec<u32>) {
        let mut data = Vec::new();
        let mut offsets = Vec::new();
        for l in &self.levels {
            offsets.push(data.len() as u32);
            data.extend_from_slice(&l.texels);
        }
        (data, offsets)
    }
}

/// The level and the inclusive texel range `(level, lo, hi)` that the occlusion test reads for
/// `rect` (level-0 pixels) in a pyramid with `levels` levels over `base`.
///
/// `Coarse`: `min(L, levels − 1)` with `L` from [`hiz_level`] (≤ 2×2 texels); `Finer`: one level
/// below that when it is not 0 (≤ 3×3 texels). The proofs are on [`hiz_level`].
pub fn texel_range(base: UVec2, levels: u32, rect: PixelRect, variant: HizVariant) -> (u32, UVec2, UVec2) {
    let mut level = hiz_level(rect).min(levels - 1);
    if variant == HizVariant::Finer && level > 0 {
        level -= 1;
    }
    let size = level_size(base, level);
    let lo = texel_of_pixel(UVec2::new(rect.x0, rect.y0), level, size);
    let hi = texel_of_pixel(UVec2::new(rect.x1, rect.y1), level, size);
    (level, lo, hi)
}

/// Whether a bound with screen rectangle `rect` and nearest reversed-Z depth `nearest_depth`
/// (from [`super::math::project_sphere`] or [`super::math::project_aabb`]) is hidden:
/// `nearest_depth` strictly below every texel covering the rectangle at the chosen level.
///
/// Conservative: each covering texel is ≤ the depth of every level-0 pixel under it, so if any
/// pixel of `rect` has depth ≤ `nearest_depth`, some texel read does too and the answer is
/// `false`. NaN depth gives `false`.
///
/// GLSL: `bool cull_hiz_occluded(uvec4 rect, float nearest_depth, uvec2 base_size, bool finer)`
/// with `hiz_load` reading the pyramid.
pub fn is_occluded(pyramid: &HiZPyramid, rect: PixelRect, nearest_depth: f32, variant: HizVariant) -> bool {
    let (level, lo, hi) = texel_range(pyramid.base_size(), pyramid.level_count(), rect, variant);
    for ty in lo.y..=hi.y {
        for tx in lo.x..=hi.x {
            // Visible unless strictly nearer-than-stored fails; NaN on either side: visible.
            if nearest_depth.partial_cmp(&pyramid.texel(level, tx, ty)) != Some(std::cmp::Ordering::Less) {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_sizes_of_npot_and_thin_buffers() {
        let sizes =
            |w, h| (0..level_count(UVec2::new(w, h))).map(|k| level_size(UVec2::new(w, h), k)).collect::<Vec<_>>();
        assert_eq!(sizes(1, 1), vec![UVec2::new(1, 1)]);
        assert_eq!(sizes(5, 1), vec![UVec2::new(5, 1), UVec2::new(2, 1), UVec2::new(1, 1)]);
        assert_eq!(sizes(1023, 767).last(), Some(&UVec2::ONE));
        assert_eq!(sizes(1023, 767).len(), 10);
        assert_eq!(sizes(1024, 768).len(), 11);
    }

    #[test]
    fn footprints_fold_the_dropped_texels() {
        // 5 -> 2: {0,1}, {2,3,4}
        assert_eq!((footprint_count(0, 5), footprint_count(1, 5)), (2, 3));
        assert_eq!(footprint_count(0, 3), 3);
        assert_eq!(footprint_count(0, 2), 2);
        assert_eq!(footprint_count(0, 1), 1);
        let p = HiZPyramid::from_depth(5, 1, &[0.9, 0.8, 0.7, 0.6, 0.1]);
        assert_eq!(p.level(1).texels, vec![0.8, 0.1]);
        assert_eq!(p.level(2).texels, vec![0.1]);
    }

    #[test]
    fn the_stored_pyramid_starts_at_level_one() {
        for (w, h) in [(1, 1), (1, 7), (7, 1), (2, 2), (3, 3), (5, 3), (65, 33), (1023, 767), (1920, 1080)] {
            let base = UVec2::new(w, h);
            let mips = stored_mip_count(base);
            assert_eq!(mips, level_count(stored_size(base)), "{w}x{h}");
            assert_eq!(mips, level_count(base).max(2) - 1, "{w}x{h}");
            for m in 0..mips {
                assert_eq!(level_size(stored_size(base), m), level_size(base, m + 1), "{w}x{h} mip {m}");
            }
        }
        let p = HiZPyramid::from_depth(1, 1, &[0.25]);
        assert_eq!(stored_size(UVec2::ONE), UVec2::ONE);
        assert_eq!(p.stored_level(0).texels, vec![0.25]);
        let p = HiZPyramid::from_depth(5, 1, &[0.9, 0.8, 0.7, 0.6, 0.1]);
        assert_eq!(p.stored_level(0).texels, vec![0.8, 0.1]);
        assert_eq!(p.stored_level(1).texels, vec![0.1]);
    }

    #[test]
    fn msaa_takes_the_farthest_sample() {
        let p = HiZPyramid::from_msaa_depth(2, 1, 4, &[0.5, 0.4, 0.9, 0.6, 1.0, 0.2, 0.3, 0.7]);
        assert_eq!(p.level(0).texels, vec![0.4, 0.2]);
        assert_eq!(p.level(1).texels, vec![0.2]);
    }
}
