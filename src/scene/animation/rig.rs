//! The nodes, skins and instances an animation moves.

use crate::scene::Transform;
use glam::{DMat3, DQuat, Mat4, Quat, Vec3};

/// A node's local transform as translation, rotation and scale (what glTF animates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: Vec3,
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Scale along the rotated axes.
    pub scale: Vec3,
}

impl Default for Trs {
    fn default() -> Self {
        Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE }
    }
}

impl Trs {
    /// The transform `translation * rotation * scale`, composed in double precision as the
    /// glTF import composes node transforms.
    pub fn transform(&self) -> Transform {
        let q = self.rotation.as_dquat();
        let q = if q.length_squared() > 0.0 { q.normalize() } else { DQuat::IDENTITY };
        let linear = DMat3::from_quat(q) * DMat3::from_diagonal(self.scale.as_dvec3());
        Transform { linear: linear.as_mat3(), translation: self.translation.as_dvec3() }
    }
}

/// A node of the animated hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct RigNode {
    /// The glTF node it comes from (its index in the file).
    pub source: u32,
    /// Its parent among [`super::SceneAnimation::nodes`] (always an earlier one), `None` for a
    /// root of the scene.
    pub parent: Option<u32>,
    /// Its local transform at rest.
    pub rest: Transform,
    /// The same as translation, rotation and scale; `None` for a node given by a matrix,
    /// which no channel animates.
    pub rest_trs: Option<Trs>,
    /// Its morph weights at rest (the node's `weights`, else its mesh's; empty without morph
    /// targets).
    pub weights: Vec<f32>,
}

/// A skin: the nodes that are its joints and their inverse bind matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Name for messages (glTF skin name, or `skin #i`).
    pub name: String,
    /// Its joints, as indices into [`super::SceneAnimation::nodes`].
    pub joints: Vec<u32>,
    /// One per joint: from the mesh's bind space into the joint's space.
    pub inverse_bind: Vec<Mat4>,
}

/// An instance of the scene that an animation moves, skins or morphs.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimatedInstance {
    /// Its index in [`crate::scene::Scene::instances`].
    pub instance: u32,
    /// The node that places it, an index into [`super::SceneAnimation::nodes`].
    pub node: u32,
    /// Its skin, an index into [`super::SceneAnimation::skins`] (`None`: not skinned).
    pub skin: Option<u32>,
    /// The number of morph weights its mesh takes (0: not morphed).
    pub morph_targets: u32,
}

/// `transform` as a 4x4 matrix in double precision.
pub(crate) fn dmat4(t: &Transform) -> glam::DMat4 {
    let l = t.linear.as_dmat3();
    glam::DMat4::from_cols(l.x_axis.extend(0.0), l.y_axis.extend(0.0), l.z_axis.extend(0.0), t.translation.extend(1.0))
}

/// Whether `t` can be inverted with some precision left.
pub(crate) fn invertible(t: &Transform) -> bool {
    let d = t.linear.as_dmat3().determinant();
    d.is_finite() && d.abs() > 1e-18 && t.translation.is_finite()
}
