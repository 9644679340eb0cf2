//! glTF animations and skins to a [`SceneAnimation`]: the channels of every animation, checked,
//! and the part of the hierarchy that moves drawn instances (the nodes that place them, their
//! skins' joints, and the ancestors of both).

use super::accessor;
use super::nodes::{node_label, Placed};
use crate::scene::animation::{AnimatedInstance, Channel, Clip, Interpolation, Property, RigNode, SceneAnimation, Trs};
use crate::scene::error::SceneError;
use glam::{Quat, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::Property as GltfProperty;
use gltf::scene::Transform as NodeTransform;

/// A drawn instance that may be animated: its index, its node, whether its node's skin deforms
/// it, and how many morph targets its mesh has.
pub(super) struct Candidate {
    pub instance: u32,
    pub node: usize,
    pub skinned: bool,
    pub targets: usize,
}

/// A channel as read, on a glTF node.
struct Read {
    node: usize,
    channel: Channel,
}

/// Builds the scene's animation from `placed` (the drawn nodes, parents first) and the drawn
/// `candidates`; `None` when nothing drawn moves, skins or morphs.
pub(super) fn build(
    document: &gltf::Document,
    placed: &[Placed<'_>],
    candidates: &[Candidate],
    buffers: &[Vec<u8>],
    file: &str,
    notes: &mut Vec<String>,
) -> Result<Option<SceneAnimation>, SceneError> {
    let count = document.nodes().len();
    let mut in_scene = vec![false; count];
    let mut parent = vec![None::<usize>; count];
    for p in placed {
        in_scene[p.node.index()] = true;
        for child in p.node.children() {
            parent[child.index()] = Some(p.node.index());
        }
    }
    let mut clips = Vec::new();
    let mut keyed = vec![false; count];
    for animation in document.animations() {
        let (name, channels) = read_animation(&animation, &in_scene, buffers, file)?;
        for r in &channels {
            keyed[r.node] = true;
        }
        clips.push((name, channels));
    }
    // Whether a node or one of its ancestors is keyed (parents come first in `placed`).
    let mut moved = vec![false; count];
    for p in placed {
        let i = p.node.index();
        moved[i] = keyed[i] || parent[i].is_some_and(|q| moved[q]);
    }
    let animated: Vec<&Candidate> = candidates.iter().filter(|c| c.skinned || c.targets > 0 || moved[c.node]).collect();
    if animated.is_empty() {
        if !clips.is_empty() {
            notes.push(format!("{} animations move nothing that is drawn; they are ignored", clips.len()));
        }
        return Ok(None);
    }

    let mut needed = vec![false; count];
    let mut mark = |mut n: usize| {
        while !needed[n] {
            needed[n] = true;
            match parent[n] {
                Some(p) => n = p,
                None => break,
            }
        }
    };
    let nodes_by_index: Vec<gltf::Node<'_>> = document.nodes().collect();
    for c in &animated {
        mark(c.node);
        if c.skinned {
            if let Some(skin) = nodes_by_index[c.node].skin() {
                for joint in skin.joints().filter(|j| in_scene[j.index()]) {
                    mark(joint.index());
                }
            }
        }
    }

    let mut rig = vec![None::<u32>; count];
    let mut nodes = Vec::new();
    for p in placed.iter().filter(|p| needed[p.node.index()]) {
        rig[p.node.index()] = Some(nodes.len() as u32);
        nodes.push(rig_node(&p.node, parent[p.node.index()].and_then(|q| rig[q])));
    }

    let mut skins = Vec::new();
    let mut skin_index = vec![None::<u32>; document.skins().len()];
    let mut instances = Vec::with_capacity(animated.len());
    for c in &animated {
        let skin = match nodes_by_index[c.node].skin().filter(|_| c.skinned) {
            None => None,
            Some(skin) => Some(match skin_index[skin.index()] {
                Some(s) => s,
                None => {
                    skins.push(super::skin::import(&skin, buffers, |n| rig[n], file)?);
                    let s = skins.len() as u32 - 1;
                    skin_index[skin.index()] = Some(s);
                    s
                }
            }),
        };
        // Marked above, so always in the rig.
        let Some(node) = rig[c.node] else { continue };
        instances.push(AnimatedInstance { instance: c.instance, node, skin, morph_targets: c.targets as u32 });
    }

    let mut dropped = 0usize;
    let clips = clips
        .into_iter()
        .map(|(name, channels)| {
            let duration = channels.iter().map(|r| r.channel.end() as f64).fold(0.0, f64::max);
            let channels = channels
                .into_iter()
                .filter_map(|r| {
                    let kept = rig[r.node].map(|node| Channel { node, ..r.channel });
                    dropped += usize::from(kept.is_none());
                    kept
                })
                .collect();
            Clip { name, duration, channels }
        })
        .collect();
    if dropped > 0 {
        notes.push(format!(
            "{dropped} animation channels move nodes that place nothing drawn (cameras, lights, empty nodes); they are ignored"
        ));
    }
    Ok(Some(SceneAnimation::new(nodes, skins, clips, instances)))
}

/// A drawn node as the animation keeps it.
fn rig_node(node: &gltf::Node<'_>, parent: Option<u32>) -> RigNode {
    let rest_trs = match node.transform() {
        NodeTransform::Decomposed { translation, rotation, scale } => Some(Trs {
            translation: Vec3::from_array(translation),
            rotation: Quat::from_array(rotation).normalize(),
            scale: Vec3::from_array(scale),
        }),
        NodeTransform::Matrix { .. } => None,
    };
    // The walk checked the transform already; notes it gave then are not repeated.
    let rest = super::nodes::local_transform(node, &mut Vec::new()).unwrap_or_default();
    let weights = node.weights().or_else(|| node.mesh().and_then(|m| m.weights())).map(<[f32]>::to_vec);
    RigNode { source: node.index() as u32, parent, rest, rest_trs, weights: weights.unwrap_or_default() }
}

/// `animation 'name' (#i)`, or `animation #i`.
fn animation_label(animation: &gltf::Animation<'_>) -> String {
    match animation.name() {
        Some(name) => format!("animation '{name}' (#{})", animation.index()),
        None => format!("animation #{}", animation.index()),
    }
}

/// The name and the checked channels of `animation`.
fn read_animation(
    animation: &gltf::Animation<'_>,
    in_scene: &[bool],
    buffers: &[Vec<u8>],
    file: &str,
) -> Result<(String, Vec<Read>), SceneError> {
    let label = animation_label(animation);
    let mut channels = Vec::new();
    for (c, channel) in animation.channels().enumerate() {
        let place = format!("{file}: {label} channel {c}");
        let node = channel.target().node();
        if !in_scene[node.index()] {
            return Err(SceneError::invalid(
                place,
                format!("it animates {}, which is not in the drawn scene", node_label(&node)),
            ));
        }
        channels.push(Read { node: node.index(), channel: read_channel(&channel, &node, buffers, &place)? });
    }
    let name = animation.name().map_or_else(|| format!("animation #{}", animation.index()), str::to_string);
    Ok((name, channels))
}

/// One channel's keys and values, checked: increasing finite times, finite values of the count
/// its keys, interpolation and property need.
fn read_channel(
    channel: &gltf::animation::Channel<'_>,
    node: &gltf::Node<'_>,
    buffers: &[Vec<u8>],
    place: &str,
) -> Result<Channel, SceneError> {
    let sampler = channel.sampler();
    let property = match channel.target().property() {
        GltfProperty::Translation => Property::Translation,
        GltfProperty::Rotation => Property::Rotation,
        GltfProperty::Scale => Property::Scale,
        GltfProperty::MorphTargetWeights => Property::Weights,
    };
    if property != Property::Weights && matches!(node.transform(), NodeTransform::Matrix { .. }) {
        return Err(SceneError::invalid(
            place,
            format!("it animates {} of {}, which has a matrix transform (glTF animates only nodes given by translation, rotation and scale)", property_name(property), node_label(node)),
        ));
    }
    let interpolation = match sampler.interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let input = sampler.input();
    let in_at = format!("{place}, input accessor {}", input.index());
    let times = accessor::read_floats(&input, buffers, Dimensions::Scalar, &[], "SCALAR of FLOAT")
        .map_err(|m| SceneError::invalid(&in_at, m))?;
    if let Some(k) = times.iter().position(|t| !t.is_finite()) {
        return Err(SceneError::invalid(in_at, format!("key time {k} is not finite")));
    }
    if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
        return Err(SceneError::invalid(
            in_at,
            format!("key times are not increasing: key {} at {} s follows {} s", k + 1, times[k + 1], times[k]),
        ));
    }
    let width = match property {
        Property::Translation | Property::Scale => 3,
        Property::Rotation => 4,
        Property::Weights => {
            let targets = node.mesh().map_or(0, |m| m.primitives().map(|p| p.morph_targets().len()).max().unwrap_or(0));
            if targets == 0 {
                return Err(SceneError::invalid(
                    place,
                    format!("it animates the morph weights of {}, whose mesh has no morph targets", node_label(node)),
                ));
            }
            targets
        }
    };
    let output = sampler.output();
    let out_at = format!("{place}, output accessor {}", output.index());
    let (dims, normalized, what): (_, &[DataType], _) = match property {
        Property::Translation | Property::Scale => (Dimensions::Vec3, &[], "VEC3 of FLOAT"),
        Property::Rotation => (
            Dimensions::Vec4,
            &[DataType::I8, DataType::U8, DataType::I16, DataType::U16],
            "VEC4 of FLOAT or of a normalized integer type",
        ),
        Property::Weights => (
            Dimensions::Scalar,
            &[DataType::I8, DataType::U8, DataType::I16, DataType::U16],
            "SCALAR of FLOAT or of a normalized integer type",
        ),
    };
    let mut values =
        accessor::read_floats(&output, buffers, dims, normalized, what).map_err(|m| SceneError::invalid(&out_at, m))?;
    let per_key = width * if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
    let expected = times.len() * per_key;
    if values.len() != expected {
        let cubic = if interpolation == Interpolation::CubicSpline { " times 3 (CUBICSPLINE)" } else { "" };
        return Err(SceneError::invalid(
            out_at,
            format!("it has {} values; {} keys of {width} values{cubic} need {expected}", values.len(), times.len()),
        ));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(SceneError::invalid(out_at, format!("value {i} is not finite")));
    }
    if property == Property::Rotation && interpolation != Interpolation::CubicSpline {
        for (k, q) in values.chunks_exact_mut(4).enumerate() {
            let unit = glam::Vec4::from_slice(q)
                .try_normalize()
                .ok_or_else(|| SceneError::invalid(&out_at, format!("rotation key {k} has zero length")))?;
            q.copy_from_slice(&unit.to_array());
        }
    }
    Ok(Channel { node: 0, property, interpolation, times, values, width: width as u32 })
}

fn property_name(property: Property) -> &'static str {
    match property {
        Property::Translation => "the translation",
        Property::Rotation => "the rotation",
        Property::Scale => "the scale",
        Property::Weights => "the morph weights",
    }
}
