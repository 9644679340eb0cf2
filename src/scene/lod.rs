//! Levels of detail: each mesh's chain of simplified index lists over its own vertices, built
//! with meshoptimizer when the mesh joins a scene, each level with its object-space error.
//!
//! Each level halves the triangles of the one before, simplified from it with the vertex normals
//! as attributes (vertices split at a UV seam or a hard edge are a topological border the
//! simplifier keeps), its triangles then ordered for the post-transform vertex cache. The error of a level is the sum of the errors of the steps that made it,
//! so it bounds the level's distance from the full mesh, and errors never decrease along the
//! chain. The chain stops where a step no longer pays: fewer than [`LOD_MIN_TRIANGLES`] would
//! remain, or a step removes less than [`LOD_MIN_REDUCTION`] of the triangles.

use super::mesh::{decode_octahedral, Vertex};

/// The most levels a mesh has, the full mesh included (the cull pass stores a level in 3 bits).
pub const MAX_LOD_LEVELS: usize = 8;

/// Meshes with fewer triangles get no chain, and no level goes below this many: a few hundred
/// triangles cost a draw nothing more than a dozen do.
pub const LOD_MIN_TRIANGLES: usize = 256;

/// A step that keeps more than this share of its input's triangles ends the chain.
pub const LOD_MIN_REDUCTION: f32 = 0.15;

/// Weight of each normal component against position error (relative to the mesh's extent).
/// The reported error is the combined one, so it still bounds the geometric error, and a level
/// whose shading drifts counts as coarser: a level's normals are the full mesh's at the vertices
/// it keeps, and at light weights the speckle of sub-pixel bumps they carry dominates the image
/// error (docs/lod.md measures 0.5 to 32; at 16 the 1-pixel threshold stays within 0.001 mean FLIP
/// of full detail on `builtin:dense`).
const NORMAL_WEIGHT: f32 = 16.0;

/// One simplified level of a mesh, in the shared index pool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodLevel {
    /// First index in [`super::Scene::indices`] (relative to the mesh's `vertex_offset`, as the
    /// full mesh's are).
    pub first_index: u32,
    /// Number of indices (a multiple of 3).
    pub index_count: u32,
    /// How far, in the mesh's local units, this level's surface may be from the full mesh's.
    pub error: f32,
}

/// The simplified levels of the mesh with `vertices` and triangle list `indices` (level 0, the
/// mesh itself, not included), coarser and coarser, each as its indices and its object-space
/// error. Empty where simplification does not pay.
pub fn build_chain(vertices: &[Vertex], indices: &[u32]) -> Vec<(Vec<u32>, f32)> {
    let mut chain = Vec::new();
    if indices.len() / 3 < 2 * LOD_MIN_TRIANGLES || vertices.is_empty() {
        return chain;
    }
    let Ok(adapter) = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(vertices), size_of::<Vertex>(), 0) else {
        return chain;
    };
    let normals: Vec<f32> = vertices.iter().flat_map(|v| decode_octahedral(v.normal).to_array()).collect();
    let locks = vec![false; vertices.len()];
    // meshoptimizer reports errors relative to the mesh's extent; this converts them to units.
    let scale = meshopt::simplify_scale(&adapter);
    let mut current = indices.to_vec();
    let mut error = 0.0f32;
    while chain.len() + 1 < MAX_LOD_LEVELS {
        let triangles = current.len() / 3;
        let target = triangles / 2;
        if target < LOD_MIN_TRIANGLES {
            break;
        }
        let mut step_error = 0.0f32;
        let next = meshopt::simplify_with_attributes_and_locks(
            &current,
            &adapter,
            &normals,
            &[NORMAL_WEIGHT; 3],
            3 * size_of::<f32>(),
            &locks,
            target * 3,
            f32::MAX,
            meshopt::SimplifyOptions::None,
            Some(&mut step_error),
        );
        let kept = next.len() as f32 / current.len() as f32;
        if next.is_empty() || kept > 1.0 - LOD_MIN_REDUCTION || !step_error.is_finite() {
            break;
        }
        error += step_error * scale;
        // The simplifier keeps its input's order; the post-transform cache wants its own.
        let next = meshopt::optimize_vertex_cache(&next, vertices.len());
        chain.push((next.clone(), error));
        current = next;
    }
    chain
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::scene::{encode_octahedral, MeshData};
    use glam::Vec3;

    /// A UV sphere of about `2 * rings * segments` triangles with radius 1.
    pub fn sphere(rings: u32, segments: u32) -> MeshData {
        let mut positions = Vec::new();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * s as f32 / segments as f32;
                positions.push(Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
            }
        }
        let mut indices = Vec::new();
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b) = (r * row + s, (r + 1) * row + s);
                indices.extend([a, a + 1, b, a + 1, b + 1, b]);
            }
        }
        MeshData { normals: positions.clone(), positions, indices, ..Default::default() }
    }

    fn vertices(data: &MeshData) -> Vec<Vertex> {
        data.positions
            .iter()
            .map(|p| Vertex { position: p.to_array(), normal: encode_octahedral(*p), ..Default::default() })
            .collect()
    }

    #[test]
    fn levels_halve_the_triangles_with_growing_error() {
        let data = sphere(64, 128);
        let chain = build_chain(&vertices(&data), &data.indices);
        assert!(chain.len() >= 3, "{} levels", chain.len());
        let mut previous = (data.indices.len(), 0.0f32);
        for (indices, error) in &chain {
            assert_eq!(indices.len() % 3, 0);
            assert!(indices.len() <= previous.0 * 6 / 10, "{} after {}", indices.len(), previous.0);
            assert!(indices.len() / 3 >= LOD_MIN_TRIANGLES);
            assert!(*error >= previous.1 && error.is_finite());
            assert!(indices.iter().all(|&i| (i as usize) < data.positions.len()));
            previous = (indices.len(), *error);
        }
        // The coarsest level is still a sphere: its error (in the mesh's units, the normals'
        // drift weighed in) stays below the radius.
        assert!(previous.1 < 1.0, "error {}", previous.1);
    }

    #[test]
    fn scenes_give_meshes_their_chains_unless_told_not_to() {
        let mut scene = crate::scene::Scene::default();
        let data = sphere(64, 128);
        let with = scene.add_mesh("with", &data, "with").unwrap();
        let without = scene.add_mesh("without", &MeshData { no_lod: true, ..data.clone() }, "without").unwrap();
        let m = scene.meshes[with as usize].clone();
        assert!(!m.lods.is_empty());
        let mut end = (m.first_index + m.index_count) as usize;
        for level in &m.lods {
            // Each level follows the one before in the pool and indexes the mesh's own vertices.
            assert_eq!(level.first_index as usize, end);
            end += level.index_count as usize;
            let indices = &scene.indices[level.first_index as usize..end];
            assert!(indices.iter().all(|&i| i < m.vertex_count));
        }
        assert!(scene.meshes[without as usize].lods.is_empty());
        assert_eq!(scene.meshes[without as usize].first_index as usize, end);
    }

    #[test]
    fn degenerate_meshes_get_a_chain_or_none_without_failing() {
        // Every vertex its own (an unindexed mesh): no edge can collapse, so no step pays.
        let data = sphere(32, 64);
        let soup: Vec<Vertex> = data.indices.iter().map(|&i| vertices(&data)[i as usize]).collect();
        let sequential: Vec<u32> = (0..soup.len() as u32).collect();
        assert!(build_chain(&soup, &sequential).is_empty());
        // Zero-area triangles among good ones: levels as usual, every index in range.
        let mut data = sphere(64, 128);
        let n = data.indices.len();
        for k in (0..n).step_by(30) {
            data.indices[k + 1] = data.indices[k];
        }
        let chain = build_chain(&vertices(&data), &data.indices);
        assert!(!chain.is_empty());
        assert!(chain.iter().all(|(i, e)| i.iter().all(|&v| (v as usize) < data.positions.len()) && e.is_finite()));
    }

    #[test]
    fn small_meshes_get_no_chain() {
        let data = sphere(8, 16);
        assert!(build_chain(&vertices(&data), &data.indices).is_empty());
        assert!(build_chain(&[], &[]).is_empty());
    }
}
