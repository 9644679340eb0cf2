//! What the culling passes read about the scene: one bound per *slot* (instances sorted by draw
//! group, each group in instance order, the same order as the unculled draw list) and one entry
//! per draw group. Uploaded once; the passes never touch the full instance records.

use super::gpu_types::split_hi_lo;
use super::scene_buffers::DrawList;
use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Vec3};

/// World bound of one slot (48 bytes; `CullRecord` in `shaders/cull/cull_common.glsl`).
///
/// The sphere and the box share their center (the mesh's local box center, transformed); the
/// radius is widened to contain the local sphere around that center, then scaled by the
/// largest axis scale, so both stay conservative for any affine transform.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCullRecord {
    /// World center, hi part.
    pub center_hi: [f32; 3],
    /// Bounding-sphere radius.
    pub radius: f32,
    /// World center, lo part.
    pub center_lo: [f32; 3],
    /// Scene instance id (what the draw list stores).
    pub instance: u32,
    /// Half extents of the world axis-aligned box.
    pub half_extent: [f32; 3],
    /// Draw group (low 24 bits) | instance flags << 24.
    pub group_flags: u32,
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
    /// Padding.
    pub pad: [u32; 3],
}

/// The culling view of the scene.
pub struct CullData {
    /// One record per slot.
    pub records: Vec<GpuCullRecord>,
    /// One entry per non-empty draw group, in draw-list order.
    pub groups: Vec<GpuDrawGroup>,
    /// The draw group of each slot (what the scatter step reads instead of whole records).
    pub slot_groups: Vec<u32>,
}

impl CullData {
    /// Bounds and groups of `scene`, slots in the order of `draws`.
    pub fn new(scene: &Scene, draws: &DrawList) -> Self {
        let mut group_of_slot = vec![0u32; draws.instance_ids.len()];
        let groups: Vec<GpuDrawGroup> = draws
            .commands
            .iter()
            .enumerate()
            .map(|(g, c)| {
                for slot in c.first_instance..c.first_instance + c.instance_count {
                    group_of_slot[slot as usize] = g as u32;
                }
                GpuDrawGroup {
                    first_slot: c.first_instance,
                    slot_count: c.instance_count,
                    index_count: c.index_count,
                    first_index: c.first_index,
                    vertex_offset: c.vertex_offset,
                    pad: [0; 3],
                }
            })
            .collect();
        let records = draws
            .instance_ids
            .iter()
            .zip(group_of_slot.iter())
            .map(|(&id, &group)| {
                let inst = &scene.instances[id as usize];
                let mesh = &scene.meshes[inst.mesh as usize];
                let linear = inst.transform.linear;
                let center = inst.transform.apply(mesh.bounds.center());
                let (hi, lo) = split_hi_lo(center);
                let abs = Mat3::from_cols(linear.x_axis.abs(), linear.y_axis.abs(), linear.z_axis.abs());
                let half = abs.mul_vec3(mesh.bounds.half_extent());
                let max_scale = linear.x_axis.length().max(linear.y_axis.length()).max(linear.z_axis.length());
                let local_radius = mesh.sphere.center.distance(mesh.bounds.center()) + mesh.sphere.radius;
                GpuCullRecord {
                    center_hi: hi.to_array(),
                    radius: local_radius * max_scale,
                    center_lo: lo.to_array(),
                    instance: id,
                    half_extent: widen(half).to_array(),
                    group_flags: (group & 0xFF_FFFF) | (inst.flags << 24),
                }
            })
            .collect();
        Self { records, groups, slot_groups: group_of_slot }
    }
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
    fn records_follow_the_draw_list_and_contain_every_vertex() {
        let mut scene = Scene::default();
        let tri =
            MeshData { positions: vec![Vec3::ZERO, Vec3::X * 2.0, Vec3::Y], normals: vec![], indices: vec![0, 1, 2] };
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
        assert_eq!(data.records.iter().map(|r| r.instance).collect::<Vec<_>>(), [1, 3, 0, 2]);
        assert_eq!(data.records.iter().map(|r| r.group_flags).collect::<Vec<_>>(), [0, 0, 1, 1 | 1 << 24]);
        assert_eq!((data.groups[1].first_slot, data.groups[1].slot_count), (2, 2));
        for r in &data.records {
            let inst = &scene.instances[r.instance as usize];
            let c = DVec3::from_array(r.center_hi.map(f64::from)) + DVec3::from_array(r.center_lo.map(f64::from));
            for p in &tri.positions {
                let w = inst.transform.apply(*p);
                let d = (w - c).abs();
                assert!(d.cmple(DVec3::from_array(r.half_extent.map(f64::from))).all(), "{w} outside the box");
                assert!((w - c).length() <= r.radius as f64, "{w} outside the sphere");
            }
        }
    }
}
