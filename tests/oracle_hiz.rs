//! Brute-force proofs of the Hi-Z pyramid and occlusion test (`cullgraph::cull::hiz`):
//! coverage of every level-0 texel by exactly `min(x >> k, size_k − 1)`, conservative texel
//! values, no false "occluded" against a brute-force scan of the rectangle (1× and 4× MSAA), the
//! finer variant culling at least as much, and the `floor(log2)` regression.

use cullgraph::cull::hiz::{
    self, footprint, is_occluded, level_count, level_size, texel_of_pixel, HiZPyramid, HizVariant,
};
use cullgraph::cull::math::{ceil_log2, hiz_level, PixelRect};
use glam::UVec2;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use rand::{Rng, SeedableRng};
use std::cell::Cell;

fn runner(cases: u32) -> TestRunner {
    let cases = std::env::var("ORACLE_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(cases);
    TestRunner::new(Config { cases, failure_persistence: None, ..Config::default() })
}

/// Sizes: 1×1, thin, odd, powers of two, random.
fn size_strategy(max: u32) -> impl Strategy<Value = (u32, u32)> {
    prop_oneof![
        Just((1u32, 1u32)),
        (1u32..=max).prop_map(|n| (1, n)),
        (1u32..=max).prop_map(|n| (n, 1)),
        (0u32..=6, 0u32..=6).prop_map(|(a, b)| (2 * a + 1, 2 * b + 1)),
        (0u32..=7, 0u32..=7).prop_map(|(a, b)| (1 << a, 1 << b)),
        (1u32..=max, 1u32..=max),
    ]
}

/// A depth buffer with structure: a far background, random occluder rectangles, holes and noise.
fn depth_buffer(w: u32, h: u32, samples: u32, seed: u64) -> Vec<f32> {
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed);
    let n = (w * h) as usize;
    let background: f32 = if rng.random_bool(0.3) { 0.0 } else { rng.random_range(0.0..0.3) };
    let mut d = vec![background; n];
    for _ in 0..rng.random_range(0..8) {
        let (x0, y0) = (rng.random_range(0..w), rng.random_range(0..h));
        let (x1, y1) = (rng.random_range(x0..w), rng.random_range(y0..h));
        let z: f32 = rng.random_range(0.0..1.0);
        for y in y0..=y1 {
            for x in x0..=x1 {
                d[(y * w + x) as usize] = z;
            }
        }
    }
    for _ in 0..rng.random_range(0..=(n / 20 + 1)) {
        let i = rng.random_range(0..n);
        d[i] = if rng.random_bool(0.5) { 0.0 } else { rng.random_range(0.0..1.0) };
    }
    // Samples: the pixel's value, some of them a little nearer or farther (edges).
    let mut out = Vec::with_capacity(n * samples as usize);
    for &v in &d {
        for _ in 0..samples {
            out.push(if samples > 1 && rng.random_bool(0.2) {
                (v + rng.random_range(-0.2..0.2)).clamp(0.0, 1.0)
            } else {
                v
            });
        }
    }
    out
}

/// Every level-0 pixel is covered at level k by exactly one texel, `min(p >> k, size_k − 1)`,
/// and that texel's value is ≤ the pixel's depth (every sample's, for MSAA).
fn check_coverage(w: u32, h: u32, samples: u32, depth: &[f32]) -> Result<(), TestCaseError> {
    let p = HiZPyramid::from_msaa_depth(w, h, samples, depth);
    let base = UVec2::new(w, h);
    prop_assert_eq!(p.level_count(), level_count(base));
    let last = level_size(base, p.level_count() - 1);
    prop_assert_eq!(last, UVec2::ONE);
    // cover[p] = texel of the current level covering pixel p (index within the level).
    let mut cover: Vec<u32> = (0..w * h).collect();
    for k in 1..p.level_count() {
        let src = level_size(base, k - 1);
        let dst = level_size(base, k);
        prop_assert_eq!((p.level(k).width, p.level(k).height), (dst.x, dst.y));
        // The footprints of level k partition level k − 1: each source texel has one parent.
        let mut parent = vec![u32::MAX; (src.x * src.y) as usize];
        for ty in 0..dst.y {
            for tx in 0..dst.x {
                let (first, count) = footprint(UVec2::new(tx, ty), src);
                prop_assert!(count.x >= 1 && count.x <= 3 && count.y >= 1 && count.y <= 3);
                for sy in first.y..first.y + count.y {
                    for sx in first.x..first.x + count.x {
                        prop_assert!(sx < src.x && sy < src.y, "footprint leaves the source level");
                        let slot = &mut parent[(sy * src.x + sx) as usize];
                        prop_assert_eq!(*slot, u32::MAX, "source texel ({}, {}) reduced twice", sx, sy);
                        *slot = ty * dst.x + tx;
                    }
                }
            }
        }
        prop_assert!(parent.iter().all(|&t| t != u32::MAX), "a source texel of level {} is dropped", k - 1);
        for c in cover.iter_mut() {
            *c = parent[*c as usize];
        }
        for y in 0..h {
            for x in 0..w {
                let t = cover[(y * w + x) as usize];
                let expect = texel_of_pixel(UVec2::new(x, y), k, dst);
                prop_assert_eq!(UVec2::new(t % dst.x, t / dst.x), expect, "pixel ({}, {}) level {}", x, y, k);
                let v = p.texel(k, expect.x, expect.y);
                for s in 0..samples {
                    prop_assert!(v <= depth[((y * w + x) * samples + s) as usize]);
                }
            }
        }
    }
    Ok(())
}

#[test]
fn every_pixel_is_covered_by_exactly_the_clamped_shifted_texel() {
    runner(600)
        .run(&(size_strategy(150), prop_oneof![Just(1u32), Just(4u32)], any::<u64>()), |((w, h), samples, seed)| {
            check_coverage(w, h, samples, &depth_buffer(w, h, samples, seed))
        })
        .unwrap();
    // The sizes named in the brief, deterministically.
    for (w, h) in [(1023, 767), (1, 1), (3, 3), (1, 1000), (1000, 1), (1920, 1080), (127, 5)] {
        check_coverage(w, h, 1, &depth_buffer(w, h, 1, 1)).unwrap();
    }
}

#[derive(Default)]
struct Counts {
    cases: Cell<u64>,
    hidden: Cell<u64>,
    coarse: Cell<u64>,
    finer: Cell<u64>,
    finer_only: Cell<u64>,
}

fn random_rect(rng: &mut rand::rngs::SmallRng, w: u32, h: u32) -> PixelRect {
    // Small rectangles mostly, every size sometimes.
    let span = |rng: &mut rand::rngs::SmallRng, n: u32| {
        let len = if rng.random_bool(0.7) { rng.random_range(1..=n.min(12)) } else { rng.random_range(1..=n) };
        let a = rng.random_range(0..=n - len);
        (a, a + len - 1)
    };
    let (x0, x1) = span(rng, w);
    let (y0, y1) = span(rng, h);
    PixelRect { x0, y0, x1, y1 }
}

/// The occlusion test against a brute-force scan of the rectangle at level 0 (all samples).
#[test]
fn occlusion_never_hides_a_visible_texel() {
    let counts = Counts::default();
    runner(1500)
        .run(&(size_strategy(300), prop_oneof![Just(1u32), Just(4u32)], any::<u64>()), |((w, h), samples, seed)| {
            let depth = depth_buffer(w, h, samples, seed);
            let p = HiZPyramid::from_msaa_depth(w, h, samples, &depth);
            let mut rng = rand::rngs::SmallRng::seed_from_u64(seed ^ 0x5eed);
            for _ in 0..100 {
                let rect = random_rect(&mut rng, w, h);
                // The farthest sample in the rectangle (reversed-Z: the smallest depth). The
                // object is hidden only when its nearest depth is below it.
                let mut farthest = f32::INFINITY;
                for y in rect.y0..=rect.y1 {
                    for x in rect.x0..=rect.x1 {
                        for s in 0..samples {
                            farthest = farthest.min(depth[((y * w + x) * samples + s) as usize]);
                        }
                    }
                }
                // Nearest depths at and around the decisive value, and random ones.
                let candidates = [
                    farthest,
                    f32::from_bits(farthest.to_bits().saturating_sub(1)).max(0.0),
                    farthest - 1e-3,
                    farthest + 1e-7,
                    rng.random_range(0.0..1.0),
                    0.0,
                ];
                for nearest in candidates {
                    let hidden = nearest < farthest;
                    let coarse = is_occluded(&p, rect, nearest, HizVariant::Coarse);
                    let finer = is_occluded(&p, rect, nearest, HizVariant::Finer);
                    prop_assert!(!coarse || hidden, "coarse culled {rect:?} at {nearest} (farthest {farthest})");
                    prop_assert!(!finer || hidden, "finer culled {rect:?} at {nearest} (farthest {farthest})");
                    prop_assert!(!coarse || finer, "finer kept {rect:?} that coarse culled");
                    counts.cases.set(counts.cases.get() + 1);
                    counts.hidden.set(counts.hidden.get() + hidden as u64);
                    counts.coarse.set(counts.coarse.get() + coarse as u64);
                    counts.finer.set(counts.finer.get() + finer as u64);
                    counts.finer_only.set(counts.finer_only.get() + (finer && !coarse) as u64);
                }
                // The texels read: at most 2×2 (coarse) and 3×3 (finer).
                for (variant, max_span) in [(HizVariant::Coarse, 1), (HizVariant::Finer, 2)] {
                    let (_, lo, hi) = hiz::texel_range(p.base_size(), p.level_count(), rect, variant);
                    prop_assert!(hi.x - lo.x <= max_span && hi.y - lo.y <= max_span, "{variant:?} {rect:?}");
                }
            }
            Ok(())
        })
        .unwrap();
    let pct = |n: &Cell<u64>| 100.0 * n.get() as f64 / counts.hidden.get().max(1) as f64;
    println!(
        "occlusion: {} tests, {} hidden by brute force; coarse culls {} ({:.1}% of hidden), finer culls {} ({:.1}%); \
         finer culls {} more ({:.1}% of hidden, {:.1}% more than coarse)",
        counts.cases.get(),
        counts.hidden.get(),
        counts.coarse.get(),
        pct(&counts.coarse),
        counts.finer.get(),
        pct(&counts.finer),
        counts.finer_only.get(),
        pct(&counts.finer_only),
        100.0 * counts.finer_only.get() as f64 / counts.coarse.get().max(1) as f64
    );
}

/// The level every public project should have used: with `floor(log2)`, a 6-pixel rectangle at
/// x = 3..8 reads level 2 (4-pixel texels) and spans texels 0, 1, 2; a 2×2 read from texel 0
/// misses texel 2, where the hole is, and culls a visible object. `ceil(log2)` does not.
#[test]
fn floor_log2_would_cull_a_visible_object() {
    let (w, h) = (16u32, 4u32);
    let mut depth = vec![1.0f32; (w * h) as usize];
    for y in 0..h {
        depth[(y * w + 8) as usize] = 0.0; // a hole to the far plane at column 8
    }
    let p = HiZPyramid::from_depth(w, h, &depth);
    let rect = PixelRect { x0: 3, y0: 1, x1: 8, y1: 2 };
    let nearest = 0.5; // visible through the hole: 0 ≤ 0.5
    let floor_2x2 = |level: u32| {
        let size = level_size(p.base_size(), level);
        let t0 = texel_of_pixel(UVec2::new(rect.x0, rect.y0), level, size);
        let mut m = f32::INFINITY;
        for ty in t0.y..=(t0.y + 1).min(size.y - 1) {
            for tx in t0.x..=(t0.x + 1).min(size.x - 1) {
                m = m.min(p.texel(level, tx, ty));
            }
        }
        nearest < m
    };
    let w_rect = rect.width().max(rect.height());
    let floor_level = 31 - w_rect.leading_zeros();
    let blog_level = ceil_log2(w_rect.div_ceil(2)); // ceil(log2(max(w, h) / 2))
    assert_eq!((floor_level, blog_level, hiz_level(rect)), (2, 2, 3));
    assert!(floor_2x2(floor_level), "floor(log2) with a 2x2 read culls the visible object");
    assert!(floor_2x2(blog_level));
    assert!(!is_occluded(&p, rect, nearest, HizVariant::Coarse));
    assert!(!is_occluded(&p, rect, nearest, HizVariant::Finer));
    // Level 2 spans three texels here: the finer variant reads all of them.
    let (level, lo, hi) = hiz::texel_range(p.base_size(), p.level_count(), rect, HizVariant::Finer);
    assert_eq!((level, lo.x, hi.x), (2, 0, 2));
    // Without the hole both cull.
    let p = HiZPyramid::from_depth(w, h, &vec![1.0; (w * h) as usize]);
    assert!(is_occluded(&p, rect, nearest, HizVariant::Coarse) && is_occluded(&p, rect, nearest, HizVariant::Finer));
}

/// Odd levels fold the dropped column into the edge texel: a hole in the last column of a
/// 5-wide buffer must reach level 1's last texel; a halving that drops it would cull.
#[test]
fn the_last_column_of_an_odd_level_is_not_dropped() {
    let mut depth = vec![1.0f32; 5 * 3];
    depth[2 * 5 + 4] = 0.0; // pixel (4, 2)
    let p = HiZPyramid::from_depth(5, 3, &depth);
    assert_eq!(p.level(1).texels, vec![1.0, 0.0]);
    assert_eq!(p.level(2).texels, vec![0.0]);
    let rect = PixelRect { x0: 3, y0: 1, x1: 4, y1: 2 };
    assert!(!is_occluded(&p, rect, 0.5, HizVariant::Coarse));
    assert!(!is_occluded(&p, rect, 0.5, HizVariant::Finer));
}
