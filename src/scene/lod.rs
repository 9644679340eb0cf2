//! Levels of detail: each mesh's chain of simplified levels, built with meshoptimizer when the
//! mesh joins a scene, each level with its object-space error.
//!
//! Each level keeps half the triangles of the one before (a larger share is removed where
//! halving would need more than [`MAX_LOD_LEVELS`] levels to come down to a few dozen
//! triangles), simplified from it with the vertex normals as lightly weighted attributes
//! (vertices split at a UV seam or a hard edge are a topological border the simplifier keeps),
//! its triangles then ordered for the post-transform vertex cache. The error of a level is the
//! sum of the errors of the steps that made it, so it bounds the level's distance from the full
//! mesh, and errors never decrease along the chain: a threshold in pixels is a bound on how far
//! the surface moves on screen.
//!
//! A level draws its own copies of the vertices it keeps, whose normals are the full mesh's
//! averaged over the surface around each (`filtered_normals`): the full mesh's normal at a
//! kept vertex samples detail far finer than the level's triangles, which would shade as noise.
//!
//! The chain stops where a step no longer pays: fewer than [`LOD_FLOOR_TRIANGLES`] would remain,
//! a step removes less than [`LOD_MIN_REDUCTION`] of the triangles, or the level would be
//! further from the full mesh than a quarter of its extent.

use super::mesh::{decode_octahedral, encode_octahedral, encode_tangent, Vertex};
use glam::{Vec3, Vec4};
use std::collections::HashMap;

/// Hashes cells and positions fast; nothing here is keyed by input an attacker chooses to collide.
type FastMap<K, V> = HashMap<K, V, foldhash::fast::FixedState>;

/// The most levels a mesh has, the full mesh included (the cull pass stores a level in 3 bits).
pub const MAX_LOD_LEVELS: usize = 8;

/// Meshes with fewer than twice this many triangles get no chain, and the steps between levels
/// are sized to come down to it within [`MAX_LOD_LEVELS`] levels.
pub const LOD_MIN_TRIANGLES: usize = 64;

/// No level goes below this many triangles. Below [`LOD_MIN_TRIANGLES`], since the last step
/// aimed at it may fall just short: that level still takes a hundred triangles off each
/// distant instance a few pixels across, which add up over many instances. Coarser than this,
/// a dozen triangles more or less cost nothing next to the instance itself.
pub const LOD_FLOOR_TRIANGLES: usize = 24;

/// A step that keeps more than this share of its input's triangles ends the chain.
pub const LOD_MIN_REDUCTION: f32 = 0.15;

/// The largest error a level may have, relative to the mesh's extent.
const LOD_MAX_ERROR: f32 = 0.25;

/// The share of triangles a step keeps at least: halving gives the finest choice between levels,
/// and a mesh with too many triangles to reach [`LOD_MIN_TRIANGLES`] in [`MAX_LOD_LEVELS`]
/// halvings takes larger steps, down to a quarter.
const LOD_FINEST_STEP: f32 = 0.5;
const LOD_COARSEST_STEP: f32 = 0.25;

/// Weight of each normal component against position error (relative to the mesh's extent):
/// light, so that a level's error is its geometric error, and enough to keep hard edges and the
/// shape's larger curvature. Shading does not need more, since each level gets normals filtered
/// to its own scale ([`filtered_normals`]) rather than the full mesh's at the vertices it keeps.
const NORMAL_WEIGHT: f32 = 0.5;

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

/// A mesh's levels of detail as [`build_chain`] makes them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LodChain {
    /// The levels' own vertices, to append after the mesh's: copies of the vertices each level
    /// keeps, with normals filtered to the level's scale.
    pub vertices: Vec<Vertex>,
    /// Each level, coarser and coarser, as its indices (into the mesh's vertices followed by
    /// [`LodChain::vertices`]) and its object-space error.
    pub levels: Vec<(Vec<u32>, f32)>,
}

/// The simplified levels of the mesh with `vertices` and triangle list `indices` (level 0, the
/// mesh itself, not included). Empty where simplification does not pay.
pub fn build_chain(vertices: &[Vertex], indices: &[u32]) -> LodChain {
    let mut chain = LodChain::default();
    let triangles = indices.len() / 3;
    if triangles < 2 * LOD_MIN_TRIANGLES || vertices.is_empty() {
        return chain;
    }
    let Ok(adapter) = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(vertices), size_of::<Vertex>(), 0) else {
        return chain;
    };
    let normals: Vec<Vec3> = vertices.iter().map(|v| decode_octahedral(v.normal)).collect();
    let attributes: Vec<f32> = normals.iter().flat_map(|n| n.to_array()).collect();
    let areas = vertex_areas(vertices, indices);
    let locks = vec![false; vertices.len()];
    // meshoptimizer reports errors relative to the mesh's extent; this converts them to units.
    let scale = meshopt::simplify_scale(&adapter);
    let steps = (MAX_LOD_LEVELS - 1) as f32;
    let step =
        (LOD_MIN_TRIANGLES as f32 / triangles as f32).powf(1.0 / steps).clamp(LOD_COARSEST_STEP, LOD_FINEST_STEP);
    // Simplified over the mesh's own vertices, each level from the one before; only the result
    // is remapped to the level's copies.
    let mut current = indices.to_vec();
    let mut error = 0.0f32;
    while chain.levels.len() + 1 < MAX_LOD_LEVELS {
        let triangles = current.len() / 3;
        let target = (triangles as f32 * step) as usize;
        if target < LOD_FLOOR_TRIANGLES {
            break;
        }
        let mut step_error = 0.0f32;
        let next = meshopt::simplify_with_attributes_and_locks(
            &current,
            &adapter,
            &attributes,
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
        // A level further from the full mesh than a quarter of its extent has lost its shape:
        // only an instance of a pixel or two could take it.
        if error + step_error * scale > LOD_MAX_ERROR * scale {
            break;
        }
        // The error of each step is measured against the level before, so their sum bounds the
        // distance from the full mesh.
        error += step_error * scale;
        // The simplifier keeps its input's order; the post-transform cache wants its own.
        let next = meshopt::optimize_vertex_cache(&next, vertices.len());
        let level = level_vertices(
            vertices,
            &normals,
            &areas,
            &next,
            vertices.len() + chain.vertices.len(),
            &mut chain.vertices,
        );
        chain.levels.push((level, error));
        current = next;
    }
    chain
}

/// The vertices and levels that a mesh of `vertices` (checked) and `data`'s indices takes into
/// the pools: its vertices followed by its levels' copies, and its levels' indices and errors.
/// A deformed mesh, or one whose data asks for none, gets no chain.
pub(crate) fn with_chain(
    data: &super::MeshData,
    mut vertices: Vec<Vertex>,
    deformed: bool,
) -> (Vec<Vertex>, Vec<(Vec<u32>, f32)>) {
    if data.no_lod || deformed {
        return (vertices, Vec::new());
    }
    let chain = build_chain(&vertices, &data.indices);
    vertices.extend_from_slice(&chain.vertices);
    (vertices, chain.levels)
}

/// Each vertex's share of the surface: a third of the area of every triangle it is a corner of.
fn vertex_areas(vertices: &[Vertex], indices: &[u32]) -> Vec<f32> {
    let mut areas = vec![0.0f32; vertices.len()];
    for t in indices.chunks_exact(3) {
        let p = |k: usize| Vec3::from_array(vertices[t[k] as usize].position);
        let area = (p(1) - p(0)).cross(p(2) - p(0)).length() / 6.0;
        for &v in t {
            areas[v as usize] += area;
        }
    }
    areas
}

/// Copies the vertices that `level` (indices over `vertices`) keeps to `out`, their normals
/// filtered to the level's scale, and returns the level's indices over those copies, counted
/// from `base` (where the copies will start in the mesh's vertices).
fn level_vertices(
    vertices: &[Vertex],
    normals: &[Vec3],
    areas: &[f32],
    level: &[u32],
    base: usize,
    out: &mut Vec<Vertex>,
) -> Vec<u32> {
    let mut copy_of = FastMap::with_capacity_and_hasher(level.len() / 3, Default::default());
    let mut kept = Vec::new();
    let indices = level
        .iter()
        .map(|&v| {
            *copy_of.entry(v).or_insert_with(|| {
                kept.push(v);
                (base + kept.len() - 1) as u32
            })
        })
        .collect();
    let filtered = filtered_normals(vertices, normals, areas, &kept);
    out.extend(kept.iter().zip(filtered).map(|(&v, n)| {
        let mut vertex = vertices[v as usize];
        vertex.normal = encode_octahedral(n);
        // The tangent stays in the plane of the new normal, its handedness kept.
        let t = Vec4::from_array(vertex.tangent.map(|c| c as f32 / 32767.0));
        let along = (t.truncate() - n * n.dot(t.truncate())).normalize_or_zero();
        if along != Vec3::ZERO {
            vertex.tangent = encode_tangent(along.extend(t.w));
        }
        vertex
    }));
    indices
}

/// How far around a kept vertex the full mesh's normals are averaged, relative to the spacing of
/// the level's vertices: about the part of the surface nearest to it. Wider smooths away detail
/// the level still shows; narrower keeps the sub-pixel detail that the few vertices kept alias.
const FILTER_REACH: f32 = 0.5;

/// A vertex of the full mesh counts towards a kept vertex's normal only where their normals are
/// within this (cosine), so that the two sides of a thin part or of a hard edge stay apart.
const SAME_SURFACE: f32 = 0.3;

/// The normals a level's kept vertices (`kept`, indices into `vertices`) take: the area-weighted
/// mean of the full mesh's normals within half the spacing of the kept vertices around each, so
/// that shading shows what the full mesh averages to at the level's scale instead of the
/// sub-pixel detail of the few vertices kept. Copies of a vertex at a seam, having one normal,
/// get one.
fn filtered_normals(vertices: &[Vertex], normals: &[Vec3], areas: &[f32], kept: &[u32]) -> Vec<Vec3> {
    let position = |v: usize| Vec3::from_array(vertices[v].position);
    let surface: f32 = areas.iter().sum();
    let (low, high) = vertices.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(low, high), v| {
        let p = Vec3::from_array(v.position);
        (low.min(p), high.max(p))
    });
    // At most 2^20 cells along an axis, so that cell coordinates never saturate and pile the
    // vertices of a mesh of very uneven density into one cell.
    let reach =
        (FILTER_REACH * (surface / kept.len() as f32).sqrt()).max((high - low).max_element() / (1 << 20) as f32);
    if !(reach > 0.0 && reach.is_finite()) {
        return kept.iter().map(|&v| normals[v as usize]).collect();
    }
    // Cells as wide as the reach: every vertex within it lies in the surrounding 27.
    let key = |p: Vec3| ((p - low) / reach).floor().as_ivec3().to_array();
    let mut grid: FastMap<[i32; 3], Vec<u32>> = FastMap::with_capacity_and_hasher(kept.len(), Default::default());
    for (v, &area) in areas.iter().enumerate() {
        if area > 0.0 {
            grid.entry(key(position(v))).or_default().push(v as u32);
        }
    }
    kept.iter()
        .map(|&k| {
            let (own, p) = (normals[k as usize], position(k as usize));
            let [x, y, z] = key(p);
            let mut sum = Vec3::ZERO;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &v in grid.get(&[x + dx, y + dy, z + dz]).into_iter().flatten() {
                            let (v, n) = (v as usize, normals[v as usize]);
                            if n.dot(own) >= SAME_SURFACE && position(v).distance_squared(p) <= reach * reach {
                                sum += n * areas[v];
                            }
                        }
                    }
                }
            }
            sum.try_normalize().unwrap_or(own)
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::scene::MeshData;

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
        assert!(chain.levels.len() >= 3, "{} levels", chain.levels.len());
        let all = data.positions.len() + chain.vertices.len();
        let mut previous = (data.indices.len(), 0.0f32);
        for (indices, error) in &chain.levels {
            assert_eq!(indices.len() % 3, 0);
            assert!(indices.len() <= previous.0 * 6 / 10, "{} after {}", indices.len(), previous.0);
            assert!(indices.len() / 3 >= LOD_FLOOR_TRIANGLES);
            assert!(*error >= previous.1 && error.is_finite());
            // Each level draws its own copies of the vertices it keeps.
            assert!(indices.iter().all(|&i| (data.positions.len()..all).contains(&(i as usize))));
            previous = (indices.len(), *error);
        }
        // The coarsest level is still a sphere: its error (in the mesh's units) stays below a
        // tenth of the radius.
        assert!(previous.1 < 0.1, "error {}", previous.1);
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
            assert!(
                indices.iter().all(|&i| i as usize >= data.positions.len()),
                "a level drew the full mesh's vertices"
            );
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
        assert_eq!(build_chain(&soup, &sequential), LodChain::default());
        // Zero-area triangles among good ones: levels as usual, every index in range.
        let mut data = sphere(64, 128);
        let n = data.indices.len();
        for k in (0..n).step_by(30) {
            data.indices[k + 1] = data.indices[k];
        }
        let chain = build_chain(&vertices(&data), &data.indices);
        assert!(!chain.levels.is_empty());
        let all = data.positions.len() + chain.vertices.len();
        assert!(chain.levels.iter().all(|(i, e)| i.iter().all(|&v| (v as usize) < all) && e.is_finite()));
        assert!(chain.vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite())));
    }

    #[test]
    fn small_meshes_get_no_chain() {
        let data = sphere(4, 8);
        assert_eq!(build_chain(&vertices(&data), &data.indices), LodChain::default());
        assert_eq!(build_chain(&[], &[]), LodChain::default());
    }

    /// A sphere whose every vertex normal is tilted by a pattern finer than any level keeps.
    fn bumpy_normals(data: &MeshData) -> Vec<Vertex> {
        data.positions
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let tilt = if k % 2 == 0 { Vec3::X } else { -Vec3::X } * 0.4;
                Vertex {
                    position: p.to_array(),
                    normal: encode_octahedral((*p + tilt).normalize()),
                    ..Default::default()
                }
            })
            .collect()
    }

    /// A cube of side 2 whose faces are `n` x `n` grids of their own vertices (hard edges).
    fn cube(n: u32) -> (Vec<Vertex>, Vec<u32>) {
        let (mut vertices, mut indices) = (Vec::new(), Vec::new());
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let normal = Vec3::AXES[axis] * sign;
                let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3] * sign);
                let first = vertices.len() as u32;
                for i in 0..=n {
                    for j in 0..=n {
                        let (a, b) = (2.0 * i as f32 / n as f32 - 1.0, 2.0 * j as f32 / n as f32 - 1.0);
                        let p = normal + u * a + v * b;
                        vertices.push(Vertex {
                            position: p.to_array(),
                            normal: encode_octahedral(normal),
                            ..Default::default()
                        });
                    }
                }
                for i in 0..n {
                    for j in 0..n {
                        let at = |i: u32, j: u32| first + i * (n + 1) + j;
                        indices.extend([
                            at(i, j),
                            at(i + 1, j),
                            at(i + 1, j + 1),
                            at(i, j),
                            at(i + 1, j + 1),
                            at(i, j + 1),
                        ]);
                    }
                }
            }
        }
        (vertices, indices)
    }

    #[test]
    fn levels_shade_with_the_normals_their_surface_averages_to() {
        let data = sphere(64, 128);
        let vertices = bumpy_normals(&data);
        let chain = build_chain(&vertices, &data.indices);
        let (coarsest, _) = chain.levels.last().unwrap();
        let base = vertices.len();
        // The full mesh's normals swing 0.4 either way; the coarsest level's average them out
        // to the sphere's (a mutation keeping each kept vertex's own normal fails this).
        let worst = coarsest
            .iter()
            .map(|&i| {
                let v = chain.vertices[i as usize - base];
                decode_octahedral(v.normal).dot(Vec3::from_array(v.position).normalize())
            })
            .fold(1.0f32, f32::min);
        assert!(worst > 0.98, "a coarse normal is {:.1} degrees off the sphere's", worst.acos().to_degrees());
        // A hard edge stays: a cube's six faces keep their own normals at every level.
        let (vertices, indices) = cube(24);
        let chain = build_chain(&vertices, &indices);
        assert!(!chain.levels.is_empty());
        for v in &chain.vertices {
            let n = decode_octahedral(v.normal);
            assert!(n.abs().max_element() > 0.999, "normal {n} is not a face's");
        }
    }
}
