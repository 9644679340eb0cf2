//! Posed instances of a world: each posed instance draws its own copy of its mesh, which the
//! renderer deforms on the GPU from the shared rest mesh, and whose bounds follow the pose.
//!
//! The bound of a pose is derived from per-joint boxes, not from the deformed vertices, so that
//! it costs a few matrix products per joint instead of a pass over the mesh. For each joint,
//! the box of the rest positions it influences, and per morph target the range of its offsets
//! over those vertices, are made once per mesh ([`JointBoxes::new`]). A vertex's morphed
//! position then lies in each of its joints' boxes widened by the weighted offset ranges, so
//! each term `M_j v` of its skinned position `sum_j w_j M_j v` lies in the joint's transformed
//! box. The weights are at least 0 and sum to one, so the position lies in the convex hull of
//! those boxes: the box around every joint's transformed corners contains the deformed mesh. A
//! margin covers the GPU's rounding, so the bound stays conservative for culling.

use super::bounds::{Aabb, Sphere};
use super::deform::MeshDeform;
use super::mesh::Vertex;
use glam::{Mat4, Vec3};

/// A posed instance ([`super::world::World::set_pose`]): the mesh it was given (its source),
/// the copy of it that it draws, and its pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// The deformable mesh the instance was given.
    pub source: u32,
    /// The instance's own copy of it, which the renderer deforms.
    pub mesh: u32,
    /// Joint matrices (bind space to the instance's local space), one per joint of the source.
    pub joints: Vec<Mat4>,
    /// Morph weights (missing ones 0).
    pub morph_weights: Vec<f32>,
}

/// Per joint of a deformable mesh, the box of the rest positions it influences and the range of
/// each morph target's offsets over them (a mesh that is only morphed is one "joint").
#[derive(Clone, Debug, PartialEq)]
pub struct JointBoxes {
    joints: Vec<Option<JointBox>>,
}

#[derive(Clone, Debug, PartialEq)]
struct JointBox {
    rest: Aabb,
    /// Per morph target, the least and greatest offset over the joint's vertices.
    offsets: Vec<(Vec3, Vec3)>,
}

/// The relative margin added to a pose's bound for the GPU's rounding (its products and sums
/// of a few terms round far below this).
const ROUNDING_MARGIN: f32 = 1.0e-5;

impl JointBoxes {
    /// The boxes of `deform` over the rest vertices `rest` (checked against each other before).
    pub fn new(deform: &MeshDeform, rest: &[Vertex]) -> Self {
        let joint_count = if deform.is_skinned() { deform.joint_count.max(1) as usize } else { 1 };
        let targets = deform.morph_targets.len();
        let mut joints: Vec<Option<JointBox>> = vec![None; joint_count];
        for (i, v) in rest.iter().enumerate() {
            let p = Vec3::from_array(v.position);
            let influences: Vec<usize> = if deform.is_skinned() {
                (0..4).filter(|&k| deform.weights[i][k] > 0.0).map(|k| deform.joints[i][k] as usize).collect()
            } else {
                vec![0]
            };
            for j in influences.into_iter().filter(|&j| j < joint_count) {
                let b = joints[j].get_or_insert_with(|| JointBox {
                    rest: Aabb { min: p, max: p },
                    offsets: vec![(Vec3::ZERO, Vec3::ZERO); targets],
                });
                b.rest.min = b.rest.min.min(p);
                b.rest.max = b.rest.max.max(p);
                for (t, range) in b.offsets.iter_mut().enumerate() {
                    let d = deform.morph_targets[t].positions[i];
                    range.0 = range.0.min(d);
                    range.1 = range.1.max(d);
                }
            }
        }
        Self { joints }
    }

    /// A box that contains the mesh deformed by `joint_matrices` (taking bind-space positions
    /// into the instance's local space; ignored for a mesh that is only morphed) and
    /// `morph_weights` (missing ones 0), with the margin for rounding.
    pub fn bound(&self, joint_matrices: &[Mat4], morph_weights: &[f32]) -> (Aabb, Sphere) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (j, joint) in self.joints.iter().enumerate() {
            let Some(joint) = joint else { continue };
            let (mut min, mut max) = (joint.rest.min, joint.rest.max);
            for (&(dmin, dmax), &w) in joint.offsets.iter().zip(morph_weights) {
                let (a, b) = (dmin * w, dmax * w);
                min += a.min(b);
                max += a.max(b);
            }
            let m = if self.joints.len() == 1 && joint_matrices.is_empty() {
                Mat4::IDENTITY
            } else {
                joint_matrices.get(j).copied().unwrap_or(Mat4::IDENTITY)
            };
            for corner in 0..8 {
                let c = Vec3::new(
                    if corner & 1 == 0 { min.x } else { max.x },
                    if corner & 2 == 0 { min.y } else { max.y },
                    if corner & 4 == 0 { min.z } else { max.z },
                );
                let p = m.transform_point3(c);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if !lo.is_finite() || !hi.is_finite() {
            (lo, hi) = (Vec3::ZERO, Vec3::ZERO);
        }
        let center = (lo + hi) * 0.5;
        let margin = ROUNDING_MARGIN * (center.abs().max_element() + (hi - lo).max_element()) + f32::MIN_POSITIVE;
        let bounds = Aabb { min: lo - Vec3::splat(margin), max: hi + Vec3::splat(margin) };
        let sphere = Sphere { center: bounds.center(), radius: bounds.half_extent().length() };
        (bounds, sphere)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::deform::MorphTarget;
    use crate::scene::MeshData;
    use glam::{Quat, Vec4};

    /// A bar along x from 0 to 2 on joints 0 (x < 1) and 1 (x > 1), blended in the middle.
    fn bar() -> (MeshData, Vec<Vertex>, MeshDeform) {
        let mut m = MeshData::default();
        for i in 0..5 {
            let x = i as f32 * 0.5;
            for (y, z) in [(0.0, 0.0), (0.2, 0.0), (0.0, 0.2)] {
                m.positions.push(Vec3::new(x, y, z));
                let w1 = (x - 0.5).clamp(0.0, 1.0);
                m.joints.push([0, 1, 0, 0]);
                m.weights.push(Vec4::new(1.0 - w1, w1, 0.0, 0.0));
            }
        }
        for i in 0..4u32 {
            let b = i * 3;
            m.indices.extend([b, b + 3, b + 1, b, b + 2, b + 3]);
        }
        let n = m.positions.len();
        m.morph_targets = vec![MorphTarget {
            positions: (0..n).map(|i| Vec3::new(0.0, (i % 3) as f32 * 0.3, -0.1)).collect(),
            normals: vec![],
        }];
        let (vertices, _, _, deform) = m.validate("bar").unwrap();
        (m, vertices, deform.unwrap())
    }

    #[test]
    fn a_pose_bound_contains_every_deformed_vertex() {
        let (_, rest, deform) = bar();
        let boxes = JointBoxes::new(&deform, &rest);
        let poses = [
            (vec![Mat4::IDENTITY, Mat4::IDENTITY], vec![0.0]),
            (
                vec![
                    Mat4::from_rotation_z(0.3),
                    Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0))
                        * Mat4::from_quat(Quat::from_rotation_z(1.2))
                        * Mat4::from_translation(Vec3::new(-1.0, 0.0, 0.0)),
                ],
                vec![0.7],
            ),
            (vec![Mat4::from_scale(Vec3::new(3.0, 0.1, 2.0)), Mat4::from_rotation_y(2.5)], vec![-1.5]),
        ];
        for (joints, weights) in poses {
            let (bounds, sphere) = boxes.bound(&joints, &weights);
            let (positions, _) = deform.deform_vertices(&rest, &joints, &weights).unwrap();
            for p in positions {
                assert!(p.cmpge(bounds.min).all() && p.cmple(bounds.max).all(), "{p} outside {bounds:?}");
                assert!(p.distance(sphere.center) <= sphere.radius, "{p} outside the sphere");
            }
            // Not much larger than the exact box either.
            let exact = deform
                .bounds(&rest.iter().map(|v| Vec3::from_array(v.position)).collect::<Vec<_>>(), &joints, &weights)
                .unwrap();
            assert!((bounds.max - bounds.min).max_element() <= 2.0 * (exact.max - exact.min).max_element() + 1.0);
        }
    }
}
