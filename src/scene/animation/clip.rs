//! Clips (glTF animations): channels that key a property of a node over time, and their
//! interpolation (glTF 2.0 section 3.11, appendix C).

use glam::{Quat, Vec4};

/// How values between keys are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the key before.
    Step,
    /// Linear; rotations by spherical linear interpolation on the shorter arc.
    Linear,
    /// Cubic Hermite spline with per-key in and out tangents (scaled by the key interval);
    /// rotations are normalised after.
    CubicSpline,
}

/// The property of a node a channel keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// Translation (3 values per key).
    Translation,
    /// Rotation quaternion x, y, z, w (4 values per key).
    Rotation,
    /// Scale (3 values per key).
    Scale,
    /// Morph weights (one per morph target of the node's mesh).
    Weights,
}

/// One keyed property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node, an index into [`super::SceneAnimation::nodes`].
    pub node: u32,
    /// What it keys.
    pub property: Property,
    /// How it interpolates.
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing, at least one.
    pub times: Vec<f32>,
    /// `width` values per key, or for [`Interpolation::CubicSpline`] in-tangent, value and
    /// out-tangent of `width` values each per key.
    pub values: Vec<f32>,
    /// Values per key: 3, 4, or the number of morph targets.
    pub width: u32,
}

impl Channel {
    /// The channel's value at `t` seconds (the first key's before it, the last key's after it)
    /// into `out`, which must hold `width` values.
    pub fn sample(&self, t: f64, out: &mut [f32]) {
        let w = self.width as usize;
        let n = self.times.len();
        if n == 0 || out.len() < w || self.values.len() < n * w * self.stride_factor() {
            return;
        }
        let after = self.times.partition_point(|&k| k as f64 <= t);
        if after == 0 || after == n {
            out[..w].copy_from_slice(self.key(if after == 0 { 0 } else { n - 1 }));
            return;
        }
        let k = after - 1;
        let (t0, t1) = (self.times[k] as f64, self.times[k + 1] as f64);
        let s = ((t - t0) / (t1 - t0)) as f32;
        let (a, b) = (self.key(k), self.key(k + 1));
        match self.interpolation {
            Interpolation::Step => out[..w].copy_from_slice(a),
            Interpolation::Linear if self.property == Property::Rotation => {
                let q = slerp(quat(a), quat(b), s);
                out[..4].copy_from_slice(&q.to_array());
            }
            Interpolation::Linear => {
                for (o, (a, b)) in out.iter_mut().zip(a.iter().zip(b)) {
                    *o = a + (b - a) * s;
                }
            }
            Interpolation::CubicSpline => {
                let dt = (t1 - t0) as f32;
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                let out_tangent = &self.values[(3 * k + 2) * w..][..w];
                let in_tangent = &self.values[3 * (k + 1) * w..][..w];
                for i in 0..w {
                    out[i] = h00 * a[i] + h10 * dt * out_tangent[i] + h01 * b[i] + h11 * dt * in_tangent[i];
                }
                if self.property == Property::Rotation {
                    let q = Vec4::from_slice(&out[..4]).try_normalize().unwrap_or(Vec4::W);
                    out[..4].copy_from_slice(&q.to_array());
                }
            }
        }
    }

    /// The value of key `k` (without tangents).
    fn key(&self, k: usize) -> &[f32] {
        let w = self.width as usize;
        let at = if self.interpolation == Interpolation::CubicSpline { (3 * k + 1) * w } else { k * w };
        &self.values[at..at + w]
    }

    fn stride_factor(&self) -> usize {
        if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        }
    }

    /// The time of the last key.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }
}

/// A quaternion from 4 values (x, y, z, w).
fn quat(v: &[f32]) -> Quat {
    Quat::from_xyzw(v[0], v[1], v[2], v[3])
}

/// Spherical linear interpolation on the shorter arc, normalised; `a` itself at `s = 0`.
fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    if s == 0.0 {
        return a;
    }
    let b = if a.dot(b) < 0.0 { -b } else { b };
    a.slerp(b, s).normalize()
}

/// A glTF animation: channels and the time of its last key.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The glTF animation's name, or `animation #i`.
    pub name: String,
    /// Seconds from 0 to its last key; a pose's time wraps over it.
    pub duration: f64,
    /// Its channels on the animated nodes.
    pub channels: Vec<Channel>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(property: Property, interpolation: Interpolation, values: Vec<f32>, width: u32) -> Channel {
        Channel { node: 0, property, interpolation, times: vec![1.0, 3.0], values, width }
    }

    fn at(c: &Channel, t: f64) -> Vec<f32> {
        let mut out = vec![0.0; c.width as usize];
        c.sample(t, &mut out);
        out
    }

    #[test]
    fn step_and_linear_hold_the_ends_and_keys() {
        let lin = channel(Property::Translation, Interpolation::Linear, vec![0.0, 2.0, 4.0, 1.0, 0.0, 8.0], 3);
        assert_eq!(at(&lin, 0.0), vec![0.0, 2.0, 4.0]);
        assert_eq!(at(&lin, 1.0), vec![0.0, 2.0, 4.0]);
        assert_eq!(at(&lin, 2.0), vec![0.5, 1.0, 6.0]);
        assert_eq!(at(&lin, 3.0), vec![1.0, 0.0, 8.0]);
        assert_eq!(at(&lin, 9.0), vec![1.0, 0.0, 8.0]);
        let step = Channel { interpolation: Interpolation::Step, ..lin };
        assert_eq!(at(&step, 2.9), vec![0.0, 2.0, 4.0]);
        assert_eq!(at(&step, 3.0), vec![1.0, 0.0, 8.0]);
    }

    #[test]
    fn rotations_take_the_shorter_arc() {
        let a = Quat::IDENTITY;
        // -q of a 90 degree turn: the same rotation, the long way round if taken literally.
        let b = -Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let rot = channel(Property::Rotation, Interpolation::Linear, [a.to_array(), b.to_array()].concat(), 4);
        let mid = quat(&at(&rot, 2.0));
        let expected = Quat::from_rotation_z(std::f32::consts::FRAC_PI_4);
        assert!(mid.dot(expected).abs() > 1.0 - 1e-6, "{mid}");
        assert!((mid.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn cubic_splines_follow_hermite_with_scaled_tangents() {
        // Value 0 -> 1 over 2 seconds, out-tangent 1 per second at the first key, in-tangent 0
        // at the second: p(s) = h10 * 2 * 1 + h01 * 1.
        let c = channel(Property::Weights, Interpolation::CubicSpline, vec![9.0, 0.0, 1.0, 0.0, 1.0, 9.0], 1);
        assert_eq!(at(&c, 1.0), vec![0.0]);
        assert_eq!(at(&c, 3.0), vec![1.0]);
        let s = 0.25f32;
        let expected = (s * s * s - 2.0 * s * s + s) * 2.0 + (-2.0 * s * s * s + 3.0 * s * s);
        assert!((at(&c, 1.5)[0] - expected).abs() < 1e-6);
    }
}
