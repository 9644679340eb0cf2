//! `builtin:dense`: sculpted props of 50 000 to 100 000 triangles each, scattered over a ground
//! plane, for levels of detail: at its default size the instances draw more than 10^8 triangles,
//! so the frame grows with the triangles in view, not with the pixels, unless distant props are
//! drawn coarser.
//!
//! Each kind is a smooth base shape (sphere, torus, capsule, flattened sphere) displaced along its
//! normals by a sum of sine waves of random directions and frequencies: rock-like bumps at several
//! scales that a simplifier cannot remove without error, as a scanned or sculpted prop has.
//! Positions decide the displacement, so vertices that share a position (a seam) stay together.

use super::shapes;
use super::{count_option, instance_storage, lights, material, MAX_INSTANCES, MAX_LIGHTS};
use crate::scene::error::SceneError;
use crate::scene::mesh::MeshData;
use crate::scene::source::LoadOptions;
use crate::scene::{Instance, Scene, Transform};
use glam::{DVec3, Mat3, Quat, Vec3};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::f32::consts::TAU;

/// Instances when [`LoadOptions::instances`] is `None`: with the kinds' triangles, about
/// 1.3 x 10^8 triangles in all.
pub const DEFAULT_INSTANCES: usize = 1_600;
/// Lights when [`LoadOptions::lights`] is `None`.
pub const DEFAULT_LIGHTS: usize = 16;
/// Average spacing of the props (m).
pub const SPACING: f64 = 9.0;
/// Waves summed in a kind's displacement.
const WAVES: usize = 12;

/// Generates the dense scene.
pub fn generate(options: &LoadOptions) -> Result<Scene, SceneError> {
    let n = count_option("dense", "instances", options.instances, DEFAULT_INSTANCES, 1, MAX_INSTANCES)?;
    let light_count = count_option("dense", "lights", options.lights, DEFAULT_LIGHTS, 0, MAX_LIGHTS)?;
    let mut scene = Scene { name: "builtin:dense".into(), ..Default::default() };
    let mut rng = SmallRng::seed_from_u64(options.seed);
    let stones = [[0.42, 0.40, 0.37], [0.55, 0.50, 0.42], [0.30, 0.32, 0.34], [0.60, 0.45, 0.35]];
    for (m, albedo) in stones.iter().enumerate() {
        scene.add_material(material(&format!("dense/stone#{m}"), *albedo, 0.75, 0.0));
    }
    let ground_material = scene.add_material(material("dense/ground", [0.25, 0.3, 0.2], 0.9, 0.0));
    let kinds = kinds(&mut rng);
    for (name, data) in &kinds {
        scene.add_mesh(&format!("dense/{name}"), data, &format!("builtin:dense kind '{name}'"))?;
    }
    let side = SPACING * (n as f64).sqrt();
    let ground = scene.add_mesh("dense/ground", &shapes::ground(side as f32 + 20.0), "builtin:dense ground")?;

    scene.instances = instance_storage("dense", n + 1)?;
    scene.instances.push(Instance {
        transform: Transform { linear: Mat3::IDENTITY, translation: DVec3::ZERO },
        mesh: ground,
        material: ground_material,
        flags: crate::scene::FLAG_OCCLUDER,
    });
    for i in 0..n {
        let mesh = (i % kinds.len()) as u32;
        let scale: f32 = rng.random_range(0.8..2.5);
        let translation =
            DVec3::new(rng.random_range(-0.5..0.5) * side, scale as f64 * 0.8, rng.random_range(-0.5..0.5) * side);
        let tilt = Quat::from_axis_angle(Vec3::X, rng.random_range(-0.3..0.3));
        let rotation = Quat::from_rotation_y(rng.random_range(0.0..TAU)) * tilt;
        let linear = Mat3::from_quat(rotation) * Mat3::from_diagonal(Vec3::splat(scale));
        let material = rng.random_range(0..stones.len() as u32);
        scene.instances.push(Instance { transform: Transform { linear, translation }, mesh, material, flags: 0 });
    }
    if let Some(bounds) = scene.world_bounds() {
        scene.lights = lights::scatter(&bounds, light_count, options.seed);
    }
    Ok(scene)
}

/// The prop kinds, each with its name.
pub fn kinds(rng: &mut SmallRng) -> Vec<(&'static str, MeshData)> {
    let bases = [
        ("rock", shapes::uv_sphere(1.0, 320, 160), 0.22),
        ("ring", shapes::torus(1.0, 0.4, 384, 96), 0.08),
        ("pillar", shapes::capsule(0.45, 2.4, 256, 64), 0.1),
        ("boulder", stretched(shapes::uv_sphere(1.0, 256, 128), Vec3::new(1.3, 0.75, 1.0)), 0.18),
    ];
    bases.into_iter().map(|(name, base, amplitude)| (name, displaced(base, amplitude, rng))).collect()
}

/// `base` scaled by `scale` per axis (its normals then come from its faces).
fn stretched(mut base: MeshData, scale: Vec3) -> MeshData {
    for p in &mut base.positions {
        *p *= scale;
    }
    for n in &mut base.normals {
        *n = (*n / scale).normalize_or_zero();
    }
    base
}

/// `base` with every vertex moved along its normal by up to `amplitude`, by a sum of waves.
fn displaced(mut base: MeshData, amplitude: f32, rng: &mut SmallRng) -> MeshData {
    let waves: Vec<(Vec3, f32, f32, f32)> = (0..WAVES)
        .map(|k| {
            let direction =
                Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                    .try_normalize()
                    .unwrap_or(Vec3::Y);
            // Frequencies from broad lumps to fine grain; weights fall with frequency.
            let frequency = 1.5 * 1.45f32.powi(k as i32) * rng.random_range(0.8..1.25);
            (direction, frequency, rng.random_range(0.0..TAU), 1.0 / (1.0 + k as f32))
        })
        .collect();
    let total: f32 = waves.iter().map(|w| w.3).sum();
    let height = |p: Vec3| waves.iter().map(|(d, f, phase, w)| w * (f * d.dot(p) + phase).sin()).sum::<f32>() / total;
    for (p, n) in base.positions.iter_mut().zip(&base.normals) {
        *p += *n * amplitude * height(*p);
    }
    // The normals follow the new surface: computed from its faces.
    base.normals.clear();
    // Ordered for the post-transform vertex cache, as an asset pipeline would ship it, so that
    // full detail is measured at its best.
    base.indices = meshopt::optimize_vertex_cache(&base.indices, base.positions.len());
    base
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_is_dense_and_the_default_draws_1e8_triangles() {
        let kinds = kinds(&mut SmallRng::seed_from_u64(1));
        let triangles: Vec<usize> = kinds.iter().map(|(_, m)| m.indices.len() / 3).collect();
        assert!(triangles.iter().all(|&t| (50_000..=150_000).contains(&t)), "{triangles:?}");
        let mean = triangles.iter().sum::<usize>() / triangles.len();
        assert!(mean * DEFAULT_INSTANCES >= 100_000_000, "{} triangles", mean * DEFAULT_INSTANCES);
        for (name, m) in &kinds {
            assert!(m.positions.iter().all(|p| p.is_finite() && p.length() < 4.0), "{name}");
        }
    }
}
