//! The viewer's fly camera: yaw and pitch from the mouse, movement from held keys, at a speed
//! scaled to the scene so that crossing it takes the same time in a room and in a city.

use cullgraph::scene::Camera;
use glam::DVec3;

/// A direction of movement a held key asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    /// Along the view direction.
    Forward,
    /// Against it.
    Back,
    /// To the left, level.
    Left,
    /// To the right, level.
    Right,
    /// Straight up (world +Y).
    Up,
    /// Straight down.
    Down,
}

const MOVES: [Move; 6] = [Move::Forward, Move::Back, Move::Left, Move::Right, Move::Up, Move::Down];

/// Radians of turn per pixel of mouse movement.
const LOOK_PER_PIXEL: f64 = 0.003;
/// How much faster a held Shift moves.
const FAST: f64 = 4.0;
/// Pitch stays this far from straight up or down, so that the view never flips.
const PITCH_LIMIT: f64 = 89.0_f64 * std::f64::consts::PI / 180.0;

/// A first-person camera flying through the scene.
#[derive(Clone, Debug)]
pub struct FlyCamera {
    /// The camera as rendered: projection, near plane and jitter are kept from the start.
    camera: Camera,
    /// Radians about +Y from -Z (0 looks along -Z, positive turns left).
    yaw: f64,
    /// Radians above the horizon.
    pitch: f64,
    /// World units a second.
    speed: f64,
    held: [bool; 6],
    fast: bool,
}

impl FlyCamera {
    /// Starts at `camera`, moving `speed` world units a second.
    pub fn new(camera: Camera, speed: f64) -> Self {
        let mut fly = Self {
            camera: camera.clone(),
            yaw: 0.0,
            pitch: 0.0,
            speed: speed.max(1e-3),
            held: [false; 6],
            fast: false,
        };
        fly.look_at(&camera);
        fly
    }

    /// The speed a scene of this diagonal wants: across it in about 20 seconds.
    pub fn speed_for(diagonal: f64) -> f64 {
        (diagonal / 20.0).clamp(0.5, 1e6)
    }

    /// Jumps to `camera`'s eye and direction (a spawn point), keeping the speed.
    pub fn look_at(&mut self, camera: &Camera) {
        let dir = (camera.target - camera.eye).normalize_or(DVec3::NEG_Z);
        self.pitch = dir.y.clamp(-1.0, 1.0).asin().clamp(-PITCH_LIMIT, PITCH_LIMIT);
        self.yaw = (-dir.x).atan2(-dir.z);
        self.camera.eye = camera.eye;
        self.camera.target = camera.eye + self.forward();
    }

    /// The camera to render.
    pub fn camera(&self) -> Camera {
        self.camera.clone()
    }

    /// World units a second.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Scales the speed (the mouse wheel).
    pub fn scale_speed(&mut self, factor: f64) {
        self.speed = (self.speed * factor).clamp(1e-3, 1e7);
    }

    /// A movement key went down or up.
    pub fn hold(&mut self, movement: Move, down: bool) {
        if let Some(i) = MOVES.iter().position(|m| *m == movement) {
            self.held[i] = down;
        }
    }

    /// Shift went down or up.
    pub fn hold_fast(&mut self, down: bool) {
        self.fast = down;
    }

    /// Lets go of every key (the window lost focus: no key-up will come).
    pub fn release_all(&mut self) {
        self.held = [false; 6];
        self.fast = false;
    }

    /// Turns by a mouse movement of (`dx`, `dy`) pixels (right and down positive).
    pub fn turn(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx * LOOK_PER_PIXEL;
        self.pitch = (self.pitch - dy * LOOK_PER_PIXEL).clamp(-PITCH_LIMIT, PITCH_LIMIT);
        self.camera.target = self.camera.eye + self.forward();
    }

    /// Moves by what the held keys ask for over `seconds`.
    pub fn step(&mut self, seconds: f64) {
        let forward = self.forward();
        let right = DVec3::new(self.yaw.cos(), 0.0, -self.yaw.sin());
        let mut dir = DVec3::ZERO;
        for (held, movement) in self.held.iter().zip(MOVES) {
            if !held {
                continue;
            }
            dir += match movement {
                Move::Forward => forward,
                Move::Back => -forward,
                Move::Left => -right,
                Move::Right => right,
                Move::Up => DVec3::Y,
                Move::Down => DVec3::NEG_Y,
            };
        }
        let speed = self.speed * if self.fast { FAST } else { 1.0 };
        self.camera.eye += dir.normalize_or_zero() * speed * seconds.clamp(0.0, 0.25);
        self.camera.target = self.camera.eye + forward;
    }

    fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(-sy * cp, sp, -cy * cp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-9
    }

    #[test]
    fn a_camera_keeps_its_eye_and_direction() {
        let camera =
            Camera { eye: DVec3::new(1.0, 2.0, 3.0), target: DVec3::new(4.0, 2.0, -1.0), ..Default::default() };
        let fly = FlyCamera::new(camera.clone(), 1.0);
        let c = fly.camera();
        assert!(close(c.eye, camera.eye));
        assert!(close((c.target - c.eye).normalize(), (camera.target - camera.eye).normalize()));
    }

    #[test]
    fn keys_move_along_the_view_and_level_sideways_at_the_speed() {
        let camera = Camera { eye: DVec3::ZERO, target: DVec3::new(0.0, 0.0, -1.0), ..Default::default() };
        let mut fly = FlyCamera::new(camera, 4.0);
        fly.hold(Move::Forward, true);
        fly.step(0.25);
        assert!(close(fly.camera().eye, DVec3::new(0.0, 0.0, -1.0)));
        fly.hold(Move::Forward, false);
        fly.hold(Move::Right, true);
        fly.hold_fast(true);
        fly.step(0.125);
        assert!(close(fly.camera().eye, DVec3::new(2.0, 0.0, -1.0)), "{:?}", fly.camera().eye);
        // A hitch of a second moves as far as a quarter of one.
        fly.hold_fast(false);
        fly.step(1.0);
        assert!(close(fly.camera().eye, DVec3::new(3.0, 0.0, -1.0)), "{:?}", fly.camera().eye);
        fly.release_all();
        fly.step(0.1);
        assert!(close(fly.camera().eye, DVec3::new(3.0, 0.0, -1.0)));
    }

    #[test]
    fn the_mouse_turns_and_the_pitch_never_flips() {
        let camera = Camera { eye: DVec3::ZERO, target: DVec3::new(0.0, 0.0, -1.0), ..Default::default() };
        let mut fly = FlyCamera::new(camera, 1.0);
        // Right by a quarter turn.
        fly.turn(std::f64::consts::FRAC_PI_2 / LOOK_PER_PIXEL, 0.0);
        let dir = fly.camera().target - fly.camera().eye;
        assert!(close(dir, DVec3::X), "{dir:?}");
        fly.turn(0.0, -1e6);
        let dir = fly.camera().target - fly.camera().eye;
        assert!(dir.y > 0.99 && dir.y < 1.0, "{dir:?}");
    }
}
