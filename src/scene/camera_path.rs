//! Camera motion over a run of frames, for checking history-based culling under motion: each
//! path moves the camera enough between frames that last frame's visibility is wrong somewhere.

use super::camera::Camera;
use glam::{DQuat, DVec3};
use std::str::FromStr;

/// How the camera moves from frame to frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraPath {
    /// It does not.
    #[default]
    Still,
    /// Circles the target at constant distance and height, 12 degrees per frame.
    Orbit,
    /// Moves towards the target and back, 6% of the initial distance per frame.
    Dolly,
    /// Jitters eye and target by up to 4% of the distance (deterministic pseudo-random; frame 0
    /// is the base camera).
    Shake,
}

impl FromStr for CameraPath {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "still" => Ok(CameraPath::Still),
            "orbit" => Ok(CameraPath::Orbit),
            "dolly" => Ok(CameraPath::Dolly),
            "shake" => Ok(CameraPath::Shake),
            other => Err(format!("unknown camera path '{other}' (still, orbit, dolly, shake)")),
        }
    }
}

impl CameraPath {
    /// The camera of frame `frame`, starting from `base` at frame 0.
    pub fn camera_at(self, base: &Camera, frame: u32) -> Camera {
        let offset = base.eye - base.target;
        let distance = offset.length();
        let mut camera = base.clone();
        match self {
            CameraPath::Still => {}
            CameraPath::Orbit => {
                let turn = DQuat::from_rotation_y((12.0 * frame as f64).to_radians());
                camera.eye = base.target + turn * offset;
            }
            CameraPath::Dolly => {
                // A triangle wave between the start and 60% closer, 10 frames each way.
                let phase = (frame % 20) as f64;
                let closer = if phase <= 10.0 { phase } else { 20.0 - phase } * 0.06;
                camera.eye = base.target + offset * (1.0 - closer);
            }
            CameraPath::Shake if frame == 0 => {}
            CameraPath::Shake => {
                let jitter = |k: u32| {
                    let h = hash(frame.wrapping_mul(3).wrapping_add(k));
                    (h as f64 / u32::MAX as f64) * 2.0 - 1.0
                };
                let amount = 0.04 * distance;
                camera.eye += DVec3::new(jitter(0), jitter(1), jitter(2)) * amount;
                camera.target += DVec3::new(jitter(3), jitter(4), jitter(5)) * amount;
            }
        }
        camera
    }
}

/// A small integer hash (deterministic across platforms).
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_move_the_camera_and_keep_it_valid() {
        let base = Camera::default();
        for path in [CameraPath::Orbit, CameraPath::Dolly, CameraPath::Shake] {
            assert_eq!(path.camera_at(&base, 0).eye, base.eye, "{path:?} starts at the base camera");
            let moved = path.camera_at(&base, 3);
            assert!(moved.eye.distance(base.eye) > 0.05, "{path:?} does not move");
            assert!(moved.validate().is_ok());
        }
        let orbit = CameraPath::Orbit.camera_at(&base, 5);
        assert!(((orbit.eye - orbit.target).length() - (base.eye - base.target).length()).abs() < 1e-9);
        assert_eq!(CameraPath::Shake.camera_at(&base, 7), CameraPath::Shake.camera_at(&base, 7));
        assert!("spin".parse::<CameraPath>().is_err());
    }
}
