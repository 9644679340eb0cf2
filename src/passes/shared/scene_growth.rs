//! A changing world's scene grows in place: registering a mesh, material or texture, or
//! opening a new range of slots, writes only what changed into the scene's buffers.
//!
//! A world's scene is uploaded with room to grow in every buffer ([`with_room`]). Its successor
//! ([`GpuScene::grown`]) keeps each buffer that still holds what the world needs, so frames in
//! flight and the next one share it, and makes a larger one for each that does not, its
//! contents carried over on the GPU ([`Edits::carry`]): nothing is uploaded again from the host.
//! The caller then queues the changed parts (`write_*`), which land in the successor's buffers
//! at the next recorded frame, after the frames before it are done with what they overwrite.

use super::cull_data::{
    cluster_tables, gpu_levels, mesh_levels, GpuDrawGroup, GpuGroupBounds, GpuLodLevel, LEVELS_PER_MESH,
};
use super::gpu_types::GpuMaterial;
use super::scene_buffers::{drawn_triangles, max_mesh_triangles, GpuScene};
use super::slot_layout::SlotLayout;
use super::textures::GpuTextures;
use super::vertex_streams::{SurfaceVertex, VertexStreams, VERTEX_STRIDES};
use crate::gpu::{Buffer, BufferDesc, Edits, GpuContext, MemoryLocation};
use crate::scene::Scene;
use ash::vk;
use std::ops::Range;
use std::sync::Arc;

/// `bytes` with room to grow by half again (and a little more for tiny buffers), in whole
/// 256-byte blocks.
pub fn with_room(bytes: u64) -> u64 {
    (bytes + bytes / 2 + 256).next_multiple_of(256)
}

/// What every scene buffer may be used for beyond storage: carried into a successor, written.
fn usage(extra: vk::BufferUsageFlags) -> vk::BufferUsageFlags {
    extra
        | vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST
}

/// The byte offset of element `range.start` of a buffer of `T`.
fn at<T>(range: &Range<u32>) -> u64 {
    range.start as u64 * std::mem::size_of::<T>() as u64
}

impl GpuScene {
    /// The scene that `scene` (a changing world's scene in slot order, laid out in the same
    /// groups as this one) needs: this scene's buffers where they hold it, and larger ones
    /// where they do not, this one's contents carried over by `edits`. Its textures are
    /// `textures`. `meshes_changed`: meshes were registered or unregistered, so the cluster
    /// tables are made again and queued whole (otherwise they are this scene's). What else
    /// changed is still to be written (`write_*`).
    pub fn grown(
        &self,
        ctx: &GpuContext,
        scene: &Scene,
        textures: Arc<GpuTextures>,
        meshes_changed: bool,
        edits: &mut Edits,
    ) -> crate::Result<Self> {
        let mut fit = |old: &Arc<Buffer>, needed: u64, extra: vk::BufferUsageFlags| -> crate::Result<Arc<Buffer>> {
            if needed <= old.size() {
                return Ok(old.clone());
            }
            let desc = BufferDesc {
                name: old.name(),
                size: with_room(needed),
                usage: usage(extra),
                location: MemoryLocation::GpuOnly,
            };
            let new = Arc::new(Buffer::new(ctx, &desc)?);
            edits.carry(old.clone(), &new, old.size());
            Ok(new)
        };
        super::scene_buffers::check_index_range(scene, ctx.caps().limits.max_draw_indexed_index_value)?;
        super::instance_ranges::check_instance_count(scene.instances.len() as u64, &ctx.caps().limits)?;
        let tables = meshes_changed.then(|| cluster_tables(scene));
        let slots = scene.instances.len() as u64;
        let size_of = |n: u64, one: usize| n * one as u64;
        let none = vk::BufferUsageFlags::empty();
        let instances =
            fit(&self.instances, size_of(slots, std::mem::size_of::<super::gpu_types::GpuInstance>()), none)?;
        let prev_instances = match &self.prev_instances {
            Some(previous) => Some(fit(previous, instances.size(), none)?),
            None => None,
        };
        let user_data = match &self.user_data {
            Some(data) => Some(fit(data, size_of(slots, 4 * self.user_words as usize), none)?),
            None => None,
        };
        let cull_records =
            fit(&self.cull_records, size_of(slots, std::mem::size_of::<super::cull_data::GpuCullRecord>()), none)?;
        let next = Self {
            user_data,
            user_words: self.user_words,
            vertices: {
                let n = scene.vertices.len() as u64;
                let mut stream = |old, stride: u32| fit(old, n * stride as u64, vk::BufferUsageFlags::VERTEX_BUFFER);
                VertexStreams {
                    positions: stream(&self.vertices.positions, VERTEX_STRIDES[0])?,
                    normals: stream(&self.vertices.normals, VERTEX_STRIDES[1])?,
                    surface: stream(&self.vertices.surface, VERTEX_STRIDES[2])?,
                }
            },
            indices: fit(&self.indices, size_of(scene.indices.len() as u64, 4), vk::BufferUsageFlags::INDEX_BUFFER)?,
            prev_positions: fit(&self.prev_positions, size_of(scene.vertices.len() as u64, 12), none)?,
            instances,
            prev_instances,
            materials: fit(
                &self.materials,
                size_of(scene.materials.len() as u64, std::mem::size_of::<GpuMaterial>()),
                none,
            )?,
            draw_instance_ids: fit(&self.draw_instance_ids, size_of(slots, 4), none)?,
            draw_commands: self.draw_commands.clone(),
            draw_count: self.draw_count.clone(),
            regions: self.regions,
            cull_records: cull_records.clone(),
            // The block bounds have room for a block per slot the records have room for, and the
            // slots added since are written by updates, which mark their blocks. Records moved
            // to a larger buffer go without: every slot is tested.
            block_bounds: self.block_bounds.clone().filter(|_| Arc::ptr_eq(&cull_records, &self.cull_records)),
            draw_groups: self.draw_groups.clone(),
            group_order: self.group_order.clone(),
            groups_out_of_slot_order: self.groups_out_of_slot_order,
            group_bounds: self.group_bounds.clone(),
            // The cluster tables change only with the meshes (written whole below).
            clusters: match &tables {
                Some(t) => fit(&self.clusters, std::mem::size_of_val(t.clusters.as_slice()) as u64, none)?,
                None => self.clusters.clone(),
            },
            cluster_ranges: match &tables {
                Some(t) => fit(&self.cluster_ranges, std::mem::size_of_val(t.ranges.as_slice()) as u64, none)?,
                None => self.cluster_ranges.clone(),
            },
            cluster_meshes: match &tables {
                Some(t) => fit(&self.cluster_meshes, std::mem::size_of_val(t.meshes.as_slice()) as u64, none)?,
                None => self.cluster_meshes.clone(),
            },
            clustered_meshes: tables.as_ref().map_or(self.clustered_meshes, |t| t.clustered_meshes()),
            lod_levels: fit(
                &self.lod_levels,
                size_of(scene.meshes.len() as u64 * LEVELS_PER_MESH as u64, std::mem::size_of::<GpuLodLevel>()),
                none,
            )?,
            instance_triangles: fit(&self.instance_triangles, size_of(slots, 8), none)?,
            textures,
            instance_count: slots as u32,
            binding_range: self.binding_range,
            triangles: drawn_triangles(scene),
            max_mesh_triangles: max_mesh_triangles(scene),
            emission_or_occlusion: scene.has_emission_or_occlusion(),
            alpha_masks: scene.has_alpha_masks(),
            textured: scene.samples_textures(),
        };
        if let Some(t) = tables {
            edits.write(&next.clusters, 0, bytemuck::cast_slice(&t.clusters));
            edits.write(&next.cluster_ranges, 0, bytemuck::cast_slice(&t.ranges));
            edits.write(&next.cluster_meshes, 0, bytemuck::cast_slice(&t.meshes));
        }
        Ok(next)
    }

    /// Queues mesh `mesh` of `scene` (its vertices, its indices and its levels of detail's)
    /// into the pools, and its levels into the level table.
    pub fn write_mesh(&self, edits: &mut Edits, scene: &Scene, mesh: u32) {
        let m = &scene.meshes[mesh as usize];
        let vertices = m.vertex_offset..m.vertex_offset + m.vertex_count;
        let indices = m.first_index..m.first_index + m.index_span();
        let levels = mesh_levels(mesh)..mesh_levels(mesh) + m.lods.len() as u32;
        edits.write(&self.lod_levels, at::<GpuLodLevel>(&levels), bytemuck::cast_slice(&gpu_levels(m)));
        let (positions, normals, surface) =
            super::vertex_streams::split(&scene.vertices[vertices.start as usize..vertices.end as usize]);
        edits.write(&self.vertices.positions, at::<[f32; 3]>(&vertices), bytemuck::cast_slice(&positions));
        edits.write(&self.vertices.normals, at::<[i16; 2]>(&vertices), bytemuck::cast_slice(&normals));
        edits.write(&self.vertices.surface, at::<SurfaceVertex>(&vertices), bytemuck::cast_slice(&surface));
        edits.write(
            &self.indices,
            at::<u32>(&indices),
            bytemuck::cast_slice(&scene.indices[indices.start as usize..indices.end as usize]),
        );
    }

    /// Queues draw group `g` of `layout` (its command, its culling entry and local bounds, and
    /// its slots' triangle bases) as `scene` has its mesh.
    pub fn write_group(&self, edits: &mut Edits, scene: &Scene, layout: &SlotLayout, g: usize) {
        let command = layout.command(g, scene);
        let group = layout.groups[g];
        let index = g as u32..g as u32 + 1;
        edits.write(
            &self.draw_commands,
            at::<super::gpu_types::DrawIndexedIndirect>(&index),
            bytemuck::bytes_of(&command),
        );
        let record = match group.spare() {
            true => GpuDrawGroup::of(&command),
            false => GpuDrawGroup::with_levels(&command, scene, group.key.1, group.key.0),
        };
        edits.write(&self.draw_groups, at::<GpuDrawGroup>(&index), bytemuck::bytes_of(&record));
        if group.spare() {
            return;
        }
        let mesh = &scene.meshes[group.key.1 as usize];
        edits.write(&self.group_bounds, at::<GpuGroupBounds>(&index), bytemuck::bytes_of(&GpuGroupBounds::of(mesh)));
        let slots = group.first_slot..group.first_slot + group.capacity;
        let bases = vec![[mesh.first_index, mesh.vertex_offset]; group.capacity as usize];
        edits.write(&self.instance_triangles, at::<[u32; 2]>(&slots), bytemuck::cast_slice(&bases));
    }

    /// Queues the order of `layout`'s groups by slot ([`super::cull_data::slot_order`]), after
    /// groups were opened.
    pub fn write_group_order(&mut self, edits: &mut Edits, layout: &SlotLayout) {
        let (order, out_of_order) =
            super::cull_data::slot_order(layout.groups.iter().map(|g| (g.first_slot, g.capacity)));
        edits.write(&self.group_order, 0, bytemuck::cast_slice(&order));
        self.groups_out_of_slot_order = out_of_order;
    }

    /// Queues the draw-list entries of new slots `slots` (slot `s` draws record `s`).
    pub fn write_slot_ids(&self, edits: &mut Edits, slots: Range<u32>) {
        let ids: Vec<u32> = slots.clone().collect();
        edits.write(&self.draw_instance_ids, at::<u32>(&slots), bytemuck::cast_slice(&ids));
    }

    /// Queues material `material` of `scene`, its textures where [`GpuScene::textures`] has them.
    pub fn write_material(&self, edits: &mut Edits, scene: &Scene, material: u32) {
        let record = GpuMaterial::new(&scene.materials[material as usize], self.textures.placements());
        let index = material..material + 1;
        edits.write(&self.materials, at::<GpuMaterial>(&index), bytemuck::bytes_of(&record));
    }
}
