//! `builtin:crowd`: skinned stalks on a ground slab, each swaying on its own phase through one
//! clip of a [`SceneAnimation`], as a glTF file with skins and an animation would give them: a
//! scene to measure posed instances with (`cullgraph render --scene builtin:crowd --animate`).
//!
//! Every stalk is one instance of one tube mesh (`RINGS` rings of `SIDES` vertices) on three
//! joints (base, middle, top), each joint a node under the stalk's root node, which places the
//! instance. The clip turns the middle and top joints about a horizontal axis of the stalk's
//! own, so the top sweeps out well past the rest pose's bounds.

use super::{count_option, instance_storage, material, shapes, MAX_INSTANCES};
use crate::scene::animation::{
    AnimatedInstance, Channel, Clip, Interpolation, Property, RigNode, SceneAnimation, Skin, Trs,
};
use crate::scene::error::SceneError;
use crate::scene::mesh::MeshData;
use crate::scene::source::LoadOptions;
use crate::scene::{Instance, Scene, Transform};
use glam::{DVec3, Mat4, Quat, Vec3, Vec4};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::f32::consts::TAU;
use std::sync::Arc;

/// Stalks when [`LoadOptions::instances`] is `None`.
pub const DEFAULT_INSTANCES: usize = 1_000;
/// The most stalks: each posed stalk draws its own copy of the mesh (9 KB).
pub const MAX_STALKS: usize = 100_000;
/// Height of a stalk (m) and the distance between neighbours.
const HEIGHT: f32 = 3.0;
const SPACING: f64 = 2.5;
/// Rings along a stalk and vertices around a ring.
const RINGS: u32 = 24;
const SIDES: u32 = 12;
/// The clip's length (s) and keys.
const PERIOD: f32 = 2.0;
const KEYS: usize = 9;

/// Generates the crowd.
pub fn generate(options: &LoadOptions) -> Result<Scene, SceneError> {
    let n = count_option("crowd", "instances", options.instances, DEFAULT_INSTANCES, 1, MAX_STALKS.min(MAX_INSTANCES))?;
    let mut scene = Scene { name: "builtin:crowd".into(), ..Default::default() };
    let mut rng = SmallRng::seed_from_u64(options.seed);
    let ground_material = scene.add_material(material("ground", [0.45, 0.42, 0.38], 0.9, 0.0));
    let stalk_material = scene.add_material(material("stalk", [0.25, 0.6, 0.2], 0.5, 0.0));
    let side = (n as f64).sqrt().ceil() as usize;
    let extent = side as f64 * SPACING;
    let ground = scene.add_mesh("crowd/ground", &shapes::ground(extent as f32 + 4.0), "builtin:crowd ground")?;
    let stalk = scene.add_mesh("crowd/stalk", &stalk_mesh(), "builtin:crowd stalk")?;
    scene.instances = instance_storage("crowd", n + 1)?;
    scene.instances.push(Instance {
        transform: Transform::default(),
        mesh: ground,
        material: ground_material,
        flags: 0,
    });

    let third = HEIGHT / 3.0;
    let mut nodes = Vec::with_capacity(3 * n);
    let mut skins = Vec::with_capacity(n);
    let mut channels = Vec::with_capacity(2 * n);
    let mut animated = Vec::with_capacity(n);
    let node = |parent: Option<u32>, translation: Vec3| {
        let trs = Trs { translation, ..Default::default() };
        RigNode { source: 0, parent, rest: trs.transform(), rest_trs: Some(trs), weights: Vec::new() }
    };
    for i in 0..n {
        // In single precision, as the root node keeps it, so that the first pose puts the
        // stalk exactly where it stands.
        let at = DVec3::new(
            (i % side) as f64 * SPACING - extent / 2.0 + rng.random_range(-0.5..0.5),
            0.0,
            (i / side) as f64 * SPACING - extent / 2.0 + rng.random_range(-0.5..0.5),
        )
        .as_vec3()
        .as_dvec3();
        let instance = scene.instances.len() as u32;
        scene.instances.push(Instance {
            transform: Transform { translation: at, ..Default::default() },
            mesh: stalk,
            material: stalk_material,
            flags: 0,
        });
        let root = nodes.len() as u32;
        nodes.push(node(None, at.as_vec3()));
        nodes.push(node(Some(root), Vec3::new(0.0, third, 0.0)));
        nodes.push(node(Some(root + 1), Vec3::new(0.0, third, 0.0)));
        skins.push(Skin {
            name: format!("stalk {i}"),
            joints: vec![root, root + 1, root + 2],
            inverse_bind: (0..3).map(|j| Mat4::from_translation(Vec3::new(0.0, -third * j as f32, 0.0))).collect(),
        });
        let axis = Quat::from_rotation_y(rng.random_range(0.0..TAU)) * Vec3::X;
        let phase = rng.random_range(0.0..TAU);
        for (joint, amplitude) in [(root + 1, 0.35f32), (root + 2, 0.6)] {
            let times: Vec<f32> = (0..KEYS).map(|k| PERIOD * k as f32 / (KEYS - 1) as f32).collect();
            let values = times
                .iter()
                .flat_map(|&t| {
                    let q = Quat::from_axis_angle(axis, amplitude * (phase + TAU * t / PERIOD).sin());
                    q.to_array()
                })
                .collect();
            channels.push(Channel {
                node: joint,
                property: Property::Rotation,
                interpolation: Interpolation::Linear,
                times,
                values,
                width: 4,
            });
        }
        animated.push(AnimatedInstance { instance, node: root, skin: Some(i as u32), morph_targets: 0 });
    }
    let clip = Clip { name: "sway".into(), duration: PERIOD as f64, channels };
    scene.animation = Some(Arc::new(SceneAnimation::new(nodes, skins, vec![clip], animated)));
    let lights = count_option("crowd", "lights", options.lights, 4, 0, super::MAX_LIGHTS)?;
    let half = extent / 2.0;
    let bounds = (DVec3::new(-half, 0.0, -half), DVec3::new(half, HEIGHT as f64, half));
    scene.lights = super::lights::scatter(&bounds, lights, options.seed);
    Ok(scene)
}

/// A tube of height [`HEIGHT`] along y, thinning to the top, on joints 0 (base), 1 and 2,
/// blended over a band around each joint.
fn stalk_mesh() -> MeshData {
    let mut m = MeshData::default();
    let third = HEIGHT / 3.0;
    for r in 0..RINGS {
        let y = HEIGHT * r as f32 / (RINGS - 1) as f32;
        let radius = 0.18 * (1.0 - 0.7 * y / HEIGHT);
        // The share of the joint above, rising over a band around each joint.
        let blend = |joint: f32| ((y - joint * third) / (0.3 * third) + 0.5).clamp(0.0, 1.0);
        let (b1, b2) = (blend(1.0), blend(2.0));
        let weights = Vec4::new(1.0 - b1, b1 - b2, b2, 0.0);
        for s in 0..SIDES {
            let a = TAU * s as f32 / SIDES as f32;
            m.positions.push(Vec3::new(radius * a.cos(), y, radius * a.sin()));
            m.normals.push(Vec3::new(a.cos(), 0.0, a.sin()));
            m.joints.push([0, 1, 2, 0]);
            m.weights.push(weights);
        }
    }
    for r in 0..RINGS - 1 {
        for s in 0..SIDES {
            let (a, b) = (r * SIDES + s, r * SIDES + (s + 1) % SIDES);
            let (c, d) = (a + SIDES, b + SIDES);
            m.indices.extend([a, c, b, b, c, d]);
        }
    }
    // A cap on top.
    let top = (RINGS - 1) * SIDES;
    for s in 1..SIDES - 1 {
        m.indices.extend([top, top + s + 1, top + s]);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every stalk is animated and skinned on 3 joints, and its pose stays finite and bends it
    /// away from its rest shape.
    #[test]
    fn every_stalk_sways_through_the_clip() {
        let scene = generate(&LoadOptions { instances: Some(10), ..Default::default() }).unwrap();
        crate::scene::validate::validate_contents(&scene).unwrap();
        let animation = scene.animation.as_ref().unwrap();
        assert_eq!(animation.instances().len(), 10);
        assert!(animation.problem(&scene).is_none());
        let (rest, later) = (animation.pose(0, 0.0), animation.pose(0, 0.5));
        for (a, b) in rest.iter().zip(&later) {
            assert_eq!(a.joints.len(), 3);
            assert!(b.joints.iter().all(|m| m.is_finite()));
            assert!(a.joints[2] != b.joints[2], "stalk {} does not sway", a.instance);
            assert_eq!(a.transform, scene.instances[a.instance as usize].transform);
        }
        // A world keeps the animation; its live scene, whose indices it compacts, does not.
        let (world, _) = crate::scene::world::World::new(scene).unwrap();
        assert!(world.scene().animation.is_some() && world.live_scene().animation.is_none());
    }
}
