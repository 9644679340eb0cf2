//! Vertex format and mesh data as sources produce it, with the checks every mesh passes.

use super::bounds::{Aabb, Sphere};
use super::deform::{MeshDeform, MorphTarget};
use super::error::SceneError;
use glam::{Vec2, Vec3};

/// A vertex of the shared pool (32 bytes): position, octahedral-encoded unit normal, texture
/// coordinates and tangent.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// Local-space position.
    pub position: [f32; 3],
    /// Normal, octahedral-encoded as two snorm16 values (see [`encode_octahedral`]).
    pub normal: [i16; 2],
    /// Texture coordinates (glTF `TEXCOORD_0`; 0 where the mesh has none).
    pub uv: [f32; 2],
    /// Tangent as snorm16: xyz the direction of increasing u, w the handedness of the
    /// bitangent (glTF `TANGENT`, or generated with MikkTSpace).
    pub tangent: [i16; 4],
}

/// Packs a unit tangent and its handedness as [`Vertex::tangent`] stores them.
pub fn encode_tangent(t: glam::Vec4) -> [i16; 4] {
    let q = |v: f32| (v.clamp(-1.0, 1.0) * 32767.0).round() as i16;
    [q(t.x), q(t.y), q(t.z), if t.w < 0.0 { -32767 } else { 32767 }]
}

/// Encodes a unit vector into two snorm16 values (octahedral map; error below 0.01 degrees).
pub fn encode_octahedral(n: Vec3) -> [i16; 2] {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs()).max(f32::MIN_POSITIVE);
    let mut p = Vec2::new(n.x, n.y);
    if n.z < 0.0 {
        let sign = Vec2::new(if p.x >= 0.0 { 1.0 } else { -1.0 }, if p.y >= 0.0 { 1.0 } else { -1.0 });
        p = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign;
    }
    let q = |v: f32| (v.clamp(-1.0, 1.0) * 32767.0).round() as i16;
    [q(p.x), q(p.y)]
}

/// Inverse of [`encode_octahedral`] (what the shaders do).
pub fn decode_octahedral(e: [i16; 2]) -> Vec3 {
    let p = Vec2::new((e[0] as f32 / 32767.0).max(-1.0), (e[1] as f32 / 32767.0).max(-1.0));
    let z = 1.0 - p.x.abs() - p.y.abs();
    let t = (-z).max(0.0);
    let x = p.x + if p.x >= 0.0 { -t } else { t };
    let y = p.y + if p.y >= 0.0 { -t } else { t };
    Vec3::new(x, y, z).normalize()
}

/// What [`MeshData::validate`] gives: pool vertices, local bounds of the rest shape, and the
/// deformation of a skinned or morphed mesh.
pub type MeshParts = (Vec<Vertex>, Aabb, Sphere, Option<MeshDeform>);

/// Raw triangle-list geometry of one mesh before it joins the pool.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Normals, one per position; empty to compute flat-ish area-weighted vertex normals.
    pub normals: Vec<Vec3>,
    /// Triangle list indices into `positions`.
    pub indices: Vec<u32>,
    /// Texture coordinates, one per position; empty for none (all zero).
    pub uvs: Vec<Vec2>,
    /// Tangents (xyz unit, w ±1 handedness), one per position; empty to generate them from the
    /// texture coordinates (MikkTSpace).
    pub tangents: Vec<glam::Vec4>,
    /// Skin joint indices, four per position; empty for a mesh that is not skinned.
    pub joints: Vec<[u16; 4]>,
    /// Skin weights of `joints`, one per position (at least 0, not all 0; normalised to sum 1
    /// by [`MeshData::validate`]); empty with `joints`.
    pub weights: Vec<glam::Vec4>,
    /// Morph targets (offsets from the rest shape).
    pub morph_targets: Vec<MorphTarget>,
    /// Default weights of the morph targets (glTF mesh `weights`); missing ones are 0.
    pub morph_weights: Vec<f32>,
    /// Never simplified: the mesh gets no levels of detail and is drawn whole at any distance
    /// (a prop whose silhouette matters).
    pub no_lod: bool,
}

impl MeshData {
    /// Checks the mesh and converts it to pool vertices, returning them with local bounds (of
    /// the rest shape) and the mesh's deformation, if it has one.
    ///
    /// Refuses: no triangles, an index count not a multiple of 3, an index past the vertex
    /// count, non-finite positions, a normal count that differs from the position count, and a
    /// mesh whose triangles all have zero area. Missing or zero normals are computed from faces.
    /// Deformation: joints and weights one per position, weights finite, at least 0 and not
    /// all 0 (they are normalised to sum 1), morph targets one offset per position, finite.
    pub fn validate(&self, place: &str) -> Result<MeshParts, SceneError> {
        let err = |m: String| SceneError::invalid(place, m);
        if self.indices.is_empty() || self.positions.is_empty() {
            return Err(err("mesh has no triangles".into()));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(err(format!("index count {} is not a multiple of 3", self.indices.len())));
        }
        let n = self.positions.len();
        if let Some((at, &bad)) = self.indices.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            return Err(err(format!("index {bad} at position {at} is out of range (the mesh has {n} vertices)")));
        }
        if let Some((at, p)) = self.positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(err(format!("vertex {at} has a non-finite position {p}")));
        }
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(err(format!("{} normals for {} positions", self.normals.len(), n)));
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            return Err(err(format!("{} texture coordinates for {} positions", self.uvs.len(), n)));
        }
        if let Some((at, uv)) = self.uvs.iter().enumerate().find(|(_, uv)| !uv.is_finite()) {
            return Err(err(format!("vertex {at} has non-finite texture coordinates {uv}")));
        }
        if !self.tangents.is_empty() && self.tangents.len() != n {
            return Err(err(format!("{} tangents for {} positions", self.tangents.len(), n)));
        }
        let deform = self.validate_deform(place)?;
        let face_normals = self.area_weighted_normals();
        let has_area = face_normals.iter().any(|v| *v != Vec3::ZERO);
        if !has_area {
            return Err(err(format!("all {} triangles have zero area", self.indices.len() / 3)));
        }
        let normals: Vec<Vec3> = (0..n)
            .map(|i| {
                let given = self.normals.get(i).copied().filter(|v| v.is_finite() && v.length_squared() > 1e-12);
                given.map(Vec3::normalize).or_else(|| face_normals[i].try_normalize()).unwrap_or(Vec3::Y)
            })
            .collect();
        let tangents = if self.tangents.is_empty() {
            super::tangents::generate(&self.positions, &normals, &self.uvs, &self.indices)
        } else {
            self.tangents.iter().zip(&normals).map(|(t, n)| super::tangents::orthonormal(*t, *n)).collect()
        };
        let vertices = (0..n)
            .map(|i| Vertex {
                position: self.positions[i].to_array(),
                normal: encode_octahedral(normals[i]),
                uv: self.uvs.get(i).copied().unwrap_or(Vec2::ZERO).to_array(),
                tangent: encode_tangent(tangents[i]),
            })
            .collect();
        // Bounds over referenced vertices only: an unused far-away vertex must not inflate them.
        let mut used = vec![false; n];
        for &i in &self.indices {
            used[i as usize] = true;
        }
        let points: Vec<Vec3> = (0..n).filter(|&i| used[i]).map(|i| self.positions[i]).collect();
        let bounds = Aabb::from_points(points.iter().copied()).ok_or_else(|| err("mesh has no vertices".into()))?;
        let sphere = Sphere::around(&points, &bounds);
        Ok((vertices, bounds, sphere, deform))
    }

    /// The share of triangle area whose given vertex normals are nearly perpendicular to the
    /// triangle (more than ~73 degrees off, either side): 0 for sound normals, close to 1 for
    /// normals that ignore the geometry (an exporter that wrote +Y everywhere). `None` without normals.
    pub fn normal_disagreement(&self) -> Option<f32> {
        if self.normals.len() != self.positions.len() || self.positions.is_empty() {
            return None;
        }
        let (mut bad, mut total) = (0.0f64, 0.0f64);
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            if a.max(b).max(c) >= self.positions.len() {
                continue;
            }
            let face = (self.positions[b] - self.positions[a]).cross(self.positions[c] - self.positions[a]);
            let area = face.length() as f64;
            let mean = self.normals[a] + self.normals[b] + self.normals[c];
            if area <= 0.0 || area.is_nan() || !mean.is_finite() || mean.length_squared() <= 1e-12 {
                continue;
            }
            total += area;
            if (face.normalize().dot(mean.normalize())).abs() < 0.3 {
                bad += area;
            }
        }
        Some(if total > 0.0 { (bad / total) as f32 } else { 0.0 })
    }

    /// Per-vertex sums of adjacent face normals weighted by area (zero for isolated vertices).
    fn area_weighted_normals(&self) -> Vec<Vec3> {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let face = (self.positions[b] - self.positions[a]).cross(self.positions[c] - self.positions[a]);
            if face.is_finite() {
                for v in [a, b, c] {
                    normals[v] += face;
                }
            }
        }
        normals
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octahedral_round_trip_is_accurate() {
        let mut worst = 1.0f32;
        for i in 0..2000 {
            // Fibonacci sphere: evenly spread directions.
            let t = i as f32 * 0.618034 * std::f32::consts::TAU;
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 2000.0;
            let r = (1.0 - z * z).sqrt();
            let n = Vec3::new(r * t.cos(), r * t.sin(), z).normalize();
            worst = worst.min(decode_octahedral(encode_octahedral(n)).dot(n));
        }
        assert!(worst > 0.99999, "worst cosine {worst}");
        for axis in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            assert!(decode_octahedral(encode_octahedral(axis)).dot(axis) > 0.99999);
        }
    }

    #[test]
    fn detects_normals_that_ignore_the_geometry() {
        let mut wall = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ZERO, Vec3::Z, Vec3::X],
            normals: vec![Vec3::Z, Vec3::Z, Vec3::Z, -Vec3::Y, -Vec3::Y, -Vec3::Y],
            indices: vec![0, 1, 2, 3, 4, 5],
            ..Default::default()
        };
        assert_eq!(wall.normal_disagreement(), Some(0.0));
        wall.normals = vec![Vec3::Y; 6]; // the floor triangle agrees (flipped), the wall does not
        assert_eq!(wall.normal_disagreement(), Some(0.5));
        wall.normals.clear();
        assert_eq!(wall.normal_disagreement(), None);
    }

    #[test]
    fn refuses_bad_meshes_naming_the_place() {
        let tri = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        assert!(tri.validate("m").is_ok());
        let oob = MeshData { indices: vec![0, 1, 3], ..tri.clone() };
        let e = oob.validate("mesh 'x' (accessor 4)").unwrap_err().to_string();
        assert!(e.starts_with("mesh 'x' (accessor 4): index 3"), "{e}");
        let flat = MeshData { positions: vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], ..tri.clone() };
        assert!(flat.validate("m").unwrap_err().to_string().contains("zero area"));
        let nan = MeshData { positions: vec![Vec3::ZERO, Vec3::NAN, Vec3::Y], ..tri.clone() };
        assert!(nan.validate("m").unwrap_err().to_string().contains("non-finite"));
    }
}
