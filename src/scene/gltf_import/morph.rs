//! Morph targets of a primitive: position and normal offsets (tangent offsets are ignored).

use super::accessor;
use crate::scene::deform::MorphTarget;
use crate::scene::error::SceneError;
use glam::Vec3;
use gltf::Primitive;

/// Reads the morph targets of `primitive` (of `n` vertices); a note when tangent offsets are
/// left out.
pub(super) fn read_targets(
    primitive: &Primitive<'_>,
    buffers: &[Vec<u8>],
    n: usize,
    place: &str,
) -> Result<(Vec<MorphTarget>, Option<String>), SceneError> {
    let mut targets = Vec::new();
    let mut tangents = false;
    for (t, target) in primitive.morph_targets().enumerate() {
        let read = |acc: Option<gltf::Accessor<'_>>, what: &str| -> Result<Vec<Vec3>, SceneError> {
            let Some(acc) = acc else { return Ok(Vec::new()) };
            let at = format!("{place}, morph target {t} {what} accessor {}", acc.index());
            let values = accessor::read_vec3(&acc, buffers).map_err(|m| SceneError::invalid(&at, m))?;
            if values.len() != n {
                return Err(SceneError::invalid(at, format!("{} offsets for {n} positions", values.len())));
            }
            if let Some(i) = values.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
                return Err(SceneError::invalid(at, format!("offset {i} is not finite")));
            }
            Ok(values.into_iter().map(Vec3::from_array).collect())
        };
        let positions = read(target.positions(), "POSITION")?;
        let positions = if positions.is_empty() { vec![Vec3::ZERO; n] } else { positions };
        let normals = read(target.normals(), "NORMAL")?;
        tangents |= target.tangents().is_some();
        targets.push(MorphTarget { positions, normals });
    }
    let within_file = place.split_once(": ").map_or(place, |(_, rest)| rest);
    let note =
        tangents.then(|| format!("{within_file}: morph target TANGENT offsets are ignored (tangents stay at rest)"));
    Ok((targets, note))
}
