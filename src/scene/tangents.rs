//! Per-vertex tangents for normal mapping: generated from texture coordinates with MikkTSpace
//! (the convention normal maps are baked in), or given ones made orthonormal.

use glam::{Vec2, Vec3, Vec4};

/// A unit vector perpendicular to `n`.
fn any_perpendicular(n: Vec3) -> Vec3 {
    n.any_orthonormal_vector()
}

/// `t` made a unit tangent perpendicular to `n`, with its handedness kept (any perpendicular
/// where `t` is unusable).
pub fn orthonormal(t: Vec4, n: Vec3) -> Vec4 {
    let dir = t.truncate();
    let dir = if dir.is_finite() { dir - n * n.dot(dir) } else { Vec3::ZERO };
    let dir = dir.try_normalize().unwrap_or_else(|| any_perpendicular(n));
    dir.extend(if t.w < 0.0 { -1.0 } else { 1.0 })
}

/// The geometry as MikkTSpace reads it: faces are triangles of the index list.
struct Geometry<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: &'a [Vec2],
    indices: &'a [u32],
    /// Sum of the tangents MikkTSpace gives each vertex's corners, and of their handedness.
    sums: Vec<Vec4>,
}

impl Geometry<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face * 3 + vert] as usize
    }
}

impl mikktspace::Geometry for Geometry<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[self.vertex(face, vert)].to_array()
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        let v = self.vertex(face, vert);
        if tangent.iter().all(|x| x.is_finite()) {
            self.sums[v] += Vec4::from_array(tangent);
        }
    }
}

/// Tangents for a mesh with `uvs` (one per position, or none). A vertex shared by faces gets the
/// average of its corners' MikkTSpace tangents (vertices on texture seams are split by the
/// exporter, having different coordinates); without coordinates, or where they are degenerate,
/// any tangent perpendicular to the normal.
pub fn generate(positions: &[Vec3], normals: &[Vec3], uvs: &[Vec2], indices: &[u32]) -> Vec<Vec4> {
    let fallback = || normals.iter().map(|&n| any_perpendicular(n).extend(1.0)).collect();
    if uvs.len() != positions.len() || indices.is_empty() {
        return fallback();
    }
    let mut geometry = Geometry { positions, normals, uvs, indices, sums: vec![Vec4::ZERO; positions.len()] };
    if !mikktspace::generate_tangents(&mut geometry) {
        return fallback();
    }
    geometry.sums.iter().zip(normals).map(|(sum, &n)| orthonormal(*sum, n)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad in the xy plane facing +z with u along +x and v along -y (glTF's v points down the
    /// image): the tangent is +x, and the bitangent (n x t * w) points along +v, that is -y.
    #[test]
    fn a_quad_gets_the_tangent_of_increasing_u() {
        let positions =
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let normals = [Vec3::Z; 4];
        let uvs = [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)];
        let tangents = generate(&positions, &normals, &uvs, &[0, 1, 2, 0, 2, 3]);
        for t in tangents {
            assert!(t.truncate().distance(Vec3::X) < 1e-4, "{t}");
            let bitangent = Vec3::Z.cross(t.truncate()) * t.w;
            assert!(bitangent.distance(Vec3::NEG_Y) < 1e-4, "{bitangent}");
        }
    }

    #[test]
    fn without_coordinates_tangents_are_perpendicular_to_the_normal() {
        let normals = [Vec3::Y, Vec3::new(0.0, 0.6, 0.8)];
        for (t, n) in generate(&[Vec3::ZERO; 2], &normals, &[], &[]).iter().zip(normals) {
            assert!(t.truncate().dot(n).abs() < 1e-5 && (t.truncate().length() - 1.0).abs() < 1e-5);
        }
    }
}
