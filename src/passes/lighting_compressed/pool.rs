//! Sizing the compressed G-buffer's pool from its counters, read back a few frames late: grow
//! at once when fragments were dropped (to what they asked for, plus a margin), shrink only
//! after the pool has stayed mostly empty for a while, so that the size does not oscillate.
//! A new size is a new value of the `pool_fraction` setting (pool blocks per pixel) of the
//! `gbuffer_compressed` pass that writes the pool the lighting read; the host compiles the graph
//! again with it ([`crate::graph::Adaptation`]).

use super::GbufferPassStats;
use crate::graph::{Adaptation, CompiledGraph, CounterEntry, SettingOverride, Version};

/// Frames the pool must stay under a quarter full before it shrinks.
pub const SHRINK_AFTER_FRAMES: u32 = 30;
/// The largest pool: 7 blocks per pixel, every sample of 8x but the head's.
pub const MAX_FRACTION: f64 = 7.0;
/// The smallest pool the adapter shrinks to.
pub const MIN_FRACTION: f64 = 0.02;

/// The adapter's state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoolAdapter {
    /// Pool blocks per pixel of the graph as last planned; `None` until the first frame says
    /// what the graph started with.
    fraction: Option<f64>,
    quiet_frames: u32,
}

impl PoolAdapter {
    /// Looks at one completed frame's counters for an image of `pixels`; returns the new pool
    /// fraction when the pool should change.
    pub fn observe(&mut self, g: &GbufferPassStats, pixels: u64) -> Option<f64> {
        let pixels = pixels.max(1) as f64;
        // Frames still in flight when the graph was re-planned report the old pool: compare
        // with the planned fraction, not theirs.
        let current = *self.fraction.get_or_insert(g.pool_blocks as f64 / pixels);
        let round = |f: f64| (f.clamp(MIN_FRACTION, MAX_FRACTION) * 1000.0).ceil() / 1000.0;
        if g.overflow_fragments > 0 {
            self.quiet_frames = 0;
            let wanted = round((g.pool_requested as f64 * 1.25 / pixels).max(current * 1.5));
            return (wanted > current).then(|| {
                self.fraction = Some(wanted);
                wanted
            });
        }
        if (g.pool_used as f64) < 0.25 * g.pool_blocks as f64 {
            self.quiet_frames += 1;
            if self.quiet_frames >= SHRINK_AFTER_FRAMES {
                self.quiet_frames = 0;
                let wanted = round(g.pool_used as f64 * 2.0 / pixels);
                if wanted < current {
                    self.fraction = Some(wanted);
                    return Some(wanted);
                }
            }
        } else {
            self.quiet_frames = 0;
        }
        None
    }
}

/// The pool policy of one `lighting_compressed` pass.
#[derive(Default)]
pub struct PoolAdaptation(PoolAdapter);

impl Adaptation for PoolAdaptation {
    fn observe(&mut self, counters: &CounterEntry, plan: &CompiledGraph, pass: usize) -> Vec<SettingOverride> {
        let Ok(stats) = serde_json::from_value::<GbufferPassStats>(counters.value.clone()) else { return Vec::new() };
        // The pass that writes the pool this one reads, and so sizes it.
        let pool = plan.passes.get(pass).and_then(|p| p.bindings.iter().find(|b| b.slot == "gbuffer_pool"));
        let writer = pool.and_then(|pool| {
            plan.passes.iter().find(|p| {
                p.settings.contains_key(POOL_SETTING)
                    && p.bindings.iter().any(|b| b.resource == pool.resource && b.version == Version::Current)
            })
        });
        let (Some(writer), Some(fraction)) = (writer, self.0.observe(&stats, stats.pixels())) else {
            return Vec::new();
        };
        vec![SettingOverride { pass: writer.name.clone(), setting: POOL_SETTING.into(), value: format!("{fraction}") }]
    }
}

/// The setting of `gbuffer_compressed` that sizes its pool.
pub const POOL_SETTING: &str = "pool_fraction";

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(requested: u32, blocks: u32) -> GbufferPassStats {
        GbufferPassStats {
            pool_blocks: blocks,
            pool_used: requested.min(blocks),
            pool_requested: requested,
            overflow_fragments: requested.saturating_sub(blocks),
            ..Default::default()
        }
    }

    #[test]
    fn grows_at_once_and_shrinks_slowly() {
        let mut a = PoolAdapter::default();
        // 1000 pixels, a pool of 100 blocks asked for 300: grow to 300 * 1.25.
        assert_eq!(a.observe(&stats(300, 100), 1000), Some(0.375));
        assert_eq!(a.observe(&stats(300, 375), 1000), None);
        // Mostly empty: nothing for 29 frames, then down to twice the use.
        for _ in 0..SHRINK_AFTER_FRAMES - 1 {
            assert_eq!(a.observe(&stats(20, 375), 1000), None);
        }
        assert_eq!(a.observe(&stats(20, 375), 1000), Some(0.04));
        // Never beyond 7 blocks per pixel, never below the floor.
        assert_eq!(a.observe(&stats(100_000, 40), 1000), Some(MAX_FRACTION));
        let mut b = PoolAdapter::default();
        assert_eq!(b.fraction, None);
        for _ in 0..SHRINK_AFTER_FRAMES {
            b.observe(&stats(0, 500), 1000);
        }
        assert_eq!(b.fraction, Some(MIN_FRACTION));
    }
}
