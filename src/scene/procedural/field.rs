//! `builtin:field`: `kinds` distinct meshes scattered over a square with random rotations and
//! scales, for heterogeneous instanced culling (many draw groups of different sizes).
//!
//! Kind `k` is shape family `k % FAMILIES` with parameters (segment counts, proportions) derived
//! from `k` and the seed, so every kind is a genuinely different mesh; instance `i` uses kind
//! `i % kinds`, so every kind is used once `instances >= kinds`. About 2% of the instances are
//! mirrored (negative determinant), 20% are tilted off the vertical and 15% are scaled
//! non-uniformly, since those are the hard cases of bounds transformation and culling.

use super::shapes;
use super::{count_option, instance_storage, lights, material, MAX_INSTANCES, MAX_KINDS, MAX_LIGHTS};
use crate::scene::error::SceneError;
use crate::scene::mesh::MeshData;
use crate::scene::source::LoadOptions;
use crate::scene::{Instance, Scene, Transform};
use glam::{DVec3, Mat3, Mat4, Quat, Vec3};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::f32::consts::TAU;

/// Instances when [`LoadOptions::instances`] is `None`.
pub const DEFAULT_INSTANCES: usize = 5_000;
/// Mesh kinds when [`LoadOptions::kinds`] is `None`.
pub const DEFAULT_KINDS: usize = 64;
/// Lights when [`LoadOptions::lights`] is `None`.
pub const DEFAULT_LIGHTS: usize = 16;
/// Average spacing of instances (m): the square's side is `spacing * sqrt(instances)`.
pub const SPACING: f64 = 6.0;
/// Number of shape families that kinds cycle through.
pub const FAMILIES: usize = 24;
/// One instance in `MIRROR_EVERY` is mirrored.
const MIRROR_EVERY: usize = 50;

/// Generates the field.
pub fn generate(options: &LoadOptions) -> Result<Scene, SceneError> {
    let n = count_option("field", "instances", options.instances, DEFAULT_INSTANCES, 1, MAX_INSTANCES)?;
    let kinds = count_option("field", "kinds", options.kinds, DEFAULT_KINDS, 1, MAX_KINDS)?;
    let light_count = count_option("field", "lights", options.lights, DEFAULT_LIGHTS, 0, MAX_LIGHTS)?;
    let mut scene = Scene { name: "builtin:field".into(), ..Default::default() };
    let mut rng = SmallRng::seed_from_u64(options.seed);
    for m in 0..12 {
        let hue = m as f32 / 12.0;
        let albedo = hsv(hue, 0.65, 0.75).to_array();
        scene.add_material(material(
            &format!("field#{m}"),
            albedo,
            0.3 + 0.05 * m as f32,
            if m % 4 == 3 { 0.9 } else { 0.0 },
        ));
    }
    for k in 0..kinds {
        let (family, data) = kind(k, &mut rng);
        scene.add_mesh(&format!("field/{family}#{k}"), &data, &format!("builtin:field kind {k} ({family})"))?;
    }

    let side = SPACING * (n as f64).sqrt();
    scene.instances = instance_storage("field", n)?;
    for i in 0..n {
        let mesh = (i % kinds) as u32;
        let translation = DVec3::new(rng.random_range(-0.5..0.5) * side, 0.0, rng.random_range(-0.5..0.5) * side);
        let rotation = if rng.random::<f32>() < 0.2 {
            let axis = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            Quat::from_axis_angle(axis.try_normalize().unwrap_or(Vec3::X), rng.random_range(0.0..TAU))
        } else {
            Quat::from_rotation_y(rng.random_range(0.0..TAU))
        };
        let s: f32 = rng.random_range(0.5..2.0);
        let mut scale = if rng.random::<f32>() < 0.15 {
            Vec3::new(s * rng.random_range(0.5..1.5), s * rng.random_range(0.5..1.5), s * rng.random_range(0.5..1.5))
        } else {
            Vec3::splat(s)
        };
        if i % MIRROR_EVERY == MIRROR_EVERY / 2 {
            scale.x = -scale.x;
        }
        let linear = Mat3::from_quat(rotation) * Mat3::from_diagonal(scale);
        let material = rng.random_range(0..12u32);
        scene.instances.push(Instance { transform: Transform { linear, translation }, mesh, material, flags: 0 });
    }
    if let Some(bounds) = scene.world_bounds() {
        scene.lights = lights::scatter(&bounds, light_count, options.seed);
    }
    Ok(scene)
}

/// The mesh of kind `k`: family `k % FAMILIES`, variant `k / FAMILIES` picks the segment counts,
/// `rng` the proportions, and a random stretch of 0.8 to 1.25 per axis makes kinds whose family
/// has no continuous parameter distinct as well. Meshes stay small (at most a few hundred triangles) so that 100 000
/// kinds fit comfortably.
pub fn kind(k: usize, rng: &mut SmallRng) -> (&'static str, MeshData) {
    let v = (k / FAMILIES) as u32;
    let seg = 3 + v % 22;
    let mut r = |lo: f32, hi: f32| rng.random_range(lo..hi);
    let stretch = Mat4::from_scale(Vec3::new(r(0.8, 1.25), r(0.8, 1.25), r(0.8, 1.25)));
    let (family, data) = match k % FAMILIES {
        0 => ("box", shapes::cuboid(Vec3::new(r(0.3, 2.0), r(0.3, 2.0), r(0.3, 2.0)))),
        1 => ("chamfered_box", shapes::chamfered_box(Vec3::new(r(0.5, 2.0), r(0.5, 2.0), r(0.5, 2.0)), r(0.02, 0.2))),
        2 => ("cylinder", shapes::cylinder(r(0.2, 1.0), r(0.3, 2.5), seg)),
        3 => ("cone", shapes::cone(r(0.2, 1.0), r(0.3, 2.5), seg)),
        4 => ("frustum", shapes::frustum(r(0.3, 1.0), r(0.05, 0.9), r(0.3, 2.0), seg)),
        5 => ("uv_sphere", shapes::uv_sphere(r(0.3, 1.2), seg.max(4), 2 + v % 10)),
        6 => ("icosphere", shapes::icosphere(r(0.3, 1.2), v % 3)),
        7 => ("torus", shapes::torus(r(0.6, 1.2), r(0.1, 0.4), seg.max(5), 3 + v % 9)),
        8 => ("capsule", shapes::capsule(r(0.15, 0.5), r(1.0, 2.5), seg, 1 + v % 5)),
        9 => ("pyramid", shapes::pyramid(r(0.4, 2.0), r(0.4, 2.0), r(0.3, 2.0))),
        10 => ("prism", shapes::prism(3 + v % 14, r(0.3, 1.2), r(0.2, 2.0))),
        11 => ("tent_prism", shapes::tent_prism(r(0.5, 2.0), r(0.3, 1.5), r(0.5, 3.0))),
        12 => ("wedge", shapes::wedge(Vec3::new(r(0.5, 2.0), r(0.2, 1.5), r(0.5, 2.5)))),
        13 => ("tube", shapes::tube(r(0.2, 0.5), r(0.55, 1.0), r(0.2, 2.0), seg.max(5))),
        14 => ("arch", shapes::arch(r(1.5, 4.0), r(2.0, 4.0), r(0.3, 1.0), 2 + v % 12)),
        15 => ("stairs", shapes::stairs(2 + v % 10, r(0.8, 2.0), r(0.1, 0.25), r(0.2, 0.4))),
        16 => ("crate_stack", shapes::crate_stack(1 + v % 4)),
        17 => ("fence", shapes::fence(r(1.5, 4.0), 2 + v % 8)),
        18 => ("tree_conifer", shapes::tree_conifer(r(2.0, 8.0), seg.max(4))),
        19 => ("kiosk", shapes::kiosk(5 + v % 8)),
        20 => ("car", shapes::car(r(3.5, 6.0), r(1.6, 2.2), r(1.3, 2.4), seg.max(6))),
        21 => ("lamp_post", shapes::lamp_post(r(3.0, 8.0), seg.max(4))),
        22 => ("bench", shapes::bench(r(1.0, 2.5))),
        _ => ("building_stepped", shapes::building_stepped(1 + v % 6)),
    };
    (family, shapes::combine(&[(data, stretch)]))
}

/// HSV (all in [0, 1]) to linear RGB, for spreading material colors.
fn hsv(h: f32, s: f32, v: f32) -> Vec3 {
    let c = v * s;
    let h6 = h.fract() * 6.0;
    let x = c * (1.0 - (h6 % 2.0 - 1.0).abs());
    let (r, g, b) = match h6 as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    Vec3::new(r, g, b) + Vec3::splat(v - c)
}
