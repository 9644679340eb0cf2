//! Playback of a scene's animations (glTF skins, morph weights and node animations): the part
//! of the node hierarchy that moves something drawn ([`rig`]), the clips ([`clip`]) and the
//! pose of every animated instance at a time ([`pose`]).

pub mod clip;
pub mod pose;
pub mod rig;

pub use clip::{Channel, Clip, Interpolation, Property};
pub use pose::InstancePose;
pub use rig::{AnimatedInstance, RigNode, Skin, Trs};

use super::Transform;

/// What a scene needs to play its animations: the nodes that move drawn instances (parents
/// before children), the skins, the clips and the instances they animate.
///
/// Built by the glTF import, which checks every index; a pose of it never panics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneAnimation {
    nodes: Vec<RigNode>,
    skins: Vec<Skin>,
    clips: Vec<Clip>,
    instances: Vec<AnimatedInstance>,
    placement: Transform,
}

impl SceneAnimation {
    /// Assembles an animation from parts the caller checked: every parent of a node comes
    /// before it, every node, skin and joint index is in range, every channel's values match
    /// its key count (see [`Channel`]).
    pub(crate) fn new(
        nodes: Vec<RigNode>,
        skins: Vec<Skin>,
        clips: Vec<Clip>,
        instances: Vec<AnimatedInstance>,
    ) -> Self {
        Self { nodes, skins, clips, instances, placement: Transform::default() }
    }

    /// The nodes that move drawn instances, parents before children.
    pub fn nodes(&self) -> &[RigNode] {
        &self.nodes
    }

    /// The skins of the animated instances.
    pub fn skins(&self) -> &[Skin] {
        &self.skins
    }

    /// The clips (glTF animations), in file order.
    pub fn clips(&self) -> &[Clip] {
        &self.clips
    }

    /// The index of the first clip named `name`.
    pub fn clip_index(&self, name: &str) -> Option<usize> {
        self.clips.iter().position(|c| c.name == name)
    }

    /// The instances the animation moves, skins or morphs, in instance order.
    pub fn instances(&self) -> &[AnimatedInstance] {
        &self.instances
    }

    /// The transform every pose is placed by (identity as imported; [`super::Scene::translate`]
    /// moves it with the instances).
    pub fn placement(&self) -> Transform {
        self.placement
    }

    /// What is wrong with this animation for `scene`, if anything: an animated instance the
    /// scene does not have, or a skin with fewer joints than its instance's mesh uses.
    pub fn problem(&self, scene: &super::Scene) -> Option<String> {
        for a in &self.instances {
            let Some(instance) = scene.instances.get(a.instance as usize) else {
                return Some(format!(
                    "animated instance {} does not exist ({} instances)",
                    a.instance,
                    scene.instances.len()
                ));
            };
            let deform = scene.meshes.get(instance.mesh as usize).and_then(|m| m.deform.as_deref());
            let used = deform.map_or(0, |d| d.joint_count as usize);
            let joints = a.skin.and_then(|s| self.skins.get(s as usize)).map_or(0, |s| s.joints.len());
            if a.skin.is_some() && joints < used {
                return Some(format!("instance {}: its skin has {joints} joints, its mesh uses {used}", a.instance));
            }
        }
        None
    }

    /// Sets the transform every pose is placed by (its root nodes' parent).
    pub fn set_placement(&mut self, placement: Transform) {
        self.placement = placement;
    }
}
