//! One glTF primitive to triangle-list [`MeshData`]: attribute reads, index checks and the
//! conversion of strips and fans.

use super::accessor;
use crate::scene::error::SceneError;
use crate::scene::mesh::MeshData;
use glam::{Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};
use gltf::Primitive;

/// What became of a primitive.
pub(super) enum Converted {
    /// Triangle-list geometry, the place string to hand to `Scene::add_mesh`, and notes on
    /// attributes that were unusable (normals recomputed from the faces, texture coordinates or
    /// tangents dropped).
    Mesh(Box<MeshData>, String, Vec<String>),
    /// A primitive that cannot be drawn as triangles, with the reason.
    Skipped(String),
}

/// Reads `primitive`; `place` names file, mesh and primitive (e.g. `a.glb: mesh 'wall' (#3)
/// primitive 0`) and is extended with the accessor in every error.
pub(super) fn convert(primitive: &Primitive<'_>, buffers: &[Vec<u8>], place: &str) -> Result<Converted, SceneError> {
    let mode = primitive.mode();
    if !super::totals::drawable(mode) {
        return Ok(Converted::Skipped(format!("mode {} cannot be drawn as triangles", mode_name(mode))));
    }
    let positions_accessor = primitive
        .get(&Semantic::Positions)
        .ok_or_else(|| SceneError::invalid(place, "primitive has no POSITION attribute"))?;
    let pos_place = format!("{place}, POSITION accessor {}", positions_accessor.index());
    let positions: Vec<Vec3> = accessor::read_vec3(&positions_accessor, buffers)
        .map_err(|m| SceneError::invalid(&pos_place, m))?
        .into_iter()
        .map(Vec3::from_array)
        .collect();
    if let Some((at, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(SceneError::invalid(&pos_place, format!("vertex {at} has a non-finite position {p}")));
    }
    let n = positions.len();

    let mut place_for_mesh = pos_place.clone();
    let mut normal_note: Option<String> = None;
    let normals = match primitive.get(&Semantic::Normals) {
        None => Vec::new(),
        Some(acc) => {
            let nrm_place = format!("{place}, NORMAL accessor {}", acc.index());
            let normals = accessor::read_vec3(&acc, buffers).map_err(|m| SceneError::invalid(&nrm_place, m))?;
            if normals.len() != n {
                return Err(SceneError::invalid(
                    &nrm_place,
                    format!(
                        "{} normals for {n} positions (POSITION accessor {})",
                        normals.len(),
                        positions_accessor.index()
                    ),
                ));
            }
            // Non-finite or zero normals are recomputed from the faces by `MeshData::validate`.
            let normals: Vec<Vec3> = normals.into_iter().map(Vec3::from_array).collect();
            let bad = normals.iter().filter(|v| !v.is_finite() || v.length_squared() <= 1e-12).count();
            if bad > 0 {
                normal_note = Some(format!(
                    "{nrm_place}: {bad} of {n} normals are zero or not finite; they are computed from the faces"
                ));
            }
            normals
        }
    };

    let raw_indices = match primitive.indices() {
        None => {
            let count = u32::try_from(n).map_err(|_| SceneError::too_large(&pos_place, "vertex count"))?;
            (0..count).collect()
        }
        Some(acc) => {
            let idx_place = format!("{place}, indices accessor {}", acc.index());
            let indices = accessor::read_indices(&acc, buffers).map_err(|m| SceneError::invalid(&idx_place, m))?;
            if let Some((at, &bad)) = indices.iter().enumerate().find(|(_, &i)| i as usize >= n) {
                return Err(SceneError::invalid(
                    &idx_place,
                    format!(
                        "index {bad} at element {at} is out of range (POSITION accessor {} has {n} vertices)",
                        positions_accessor.index()
                    ),
                ));
            }
            place_for_mesh = format!("{pos_place}, indices accessor {}", acc.index());
            indices
        }
    };
    let indices = match mode {
        Mode::TriangleStrip => strip_to_list(&raw_indices),
        Mode::TriangleFan => fan_to_list(&raw_indices),
        _ => raw_indices,
    };
    if !indices.len().is_multiple_of(3) {
        let what = if primitive.indices().is_some() { "indices" } else { "vertices (it has no indices)" };
        return Err(SceneError::invalid(
            &place_for_mesh,
            format!("a TRIANGLES primitive needs a multiple of 3 {what}, it has {}", indices.len()),
        ));
    }
    let (uvs, uv_note) = optional_attribute(primitive, Semantic::TexCoords(0), "TEXCOORD_0", n, place, |acc| {
        accessor::read_uv(acc, buffers).map(|v| v.into_iter().map(Vec2::from_array).collect())
    });
    let (tangents, tangent_note) = optional_attribute(primitive, Semantic::Tangents, "TANGENT", n, place, |acc| {
        accessor::read_vec4(acc, buffers).map(|v| v.into_iter().map(Vec4::from_array).collect())
    });
    let tangents = if uvs.is_empty() { Vec::new() } else { tangents };
    let ((joints, weights), influence_note) = super::skin::read_influences(primitive, buffers, n, place)?;
    let (morph_targets, morph_note) = super::morph::read_targets(primitive, buffers, n, place)?;
    let mut notes: Vec<String> =
        normal_note.into_iter().chain(uv_note).chain(tangent_note).chain(influence_note).chain(morph_note).collect();
    let mut mesh = MeshData {
        uvs,
        tangents,
        positions,
        normals,
        indices,
        joints,
        weights,
        morph_targets,
        morph_weights: Vec::new(),
        no_lod: false,
    };
    // Normals that contradict the faces (all +Y on walls, say) would light the mesh as if it
    // were flat; recompute them from the faces and say so.
    if let Some(share) = mesh.normal_disagreement().filter(|&s| s > NORMAL_DISAGREEMENT_LIMIT) {
        // Notes are printed after the file name already.
        let within_file = place.split_once(": ").map_or(place, |(_, rest)| rest);
        notes.push(format!(
            "{within_file}: the file's normals are nearly perpendicular to {:.0}% of the surface area; they are ignored and computed from the faces",
            share * 100.0
        ));
        mesh.normals.clear();
    }
    Ok(Converted::Mesh(Box::new(mesh), place_for_mesh, notes))
}

/// Reads an attribute the mesh can do without (texture coordinates, tangents): one that is
/// unreadable, of the wrong type or count, or not finite is dropped with a note naming its
/// accessor, and the primitive still loads.
fn optional_attribute<T>(
    primitive: &Primitive<'_>,
    semantic: Semantic,
    name: &str,
    count: usize,
    place: &str,
    read: impl Fn(&gltf::Accessor<'_>) -> Result<Vec<T>, String>,
) -> (Vec<T>, Option<String>)
where
    T: Finite,
{
    let Some(acc) = primitive.get(&semantic) else { return (Vec::new(), None) };
    let at = format!("{place}, {name} accessor {}", acc.index());
    let checked = read(&acc).and_then(|values| {
        if values.len() != count {
            Err(format!("{} values for {count} positions", values.len()))
        } else if let Some(i) = values.iter().position(|v| !v.finite()) {
            Err(format!("value {i} is not finite"))
        } else {
            Ok(values)
        }
    });
    match checked {
        Ok(values) => (values, None),
        Err(why) => (Vec::new(), Some(format!("{at}: {why}; the attribute is ignored"))),
    }
}

/// Values that can be checked for being finite.
trait Finite {
    fn finite(&self) -> bool;
}

impl Finite for Vec2 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}

impl Finite for Vec4 {
    fn finite(&self) -> bool {
        self.is_finite()
    }
}

/// Share of surface area with contradicting normals above which a primitive's normals are
/// recomputed. Sound smooth normals stay far below it (only sharp creases disagree that much).
const NORMAL_DISAGREEMENT_LIMIT: f32 = 0.2;

/// The glTF spelling of a primitive mode.
pub(super) fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

/// Triangle strip to list. Triangle `i` is `(i, i+1, i+2)` for even `i` and `(i+1, i, i+2)`
/// for odd `i`, so that every triangle keeps the strip's front-face winding. Triangles with a
/// repeated index (the degenerate joints between strips) are dropped.
pub fn strip_to_list(strip: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(strip.len().saturating_sub(2) * 3);
    for (i, w) in strip.windows(3).enumerate() {
        let [a, b, c] = if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[1], w[0], w[2]] };
        if a != b && b != c && a != c {
            out.extend_from_slice(&[a, b, c]);
        }
    }
    out
}

/// Triangle fan to list: triangle `i` is `(0, i+1, i+2)` (the spec's `(i+1, i+2, 0)`, rotated).
pub fn fan_to_list(fan: &[u32]) -> Vec<u32> {
    let Some(&first) = fan.first() else {
        return Vec::new();
    };
    let mut out = Vec::with_capacity(fan.len().saturating_sub(2) * 3);
    for w in fan[1..].windows(2) {
        if first != w[0] && w[0] != w[1] && first != w[1] {
            out.extend_from_slice(&[first, w[0], w[1]]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_alternate_winding() {
        assert_eq!(strip_to_list(&[0, 1, 2, 3, 4]), vec![0, 1, 2, 2, 1, 3, 2, 3, 4]);
        // Degenerate joint triangles are dropped.
        assert_eq!(strip_to_list(&[0, 1, 2, 2, 3, 4]), vec![0, 1, 2, 3, 2, 4]);
        assert!(strip_to_list(&[0, 1]).is_empty());
    }

    #[test]
    fn fans_share_the_first_vertex() {
        assert_eq!(fan_to_list(&[0, 1, 2, 3]), vec![0, 1, 2, 0, 2, 3]);
        assert!(fan_to_list(&[]).is_empty());
    }
}
