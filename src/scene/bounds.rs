//! Local-space bounding volumes.

use glam::Vec3;

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The smallest box containing `points` (`None` when empty).
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Option<Self> {
        points.into_iter().fold(None, |acc, p| match acc {
            None => Some(Aabb { min: p, max: p }),
            Some(b) => Some(Aabb { min: b.min.min(p), max: b.max.max(p) }),
        })
    }
    /// Center point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    /// Half of the size along each axis.
    pub fn half_extent(&self) -> Vec3 {
        (self.max - self.min) * 0.5
    }
}

/// Sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Center.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

impl Sphere {
    /// A sphere around `points` centred on their AABB, with the radius of the farthest point
    /// (tighter than the box's circumsphere, and guaranteed to contain every point).
    pub fn around(points: &[Vec3], bounds: &Aabb) -> Self {
        let center = bounds.center();
        let radius = points.iter().map(|p| p.distance(center)).fold(0.0f32, f32::max);
        // Round up by one ulp-ish margin so float error never leaves a vertex outside.
        Sphere { center, radius: radius * (1.0 + 1e-6) + f32::EPSILON }
    }
}
