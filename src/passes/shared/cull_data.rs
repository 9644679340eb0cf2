//! What the culling passes read about the scene: one bound per *slot* (instances sorted by draw
//! group, each group in spatial order, the same order as the unculled draw list) and one entry
//! per draw group. Uploaded once; the passes never touch the full instance records.

use super::gpu_types::{split_hi_lo, DrawIndexedIndirect};
use super::scene_buffers::DrawList;
use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Vec3};
use half::f16;

/// World bound of one slot (32 bytes; `CullRecord` in `shaders/cull/cull_common.glsl`).
///
/// The sphere and the box share their center (the mesh's local box center, transformed); the
/// radius is widened to contain the local sphere around that center, then scaled by the
/// largest axis scale, so both stay conservative for any affine transform. The center's lo part,
/// the radius and the half extents are half floats: rounded outward, and the radius and extents
/// grow by the lo part's rounding error, so the bound the GPU reads contains the exact one.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuCullRecord {
    /// World center, hi part (f32 bits).
    pub center_hi: [u32; 3],
    /// Draw group (low 24 bits) | instance flags (7 bits) << 24 | [`CULL_HUGE`].
    pub group_flags: u32,
    /// f16 lo x, f16 lo y.
    pub lo_xy: u32,
    /// f16 lo z, f16 radius.
    pub lo_z_radius: u32,
    /// f16 half extents x, y.
    pub half_xy: u32,
    /// f16 half extent z.
    pub half_z: u32,
}

/// Set on a record whose bound does not fit half floats: the GPU keeps it without testing.
pub const CULL_HUGE: u32 = 0x8000_0000;

impl GpuCullRecord {
    /// Packs a bound: world center (hi + lo), radius, half extents.
    pub fn new(hi: Vec3, lo: Vec3, radius: f32, half: Vec3, group: u32, flags: u32) -> Self {
        let lo16 = lo.to_array().map(f16::from_f32);
        // How far the stored lo part is from the true one: the bound grows by that much.
        let err = lo.to_array().iter().zip(&lo16).map(|(l, h)| (l - h.to_f32()).abs()).fold(0.0f32, f32::max);
        let radius16 = f16_up(radius + err);
        let half16 = half.to_array().map(|h| f16_up(h + err));
        let huge =
            !radius16.is_finite() || half16.iter().any(|h| !h.is_finite()) || lo16.iter().any(|l| !l.is_finite());
        let pack = |a: f16, b: f16| a.to_bits() as u32 | (b.to_bits() as u32) << 16;
        Self {
            center_hi: hi.to_array().map(f32::to_bits),
            group_flags: (group & 0xFF_FFFF) | ((flags & 0x7F) << 24) | if huge { CULL_HUGE } else { 0 },
            lo_xy: pack(lo16[0], lo16[1]),
            lo_z_radius: pack(lo16[2], radius16),
            half_xy: pack(half16[0], half16[1]),
            half_z: pack(half16[2], f16::ZERO),
        }
    }

    /// The bound as the GPU reads it: (center hi, center lo, radius, half extents).
    pub fn unpack(&self) -> (Vec3, Vec3, f32, Vec3) {
        let half =
            |bits: u32, high: bool| f16::from_bits(if high { (bits >> 16) as u16 } else { bits as u16 }).to_f32();
        (
            Vec3::from_array(self.center_hi.map(f32::from_bits)),
            Vec3::new(half(self.lo_xy, false), half(self.lo_xy, true), half(self.lo_z_radius, false)),
            half(self.lo_z_radius, true),
            Vec3::new(half(self.half_xy, false), half(self.half_xy, true), half(self.half_z, false)),
        )
    }
}

/// The smallest half float not below `x` (infinity past 65504).
fn f16_up(x: f32) -> f16 {
    let h = f16::from_f32(x);
    if h.to_f32() >= x || !h.is_finite() {
        h
    } else {
        f16::from_bits(h.to_bits() + 1)
    }
}

/// One draw group (32 bytes; `DrawGroup` in `cull_common.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuDrawGroup {
    /// First slot of the group.
    pub first_slot: u32,
    /// Number of slots (instances) in the group.
    pub slot_count: u32,
    /// Indices per instance.
    pub index_count: u32,
    /// First index in the pool.
    pub first_index: u32,
    /// Vertex offset.
    pub vertex_offset: i32,
    /// The group's first level of detail past the full mesh in [`CullData::lods`].
    pub lod_first: u32,
    /// Its levels past the full mesh (0: always drawn whole).
    pub lod_count: u32,
    /// Padding.
    pub pad: u32,
}

/// One level of detail of a draw group's mesh past the full one (16 bytes; `LodLevel` in
/// `cull_common.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLodLevel {
    /// First index in the pool.
    pub first_index: u32,
    /// Indices per instance.
    pub index_count: u32,
    /// The level's object-space error over the radius of the mesh's cull sphere: times an
    /// instance's cull radius (which is that radius times the instance's largest axis scale),
    /// its error in world units.
    pub relative_error: f32,
    /// Padding.
    pub pad: u32,
}

/// The local bounds of one draw group's mesh (32 bytes; `GroupBounds` in
/// `shaders/world/scatter.comp`, which derives a moved instance's cull bound from them).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuGroupBounds {
    /// Local box center.
    pub center: [f32; 3],
    /// Radius of the local sphere around the box center.
    pub radius: f32,
    /// Local box half extents.
    pub half_extent: [f32; 3],
    /// Padding.
    pub pad: f32,
}

impl GpuDrawGroup {
    /// The group that unculled draw command `command` draws (always whole: no levels).
    pub fn of(command: &DrawIndexedIndirect) -> Self {
        Self {
            first_slot: command.first_instance,
            slot_count: command.instance_count,
            index_count: command.index_count,
            first_index: command.first_index,
            vertex_offset: command.vertex_offset,
            lod_first: 0,
            lod_count: 0,
            pad: 0,
        }
    }

    /// The group of `command`, which draws mesh `mesh` of `scene` in face-cull region `region`:
    /// with the mesh's levels of detail, except for transparent instances (always drawn whole,
    /// [`super::face_cull::lod_commands`]).
    pub fn with_levels(command: &DrawIndexedIndirect, scene: &crate::scene::Scene, mesh: u32, region: usize) -> Self {
        let mut group = Self::of(command);
        if region != super::face_cull::FaceCull::Blended as usize {
            group.lod_first = mesh_levels(mesh);
            group.lod_count = scene.meshes[mesh as usize].lods.len() as u32;
        }
        group
    }
}

/// Entries of the level table each mesh owns: its levels past the full mesh, at most.
pub const LEVELS_PER_MESH: u32 = crate::scene::MAX_LOD_LEVELS as u32 - 1;

/// Where mesh `mesh`'s levels of detail start in the level table ([`CullData::lods`]): a fixed
/// stride per mesh, so that a live world's registered meshes write theirs in place.
pub fn mesh_levels(mesh: u32) -> u32 {
    mesh * LEVELS_PER_MESH
}

/// The level-table entries of `mesh`'s levels of detail past the full mesh.
pub fn gpu_levels(mesh: &crate::scene::Mesh) -> Vec<GpuLodLevel> {
    let radius = local_radius(mesh);
    mesh.lods
        .iter()
        .map(|l| GpuLodLevel {
            first_index: l.first_index,
            index_count: l.index_count,
            // Rounded up, so that the error read is never below the true one.
            relative_error: (l.error / radius) * (1.0 + f32::EPSILON * 4.0),
            pad: 0,
        })
        .collect()
}

/// One cluster of a mesh level (64 bytes; `Cluster` in `shaders/cluster_cull/cluster_cull.comp`),
/// in the mesh's local space.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCluster {
    /// Bounding sphere centre.
    pub center: [f32; 3],
    /// Its radius.
    pub radius: f32,
    /// Apex of the normal cone.
    pub cone_apex: [f32; 3],
    /// The cone's cutoff ([`crate::scene::clusters::Cluster::cone_cutoff`]).
    pub cone_cutoff: f32,
    /// The cone's axis.
    pub cone_axis: [f32; 3],
    /// First index in the pool.
    pub first_index: u32,
    /// Number of indices.
    pub index_count: u32,
    /// Padding.
    pub pad: [u32; 3],
}

/// Entries of the cluster-range table each mesh owns: one per level, the full mesh's first.
pub const CLUSTER_RANGES_PER_MESH: u32 = crate::scene::MAX_LOD_LEVELS as u32;

/// The cluster pass's view of a scene's clusters ([`cluster_tables`]).
pub struct ClusterTables {
    /// Every mesh's clusters, level after level.
    pub clusters: Vec<GpuCluster>,
    /// At `mesh * CLUSTER_RANGES_PER_MESH + level`, the level's first cluster and its count (0:
    /// drawn whole).
    pub ranges: Vec<[u32; 2]>,
    /// The meshes with clusters as (vertex offset, mesh), by vertex offset: a draw command
    /// names its mesh by its vertex offset, which no two meshes share.
    pub meshes: Vec<[u32; 2]>,
}

impl ClusterTables {
    /// Meshes with clusters (the entries of `meshes` but the placeholder of a scene without).
    pub fn clustered_meshes(&self) -> u32 {
        self.meshes.iter().filter(|m| m[1] != u32::MAX).count() as u32
    }
}

/// The cluster tables of `scene` (each at least one entry, so that the buffers exist).
pub fn cluster_tables(scene: &crate::scene::Scene) -> ClusterTables {
    let mut clusters = Vec::new();
    let mut ranges = vec![[0u32; 2]; (scene.meshes.len() * CLUSTER_RANGES_PER_MESH as usize).max(1)];
    for (m, mesh) in scene.meshes.iter().enumerate() {
        for (level, list) in mesh.clusters.iter().enumerate().take(CLUSTER_RANGES_PER_MESH as usize) {
            ranges[m * CLUSTER_RANGES_PER_MESH as usize + level] = [clusters.len() as u32, list.len() as u32];
            clusters.extend(list.iter().map(|c| GpuCluster {
                center: c.center.to_array(),
                radius: c.radius,
                cone_apex: c.cone_apex.to_array(),
                cone_cutoff: c.cone_cutoff,
                cone_axis: c.cone_axis.to_array(),
                first_index: c.first_index,
                index_count: c.index_count,
                pad: [0; 3],
            }));
        }
    }
    if clusters.is_empty() {
        clusters.push(GpuCluster::default());
    }
    let mut meshes: Vec<[u32; 2]> = (0..scene.meshes.len() as u32)
        .filter(|&m| !scene.meshes[m as usize].clusters.is_empty())
        .map(|m| [scene.meshes[m as usize].vertex_offset, m])
        .collect();
    meshes.sort_unstable();
    if meshes.is_empty() {
        meshes.push([u32::MAX, u32::MAX]);
    }
    ClusterTables { clusters, ranges, meshes }
}

/// The most clusters one instance of `mesh` may draw: its richest level's.
pub fn mesh_clusters(mesh: &crate::scene::Mesh) -> u32 {
    mesh.clusters.iter().map(|l| l.len() as u32).max().unwrap_or(0)
}

/// The level table of `scene`: [`LEVELS_PER_MESH`] entries per mesh (at least one entry, so
/// that the buffer exists).
pub fn level_table(scene: &crate::scene::Scene) -> Vec<GpuLodLevel> {
    let mut table = vec![GpuLodLevel::default(); (scene.meshes.len() * LEVELS_PER_MESH as usize).max(1)];
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let first = mesh_levels(m as u32) as usize;
        for (entry, level) in table[first..].iter_mut().zip(gpu_levels(mesh)) {
            *entry = level;
        }
    }
    table
}

impl GpuGroupBounds {
    /// The local bounds of `mesh`.
    pub fn of(mesh: &crate::scene::Mesh) -> Self {
        Self {
            center: mesh.bounds.center().to_array(),
            radius: local_radius(mesh),
            half_extent: mesh.bounds.half_extent().to_array(),
            pad: 0.0,
        }
    }
}

/// The draw groups given as (first slot, slots) in the order of their slots: the groups with
/// slots by first slot, then the others (which draw nothing), each set in group order; and
/// whether that order differs from the groups' own for the groups with slots. A changing
/// world's group that grows takes slots after every other group's while its command stays in
/// its region, so a world whose groups grew in several regions has them out of order.
pub fn slot_order(groups: impl Iterator<Item = (u32, u32)>) -> (Vec<u32>, bool) {
    let groups: Vec<(u32, u32)> = groups.collect();
    let mut order: Vec<u32> = (0..groups.len() as u32).collect();
    order.sort_by_key(|&g| {
        let (first_slot, slots) = groups[g as usize];
        (slots == 0, if slots == 0 { 0 } else { first_slot }, g)
    });
    let with_slots = order.iter().take_while(|&&g| groups[g as usize].1 != 0);
    let in_order = with_slots.clone().zip(with_slots.skip(1)).all(|(a, b)| a < b);
    (order, !in_order)
}

/// The culling view of the scene.
pub struct CullData {
    /// One record per slot.
    pub records: Vec<GpuCullRecord>,
    /// One entry per draw group, in draw-list order (a changing world's reserved groups are empty).
    pub groups: Vec<GpuDrawGroup>,
    /// The local bounds of each group's mesh.
    pub bounds: Vec<GpuGroupBounds>,
    /// The meshes' levels of detail past the full mesh ([`level_table`]).
    pub lods: Vec<GpuLodLevel>,
}

impl CullData {
    /// Bounds and groups of `scene`, slots in the order of `draws`.
    pub fn new(scene: &Scene, draws: &DrawList) -> Self {
        let (mut data, group_of_slot) = Self::without_records(scene, draws);
        data.records = draws
            .instance_ids
            .iter()
            .zip(group_of_slot.iter())
            .map(|(&id, &group)| cull_record(scene, &scene.instances[id as usize], group))
            .collect();
        data
    }

    /// As [`CullData::new`] without the records (left empty), and the draw group of each slot,
    /// from which [`cull_record`] makes them: for an upload that writes the records straight
    /// into upload memory.
    pub fn without_records(scene: &Scene, draws: &DrawList) -> (Self, Vec<u32>) {
        let mut group_of_slot = vec![0u32; draws.instance_ids.len()];
        let groups: Vec<GpuDrawGroup> = draws
            .commands
            .iter()
            .enumerate()
            .map(|(g, c)| {
                for slot in c.first_instance..c.first_instance + c.instance_count {
                    group_of_slot[slot as usize] = g as u32;
                }
                if c.instance_count == 0 {
                    return GpuDrawGroup::of(c);
                }
                let mesh = scene.instances[draws.instance_ids[c.first_instance as usize] as usize].mesh;
                GpuDrawGroup::with_levels(c, scene, mesh, draws.regions.region_of(g as u32))
            })
            .collect();
        let lods = level_table(scene);
        let bounds = draws
            .commands
            .iter()
            .map(|c| {
                // A changing world's reserved groups hold no slots and no mesh.
                if c.instance_count == 0 {
                    return GpuGroupBounds::default();
                }
                let inst = &scene.instances[draws.instance_ids[c.first_instance as usize] as usize];
                GpuGroupBounds::of(&scene.meshes[inst.mesh as usize])
            })
            .collect();
        (Self { records: Vec::new(), groups, bounds, lods }, group_of_slot)
    }
}

/// The cull record of `inst` (an instance of `scene`) in draw group `group`.
pub fn cull_record(scene: &Scene, inst: &crate::scene::Instance, group: u32) -> GpuCullRecord {
    let mesh = &scene.meshes[inst.mesh as usize];
    let linear = inst.transform.linear;
    let center = inst.transform.apply(mesh.bounds.center());
    let (hi, lo) = split_hi_lo(center);
    let abs = Mat3::from_cols(linear.x_axis.abs(), linear.y_axis.abs(), linear.z_axis.abs());
    let half = abs.mul_vec3(mesh.bounds.half_extent());
    let max_scale = linear.x_axis.length().max(linear.y_axis.length()).max(linear.z_axis.length());
    GpuCullRecord::new(hi, lo, local_radius(mesh) * max_scale, widen(half), group, inst.flags)
}

/// The radius of the sphere around `mesh`'s box center that contains its bounding sphere.
fn local_radius(mesh: &crate::scene::Mesh) -> f32 {
    mesh.sphere.center.distance(mesh.bounds.center()) + mesh.sphere.radius
}

/// One part in 2^20 more, so that the f32 box of a rotated instance never ends inside a vertex.
fn widen(v: Vec3) -> Vec3 {
    v * (1.0 + 1.0 / 1_048_576.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Instance, MeshData, Transform};
    use glam::{DVec3, Quat};

    #[test]
    fn groups_are_ordered_by_their_slots_with_empty_ones_last() {
        // Laid out in order, with empty (reserved) groups between regions.
        let (order, out) = slot_order([(0, 4), (4, 4), (0, 0), (8, 2), (0, 0)].into_iter());
        assert_eq!((order, out), (vec![0, 1, 3, 2, 4], false));
        // Group 1 grew after group 3: its slots come last.
        let (order, out) = slot_order([(0, 4), (10, 4), (0, 0), (4, 6)].into_iter());
        assert_eq!((order, out), (vec![0, 3, 1, 2], true));
    }

    #[test]
    fn half_float_bounds_round_outward_and_flag_huge_ones() {
        let r = GpuCullRecord::new(
            Vec3::new(1.0e7, 0.0, 3.0),
            Vec3::new(0.3333, -0.1, 0.0),
            1.0001,
            Vec3::new(0.1, 7.77, 1.0e-6),
            5,
            1,
        );
        let (_, lo, radius, half) = r.unpack();
        let err = (lo - Vec3::new(0.3333, -0.1, 0.0)).abs().max_element();
        assert!(radius >= 1.0001 + err && half.x >= 0.1 + err && half.y >= 7.77 + err && half.z >= 1.0e-6);
        assert_eq!(r.group_flags, 5 | 1 << 24);
        let huge = GpuCullRecord::new(Vec3::ZERO, Vec3::ZERO, 1.0e5, Vec3::splat(1.0e5), 0, 0);
        assert_eq!(huge.group_flags & CULL_HUGE, CULL_HUGE);
    }

    #[test]
    fn records_follow_the_draw_list_and_contain_every_vertex() {
        let mut scene = Scene::default();
        let tri = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X * 2.0, Vec3::Y],
            normals: vec![],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        let a = scene.add_mesh("a", &tri, "a").unwrap();
        let b = scene.add_mesh("b", &tri, "b").unwrap();
        scene.add_material(Default::default());
        let rot = Mat3::from_quat(Quat::from_rotation_z(0.7)) * Mat3::from_diagonal(Vec3::new(-3.0, 0.5, 2.0));
        for (i, mesh) in [b, a, b, a].into_iter().enumerate() {
            let transform = Transform { linear: rot, translation: DVec3::new(1.0e7 + i as f64, -5.0, 3.0) };
            scene.instances.push(Instance { transform, mesh, material: 0, flags: if i == 2 { 1 } else { 0 } });
        }
        let draws = DrawList::all_instances(&scene);
        let data = CullData::new(&scene, &draws);
        assert_eq!(draws.instance_ids, [1, 3, 0, 2]);
        assert_eq!(data.records.iter().map(|r| r.group_flags).collect::<Vec<_>>(), [0, 0, 1, 1 | 1 << 24]);
        assert_eq!((data.groups[1].first_slot, data.groups[1].slot_count), (2, 2));
        for (r, &id) in data.records.iter().zip(&draws.instance_ids) {
            let inst = &scene.instances[id as usize];
            let (hi, lo, radius, half) = r.unpack();
            let c = hi.as_dvec3() + lo.as_dvec3();
            for p in &tri.positions {
                let w = inst.transform.apply(*p);
                let d = (w - c).abs();
                assert!(d.cmple(half.as_dvec3()).all(), "{w} outside the box");
                assert!((w - c).length() <= radius as f64, "{w} outside the sphere");
            }
        }
    }
}
