//! Point-light placement shared by the generators and the glTF loader.
//!
//! Lights use the shaders' falloff `color * window(d / range) / (d² + 1)`, so a light that should
//! give a radiance near 1 at distance `d` needs a color of about `d² + 1`.

use crate::scene::{PointLight, MAX_COORDINATE};
use glam::{DVec3, Vec3};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// Warm white of a street lamp (sodium-ish, normalised to a maximum component of 1).
pub const WARM: Vec3 = Vec3::new(1.0, 0.78, 0.52);

/// A light whose radiance at distance `reach` (straight below it, say) is about `brightness`,
/// and which fades out completely at `range`.
pub fn light(position: DVec3, tint: Vec3, brightness: f32, reach: f32, range: f32) -> PointLight {
    PointLight::point(position, tint * brightness * (reach * reach + 1.0), range)
}

/// `n` point lights spread over the box `bounds` (world min, max): a jittered grid over x/z,
/// hanging above the top of the box, with ranges that reach the bottom of the box and overlap
/// their neighbours. Deterministic for a given `seed`. Empty for `n == 0` or a non-finite box.
pub fn scatter(bounds: &(DVec3, DVec3), n: usize, seed: u64) -> Vec<PointLight> {
    let (min, max) = *bounds;
    if n == 0 || !min.is_finite() || !max.is_finite() {
        return Vec::new();
    }
    let size = (max - min).max(DVec3::splat(1e-3));
    let cols = (n as f64).sqrt().ceil().max(1.0) as usize;
    let rows = n.div_ceil(cols);
    let cell = DVec3::new(size.x / cols as f64, 0.0, size.z / rows as f64);
    let cell_size = cell.x.max(cell.z);
    let above = 0.1 * size.y.max(cell_size);
    let drop = size.y + above;
    let reach = (drop * drop + cell_size * cell_size).sqrt();
    let range = (reach * 1.5) as f32;
    let mut rng = SmallRng::seed_from_u64(seed ^ 0x6c69_6768_7473);
    (0..n)
        .map(|i| {
            let (cx, cz) = ((i % cols) as f64, (i / cols) as f64);
            let jx = rng.random_range(0.25..0.75);
            let jz = rng.random_range(0.25..0.75);
            let position = DVec3::new(min.x + (cx + jx) * cell.x, max.y + above, min.z + (cz + jz) * cell.z);
            // A scene that reaches the top of the coordinate range gets its lights at its top,
            // not above the range: an added light must not make a valid scene invalid.
            let position = position.clamp(DVec3::splat(-MAX_COORDINATE), DVec3::splat(MAX_COORDINATE));
            let tint = Vec3::new(1.0, rng.random_range(0.82..0.95), rng.random_range(0.68..0.85));
            // Fill lights: the sun stays the main light, these add local variation.
            light(position, tint, 0.5, drop as f32, range)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scatter_is_deterministic_and_covers_the_box() {
        let b = (DVec3::new(-100.0, 0.0, -50.0), DVec3::new(100.0, 20.0, 50.0));
        let a = scatter(&b, 10, 7);
        assert_eq!(a, scatter(&b, 10, 7));
        assert_ne!(a, scatter(&b, 10, 8));
        assert_eq!(a.len(), 10);
        for l in &a {
            assert!(l.position.is_finite() && l.range > 20.0 && l.color.min_element() > 0.0);
            assert!(l.position.x >= -100.0 && l.position.x <= 100.0 && l.position.y > 20.0);
            // The light reaches the floor of the box below it.
            assert!((l.position.y - b.0.y) < l.range as f64);
        }
        assert!(scatter(&b, 0, 1).is_empty());
        // At the top of the coordinate range the lights stay inside it.
        let top = (DVec3::new(0.0, MAX_COORDINATE - 1.0, 0.0), DVec3::new(10.0, MAX_COORDINATE, 10.0));
        assert!(scatter(&top, 4, 1).iter().all(|l| l.position.y == MAX_COORDINATE));
        assert!(scatter(&(DVec3::NAN, DVec3::ONE), 3, 1).is_empty());
    }
}
