//! The pose of every animated instance at a time of a clip.

use super::clip::Property;
use super::rig::{dmat4, invertible};
use super::SceneAnimation;
use crate::scene::Transform;
use glam::{Mat4, Quat, Vec3};

/// Where an animated instance is and how its mesh deforms at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct InstancePose {
    /// The instance's index in [`crate::scene::Scene::instances`].
    pub instance: u32,
    /// Its world transform: the world transform of the node that places it, as the glTF
    /// import places instances.
    pub transform: Transform,
    /// Joint matrices, one per joint of its skin (empty when it is not skinned):
    /// `inverse(mesh node world) * joint world * inverse bind`. They take the mesh's
    /// bind-space vertices into the instance's local space, so that `transform * joints[j] * v`
    /// is glTF's skinned world position `joint world * inverse bind * v`. glTF ignores the
    /// skinned node's own transform; the first factor cancels it, as `transform` applies it.
    pub joints: Vec<Mat4>,
    /// Morph weights, one per morph target of its mesh (empty when it is not morphed): the
    /// clip's weights channel on its node, else the node's `weights`, else its mesh's.
    pub morph_weights: Vec<f32>,
}

/// A node's local transform during a pose: its rest, with the keyed properties replaced.
#[derive(Clone)]
struct Local {
    transform: Transform,
    keyed: bool,
    trs: super::Trs,
    weights: Vec<f32>,
}

impl SceneAnimation {
    /// The pose of every animated instance at `time_s` seconds into clip `clip`; the time wraps
    /// over the clip's duration (so the clip's end shows its start). A clip index past the end
    /// of [`SceneAnimation::clips`] or a non-finite time gives the rest pose.
    ///
    /// A skinned instance whose node's world transform cannot be inverted (a scale of 0) gets
    /// the node's translation alone as its transform, and joint matrices relative to that.
    pub fn pose(&self, clip: usize, time_s: f64) -> Vec<InstancePose> {
        let mut locals: Vec<Local> = self
            .nodes
            .iter()
            .map(|n| Local {
                transform: n.rest,
                keyed: false,
                trs: n.rest_trs.unwrap_or_default(),
                weights: n.weights.clone(),
            })
            .collect();
        if let Some(clip) = self.clips.get(clip) {
            let t = if time_s.is_finite() && clip.duration > 0.0 { time_s.rem_euclid(clip.duration) } else { 0.0 };
            let mut value = Vec::new();
            for channel in &clip.channels {
                let Some(local) = locals.get_mut(channel.node as usize) else { continue };
                value.clear();
                value.resize(channel.width as usize, 0.0);
                channel.sample(t, &mut value);
                let v3 = || Vec3::new(value[0], value[1], value[2]);
                match channel.property {
                    Property::Translation if value.len() == 3 => local.trs.translation = v3(),
                    Property::Scale if value.len() == 3 => local.trs.scale = v3(),
                    Property::Rotation if value.len() == 4 => {
                        local.trs.rotation = Quat::from_xyzw(value[0], value[1], value[2], value[3]).normalize()
                    }
                    Property::Weights => {
                        local.weights.clone_from(&value);
                        continue;
                    }
                    _ => continue,
                }
                local.keyed = true;
            }
        }
        let mut worlds: Vec<Transform> = Vec::with_capacity(locals.len());
        for (node, local) in self.nodes.iter().zip(&locals) {
            let transform = if local.keyed { local.trs.transform() } else { local.transform };
            let parent = node.parent.and_then(|p| worlds.get(p as usize)).unwrap_or(&self.placement);
            worlds.push(parent.then(&transform));
        }
        self.instances
            .iter()
            .map(|inst| {
                let node = inst.node as usize;
                let mut transform = worlds.get(node).copied().unwrap_or(self.placement);
                let skin = inst.skin.and_then(|s| self.skins.get(s as usize));
                let joints = match skin {
                    None => Vec::new(),
                    Some(skin) => {
                        if !invertible(&transform) {
                            transform = Transform { linear: glam::Mat3::IDENTITY, ..transform };
                        }
                        let to_local = dmat4(&transform).inverse();
                        skin.joints
                            .iter()
                            .zip(&skin.inverse_bind)
                            .map(|(&j, ibm)| {
                                let joint = worlds.get(j as usize).map_or(glam::DMat4::IDENTITY, dmat4);
                                (to_local * joint * ibm.as_dmat4()).as_mat4()
                            })
                            .collect()
                    }
                };
                let mut morph_weights = locals.get(node).map(|l| l.weights.clone()).unwrap_or_default();
                morph_weights.resize(inst.morph_targets as usize, 0.0);
                InstancePose { instance: inst.instance, transform, joints, morph_weights }
            })
            .collect()
    }

    /// The pose with no clip playing: every node at rest.
    pub fn rest_pose(&self) -> Vec<InstancePose> {
        self.pose(usize::MAX, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{AnimatedInstance, Channel, Clip, Interpolation, RigNode, Skin, Trs};
    use super::*;
    use glam::DVec3;

    /// A root moved by 10 on x with two joints below it (the second 1 along x from the first,
    /// turned by the clip), and a skinned mesh node placed away from them.
    fn arm() -> SceneAnimation {
        let node = |parent: Option<u32>, translation: Vec3| {
            let trs = Trs { translation, ..Default::default() };
            RigNode { source: 0, parent, rest: trs.transform(), rest_trs: Some(trs), weights: vec![0.25] }
        };
        let nodes = vec![
            node(None, Vec3::new(10.0, 0.0, 0.0)),
            node(Some(0), Vec3::ZERO),
            node(Some(1), Vec3::X),
            node(None, Vec3::new(0.0, 5.0, 0.0)),
        ];
        let skin = Skin {
            name: "arm".into(),
            joints: vec![1, 2],
            inverse_bind: vec![Mat4::IDENTITY, Mat4::from_translation(-Vec3::X)],
        };
        let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let turn = Channel {
            node: 2,
            property: Property::Rotation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: [Quat::IDENTITY.to_array(), quarter.to_array()].concat(),
            width: 4,
        };
        let weights = Channel {
            node: 3,
            property: Property::Weights,
            interpolation: Interpolation::Step,
            times: vec![0.0, 0.5],
            values: vec![0.0, 1.0],
            width: 1,
        };
        let clip = Clip { name: "wave".into(), duration: 1.0, channels: vec![turn, weights] };
        let instance = AnimatedInstance { instance: 7, node: 3, skin: Some(0), morph_targets: 1 };
        SceneAnimation::new(nodes, vec![skin], vec![clip], vec![instance])
    }

    #[test]
    fn skinned_positions_ignore_the_mesh_node() {
        let anim = arm();
        let pose = &anim.pose(0, 2.5)[0]; // wraps to 0.5: an eighth turn
        assert_eq!(pose.instance, 7);
        assert_eq!(pose.transform.translation, DVec3::new(0.0, 5.0, 0.0));
        assert_eq!(pose.morph_weights, vec![1.0]);
        // The tip of the arm in bind space, (2, 0, 0), bound to joint 1: it turns about the
        // second joint at world (11, 0, 0).
        let tip = pose.transform.apply(pose.joints[1].transform_point3(Vec3::new(2.0, 0.0, 0.0)));
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(tip.distance(DVec3::new(11.0 + h, h, 0.0)) < 1e-5, "{tip}");
        let rest = &anim.rest_pose()[0];
        assert_eq!(rest.morph_weights, vec![0.25]);
        let tip = rest.transform.apply(rest.joints[1].transform_point3(Vec3::new(2.0, 0.0, 0.0)));
        assert!(tip.distance(DVec3::new(12.0, 0.0, 0.0)) < 1e-5, "{tip}");
    }

    #[test]
    fn a_collapsed_mesh_node_keeps_skinned_positions() {
        let mut anim = arm();
        anim.nodes[3].rest.linear = glam::Mat3::ZERO;
        anim.nodes[3].rest_trs = None;
        let pose = &anim.pose(0, 0.0)[0];
        assert_eq!(pose.transform.linear, glam::Mat3::IDENTITY);
        let tip = pose.transform.apply(pose.joints[1].transform_point3(Vec3::new(2.0, 0.0, 0.0)));
        assert!(tip.distance(DVec3::new(12.0, 0.0, 0.0)) < 1e-5, "{tip}");
        assert!(pose.joints.iter().all(|m| m.is_finite()));
    }
}
