//! Per-vertex deformation of a mesh: skin influences (linear blend skinning) and morph targets,
//! with the CPU reference of what the GPU computes and the exact bounds of a deformed pose.

use super::bounds::Aabb;
use super::error::SceneError;
use super::mesh::{decode_octahedral, MeshData, Vertex};
use glam::{Mat4, Vec3, Vec4};

/// One morph target (blend shape): per-vertex offsets added to the rest shape times the
/// target's weight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    /// Position offsets, one per vertex.
    pub positions: Vec<Vec3>,
    /// Normal offsets, one per vertex; empty when the target leaves normals alone.
    pub normals: Vec<Vec3>,
}

/// How a mesh deforms: its skin influences and its morph targets, checked (see
/// [`MeshData::validate`]). A mesh without deformation has none ([`super::Mesh::deform`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshDeform {
    /// Four joint indices per vertex (empty: the mesh is not skinned). An influence of weight 0
    /// names joint 0.
    pub joints: Vec<[u16; 4]>,
    /// The weights of the four joints per vertex, each at least 0, summing to 1.
    pub weights: Vec<Vec4>,
    /// Morph targets, applied before skinning.
    pub morph_targets: Vec<MorphTarget>,
    /// Joint matrices a pose must give: the largest joint index with a weight above 0, plus 1
    /// (0 for a mesh that is not skinned).
    pub joint_count: u32,
    /// Morph weights when nothing sets them (glTF mesh `weights`), one per target.
    pub default_weights: Vec<f32>,
}

impl MeshDeform {
    /// Whether the mesh has skin influences.
    pub fn is_skinned(&self) -> bool {
        !self.joints.is_empty()
    }

    /// The deformed positions and unit normals of the rest shape `positions` and `normals` (one
    /// per vertex): morph targets first (offsets times `morph_weights`; weights past the end of
    /// `morph_weights` are 0), then linear blend skinning with `joint_matrices` (ignored for a
    /// mesh that is not skinned). Normals go through the same blended matrices and are
    /// renormalised.
    ///
    /// Refuses (never panics): rest arrays of another length than the influences or targets,
    /// fewer joint matrices than [`MeshDeform::joint_count`], more weights than targets, and
    /// non-finite matrices or weights.
    pub fn deform(
        &self,
        positions: &[Vec3],
        normals: &[Vec3],
        joint_matrices: &[Mat4],
        morph_weights: &[f32],
    ) -> Result<(Vec<Vec3>, Vec<Vec3>), SceneError> {
        self.check_pose(positions.len(), normals.len(), joint_matrices, morph_weights)?;
        let mut p = positions.to_vec();
        let mut n = normals.to_vec();
        for (target, &w) in self.morph_targets.iter().zip(morph_weights).filter(|(_, &w)| w != 0.0) {
            for (p, d) in p.iter_mut().zip(&target.positions) {
                *p += *d * w;
            }
            for (n, d) in n.iter_mut().zip(&target.normals) {
                *n += *d * w;
            }
        }
        if self.is_skinned() {
            for (i, p) in p.iter_mut().enumerate() {
                *p = self.skin_matrix(i, joint_matrices).transform_point3(*p);
            }
            for (i, n) in n.iter_mut().enumerate() {
                *n = self.skin_matrix(i, joint_matrices).transform_vector3(*n);
            }
        }
        for n in &mut n {
            *n = n.try_normalize().unwrap_or(Vec3::Y);
        }
        Ok((p, n))
    }

    /// [`MeshDeform::deform`] of pool vertices (their positions and decoded normals).
    pub fn deform_vertices(
        &self,
        rest: &[Vertex],
        joint_matrices: &[Mat4],
        morph_weights: &[f32],
    ) -> Result<(Vec<Vec3>, Vec<Vec3>), SceneError> {
        let positions: Vec<Vec3> = rest.iter().map(|v| Vec3::from_array(v.position)).collect();
        let normals: Vec<Vec3> = rest.iter().map(|v| decode_octahedral(v.normal)).collect();
        self.deform(&positions, &normals, joint_matrices, morph_weights)
    }

    /// The exact axis-aligned bounds of the deformed `positions` (see [`MeshDeform::deform`]).
    pub fn bounds(
        &self,
        positions: &[Vec3],
        joint_matrices: &[Mat4],
        morph_weights: &[f32],
    ) -> Result<Aabb, SceneError> {
        let (p, _) = self.deform(positions, &[], joint_matrices, morph_weights)?;
        Aabb::from_points(p).ok_or_else(|| SceneError::invalid("mesh deformation", "the mesh has no vertices"))
    }

    /// What is wrong with this deformation for a mesh of `vertices` vertices, if anything:
    /// influence or offset counts that differ from it, or joints past [`MeshDeform::joint_count`].
    pub fn problem(&self, vertices: usize) -> Option<String> {
        if self.is_skinned() && (self.joints.len() != vertices || self.weights.len() != vertices) {
            return Some(format!(
                "{} joints and {} weights for {vertices} vertices",
                self.joints.len(),
                self.weights.len()
            ));
        }
        if let Some(t) = self
            .morph_targets
            .iter()
            .position(|t| t.positions.len() != vertices || !(t.normals.is_empty() || t.normals.len() == vertices))
        {
            return Some(format!("morph target {t} does not have one offset per vertex ({vertices})"));
        }
        let past = self.joints.iter().flatten().any(|&j| j as u32 >= self.joint_count.max(1));
        past.then(|| format!("a joint index is at or past the joint count {}", self.joint_count))
    }

    /// The blended matrix of vertex `i` (its joints checked against `joint_matrices` before).
    fn skin_matrix(&self, i: usize, joint_matrices: &[Mat4]) -> Mat4 {
        let (j, w) = (self.joints[i], self.weights[i]);
        let mut m = Mat4::ZERO;
        for k in 0..4 {
            if w[k] > 0.0 {
                m += joint_matrices[j[k] as usize] * w[k];
            }
        }
        m
    }

    fn check_pose(
        &self,
        positions: usize,
        normals: usize,
        joint_matrices: &[Mat4],
        morph_weights: &[f32],
    ) -> Result<(), SceneError> {
        let err = |m: String| Err(SceneError::invalid("mesh deformation", m));
        let vertices = if self.is_skinned() {
            self.joints.len()
        } else {
            self.morph_targets.first().map_or(positions, |t| t.positions.len())
        };
        if positions != vertices || (normals != 0 && normals != vertices) {
            return err(format!("{positions} positions and {normals} normals for a mesh of {vertices} vertices"));
        }
        if self.is_skinned() && joint_matrices.len() < self.joint_count as usize {
            return err(format!("{} joint matrices for a skin of {} joints", joint_matrices.len(), self.joint_count));
        }
        if let Some(j) = joint_matrices.iter().position(|m| !m.is_finite()) {
            return err(format!("joint matrix {j} is not finite"));
        }
        if morph_weights.len() > self.morph_targets.len() {
            return err(format!("{} morph weights for {} targets", morph_weights.len(), self.morph_targets.len()));
        }
        if let Some(k) = morph_weights.iter().position(|w| !w.is_finite()) {
            return err(format!("morph weight {k} is not finite"));
        }
        Ok(())
    }
}

impl MeshData {
    /// Checks the deformation attributes of the mesh and returns them normalised (`None` when
    /// the mesh has neither skin influences nor morph targets). `n` is the vertex count.
    pub(crate) fn validate_deform(&self, place: &str) -> Result<Option<MeshDeform>, SceneError> {
        let err = |m: String| Err(SceneError::invalid(place, m));
        let n = self.positions.len();
        if self.joints.is_empty() && self.weights.is_empty() && self.morph_targets.is_empty() {
            if !self.morph_weights.is_empty() {
                return err(format!("{} morph weights for a mesh without morph targets", self.morph_weights.len()));
            }
            return Ok(None);
        }
        if self.joints.len() != self.weights.len() || (!self.joints.is_empty() && self.joints.len() != n) {
            return err(format!("{} joints and {} weights for {n} positions", self.joints.len(), self.weights.len()));
        }
        let mut joints = self.joints.clone();
        let mut weights = self.weights.clone();
        let mut joint_count = 0u32;
        for (i, (j, w)) in joints.iter_mut().zip(weights.iter_mut()).enumerate() {
            let sum = w.x + w.y + w.z + w.w;
            let sound = w.is_finite() && w.min_element() >= 0.0 && sum > 0.0 && sum.is_finite();
            if !sound {
                return err(format!("vertex {i} has weights {w}: they must be finite, at least 0 and not all 0"));
            }
            *w /= sum;
            for k in 0..4 {
                if w[k] > 0.0 {
                    joint_count = joint_count.max(j[k] as u32 + 1);
                } else {
                    j[k] = 0;
                }
            }
        }
        for (t, target) in self.morph_targets.iter().enumerate() {
            let normals = target.normals.len();
            if target.positions.len() != n || (normals != 0 && normals != n) {
                return err(format!(
                    "morph target {t} has {} position and {normals} normal offsets for {n} positions",
                    target.positions.len()
                ));
            }
            if let Some(i) = target.positions.iter().chain(&target.normals).position(|d| !d.is_finite()) {
                return err(format!("morph target {t} has a non-finite offset at element {i}"));
            }
        }
        if self.morph_weights.len() > self.morph_targets.len() {
            return err(format!("{} morph weights for {} targets", self.morph_weights.len(), self.morph_targets.len()));
        }
        if let Some(k) = self.morph_weights.iter().position(|w| !w.is_finite()) {
            return err(format!("morph weight {k} is not finite"));
        }
        let mut default_weights = self.morph_weights.clone();
        default_weights.resize(self.morph_targets.len(), 0.0);
        Ok(Some(MeshDeform {
            joints,
            weights,
            morph_targets: self.morph_targets.clone(),
            joint_count,
            default_weights,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// A strip of two quads along +x (x = 0, 1, 2), vertices at x = 0 and 1 bound to joint 0,
    /// at x = 2 to joint 1.
    fn strip() -> MeshData {
        let positions: Vec<Vec3> =
            (0..3).flat_map(|x| [Vec3::new(x as f32, 0.0, 0.0), Vec3::new(x as f32, 1.0, 0.0)]).collect();
        MeshData {
            indices: vec![0, 2, 1, 1, 2, 3, 2, 4, 3, 3, 4, 5],
            joints: vec![[0, 1, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0], [1, 0, 0, 0], [1, 0, 0, 0]],
            weights: vec![Vec4::new(2.0, 0.0, 0.0, 0.0); 4].into_iter().chain([Vec4::X * 0.5; 2]).collect(),
            morph_targets: vec![MorphTarget { positions: vec![Vec3::Z; 6], normals: vec![] }],
            positions,
            ..Default::default()
        }
    }

    #[test]
    fn validation_normalises_weights_and_counts_joints() {
        let (_, _, _, deform) = strip().validate("m").unwrap();
        let d = deform.unwrap();
        assert_eq!(d.weights[0], Vec4::X);
        assert_eq!(d.weights[5], Vec4::X);
        // The zero-weight influence of joint 1 does not count.
        assert_eq!(d.joints[0], [0, 0, 0, 0]);
        assert_eq!(d.joint_count, 2);
        assert_eq!(d.default_weights, vec![0.0]);
    }

    #[test]
    fn refuses_bad_deformations_naming_the_place() {
        let bad = |m: MeshData| m.validate("mesh 'm'").unwrap_err().to_string();
        let e = bad(MeshData { weights: vec![Vec4::ZERO; 6], ..strip() });
        assert!(e.starts_with("mesh 'm': vertex 0 has weights"), "{e}");
        let e = bad(MeshData { weights: vec![Vec4::new(1.0, -0.5, 0.0, 0.0); 6], ..strip() });
        assert!(e.contains("at least 0"), "{e}");
        let e = bad(MeshData { joints: vec![[0; 4]; 5], ..strip() });
        assert!(e.contains("5 joints and 6 weights"), "{e}");
        let mut nan = strip();
        nan.morph_targets[0].positions[3] = Vec3::NAN;
        assert!(bad(nan).contains("morph target 0 has a non-finite offset at element 3"));
        let e = bad(MeshData { morph_weights: vec![0.5, 0.5], ..strip() });
        assert!(e.contains("2 morph weights for 1 targets"), "{e}");
    }

    #[test]
    fn morphs_then_skins() {
        let (vertices, _, _, deform) = strip().validate("m").unwrap();
        let d = deform.unwrap();
        // Joint 1 turns a quarter about +z around (2, 0, 0): the far end folds up.
        let pivot = Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0));
        let turn = pivot * Mat4::from_quat(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2)) * pivot.inverse();
        let (p, n) = d.deform_vertices(&vertices, &[Mat4::IDENTITY, turn], &[1.0]).unwrap();
        let close = |a: Vec3, b: Vec3| a.distance(b) < 1e-5;
        assert!(close(p[0], Vec3::new(0.0, 0.0, 1.0)), "{}", p[0]);
        assert!(close(p[4], Vec3::new(1.0, 1.0, 1.0)), "{}", p[4]);
        assert!(close(p[5], Vec3::new(0.0, 1.0, 1.0)), "{}", p[5]);
        assert!(n.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
        let b = d
            .bounds(
                &vertices.iter().map(|v| Vec3::from(v.position)).collect::<Vec<_>>(),
                &[Mat4::IDENTITY, turn],
                &[1.0],
            )
            .unwrap();
        assert!(p.iter().all(|p| p.cmpge(b.min).all() && p.cmple(b.max).all()));
        assert_eq!(b.min.z, 1.0);
    }

    #[test]
    fn refuses_bad_poses() {
        let (vertices, _, _, deform) = strip().validate("m").unwrap();
        let d = deform.unwrap();
        assert!(d
            .deform_vertices(&vertices, &[Mat4::IDENTITY], &[])
            .unwrap_err()
            .to_string()
            .contains("1 joint matrices"));
        assert!(d.deform_vertices(&vertices[..3], &[Mat4::IDENTITY; 2], &[]).is_err());
        assert!(d.deform_vertices(&vertices, &[Mat4::IDENTITY; 2], &[0.0, 1.0]).is_err());
        assert!(d.deform_vertices(&vertices, &[Mat4::IDENTITY, Mat4::NAN], &[]).is_err());
    }
}
