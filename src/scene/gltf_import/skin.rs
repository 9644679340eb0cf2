//! Skins: a primitive's joint influences (`JOINTS_n`/`WEIGHTS_n`, reduced to the four heaviest
//! per vertex) and a skin's joints and inverse bind matrices.

use super::accessor;
use crate::scene::animation::Skin;
use crate::scene::error::SceneError;
use glam::{Mat4, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Semantic;
use gltf::Primitive;

/// Joint influences of a primitive's vertices: four joints and weights each.
pub(super) type Influences = (Vec<[u16; 4]>, Vec<Vec4>);

/// Reads every `JOINTS_n`/`WEIGHTS_n` set of `primitive` (of `n` vertices) and keeps each
/// vertex's four heaviest influences (the weights are normalised when the mesh is validated);
/// a note says how many vertices lost influences. Empty for a primitive without joints.
pub(super) fn read_influences(
    primitive: &Primitive<'_>,
    buffers: &[Vec<u8>],
    n: usize,
    place: &str,
) -> Result<(Influences, Option<String>), SceneError> {
    let mut sets: Vec<(Vec<[u16; 4]>, Vec<Vec4>)> = Vec::new();
    for set in 0.. {
        let (joints, weights) = match (primitive.get(&Semantic::Joints(set)), primitive.get(&Semantic::Weights(set))) {
            (None, None) => break,
            (Some(j), None) => {
                let at = format!("{place}, JOINTS_{set} accessor {}", j.index());
                return Err(SceneError::invalid(at, format!("the primitive has no WEIGHTS_{set} to go with it")));
            }
            (None, Some(w)) => {
                let at = format!("{place}, WEIGHTS_{set} accessor {}", w.index());
                return Err(SceneError::invalid(at, format!("the primitive has no JOINTS_{set} to go with it")));
            }
            (Some(j), Some(w)) => (j, w),
        };
        let j_at = format!("{place}, JOINTS_{set} accessor {}", joints.index());
        let w_at = format!("{place}, WEIGHTS_{set} accessor {}", weights.index());
        let joints = accessor::read_joints(&joints, buffers).map_err(|m| SceneError::invalid(&j_at, m))?;
        let what = "VEC4 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT";
        let weights: Vec<Vec4> =
            accessor::read_floats(&weights, buffers, Dimensions::Vec4, &[DataType::U8, DataType::U16], what)
                .map_err(|m| SceneError::invalid(&w_at, m))?
                .chunks_exact(4)
                .map(Vec4::from_slice)
                .collect();
        if joints.len() != n {
            return Err(SceneError::invalid(j_at, format!("{} joint sets for {n} positions", joints.len())));
        }
        if weights.len() != n {
            return Err(SceneError::invalid(w_at, format!("{} weight sets for {n} positions", weights.len())));
        }
        if let Some((i, w)) = weights.iter().enumerate().find(|(_, w)| !w.is_finite() || w.min_element() < 0.0) {
            return Err(SceneError::invalid(
                w_at,
                format!("vertex {i} has weights {w}: they must be finite and at least 0"),
            ));
        }
        sets.push((joints, weights));
    }
    let Some(first) = sets.first() else { return Ok(((Vec::new(), Vec::new()), None)) };
    if sets.len() == 1 {
        let (joints, weights) = first.clone();
        return check_sums(place, (joints, weights));
    }
    let mut reduced = 0usize;
    let mut out: Influences = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut all: Vec<(u16, f32)> = Vec::with_capacity(4 * sets.len());
    for i in 0..n {
        all.clear();
        for (joints, weights) in &sets {
            all.extend((0..4).map(|k| (joints[i][k], weights[i][k])));
        }
        // Heaviest first; equal weights keep the file's order.
        all.sort_by(|a, b| b.1.total_cmp(&a.1));
        reduced += usize::from(all[4..].iter().any(|&(_, w)| w > 0.0));
        out.0.push(std::array::from_fn(|k| all[k].0));
        out.1.push(Vec4::from_array(std::array::from_fn(|k| all[k].1)));
    }
    let within_file = place.split_once(": ").map_or(place, |(_, rest)| rest);
    let note = (reduced > 0).then(|| {
        format!(
            "{within_file}: {reduced} of {n} vertices have more than 4 joint influences ({} sets); the 4 heaviest are kept, renormalised",
            sets.len()
        )
    });
    let (influences, _) = check_sums(place, out)?;
    Ok((influences, note))
}

/// Refuses a vertex whose weights are all 0 (no joint moves it).
fn check_sums(place: &str, influences: Influences) -> Result<(Influences, Option<String>), SceneError> {
    if let Some(i) = influences.1.iter().position(|w| w.element_sum() <= 0.0) {
        return Err(SceneError::invalid(
            format!("{place}, WEIGHTS_0"),
            format!("vertex {i} has all its joint weights 0"),
        ));
    }
    Ok((influences, None))
}

/// `skin 'name' (#i)`, or `skin #i`.
pub(super) fn skin_label(skin: &gltf::Skin<'_>) -> String {
    match skin.name() {
        Some(name) => format!("skin '{name}' (#{})", skin.index()),
        None => format!("skin #{}", skin.index()),
    }
}

/// A skin with its joints as animation node indices (`rig` maps a glTF node to its index, `None`
/// for a node outside the drawn scene) and its inverse bind matrices (identity without them).
pub(super) fn import(
    skin: &gltf::Skin<'_>,
    buffers: &[Vec<u8>],
    rig: impl Fn(usize) -> Option<u32>,
    file: &str,
) -> Result<Skin, SceneError> {
    let place = format!("{file}: {}", skin_label(skin));
    let joints: Vec<gltf::Node<'_>> = skin.joints().collect();
    if joints.is_empty() {
        return Err(SceneError::invalid(place, "the skin has no joints"));
    }
    let mut rig_joints = Vec::with_capacity(joints.len());
    for (j, node) in joints.iter().enumerate() {
        let index = rig(node.index()).ok_or_else(|| {
            SceneError::invalid(
                &place,
                format!("joint {j} is {}, which is not in the drawn scene", super::nodes::node_label(node)),
            )
        })?;
        rig_joints.push(index);
    }
    let inverse_bind = match skin.inverse_bind_matrices() {
        None => vec![Mat4::IDENTITY; joints.len()],
        Some(acc) => {
            let at = format!("{place}, inverseBindMatrices accessor {}", acc.index());
            let values = accessor::read_floats(&acc, buffers, Dimensions::Mat4, &[], "MAT4 of FLOAT")
                .map_err(|m| SceneError::invalid(&at, m))?;
            let matrices: Vec<Mat4> = values.chunks_exact(16).map(Mat4::from_cols_slice).collect();
            if matrices.len() < joints.len() {
                return Err(SceneError::invalid(
                    at,
                    format!("{} matrices for {} joints", matrices.len(), joints.len()),
                ));
            }
            if let Some(i) = matrices.iter().position(|m| !m.is_finite()) {
                return Err(SceneError::invalid(at, format!("matrix {i} is not finite")));
            }
            matrices[..joints.len()].to_vec()
        }
    };
    Ok(Skin {
        name: skin.name().map_or_else(|| format!("skin #{}", skin.index()), str::to_string),
        joints: rig_joints,
        inverse_bind,
    })
}
