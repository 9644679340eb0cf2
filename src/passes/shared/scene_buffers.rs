//! The scene on the GPU: vertex/index pools, instances, materials, and the draw list that the
//! indirect draws consume.

use super::face_cull::{self, DrawRegions, FaceCull, FACE_CULL_REGIONS};
use super::gpu_types::{DrawIndexedIndirect, GpuInstance, GpuMaterial};
use super::instance_ranges;
use super::textures::GpuTextures;
use super::vertex_streams::VertexStreams;
use crate::gpu::{Bind, Buffer, GpuContext, UploadBatch};
use crate::scene::Scene;
use ash::vk;
use std::sync::Arc;

/// Scene buffers on the device (a clone shares them).
#[derive(Clone)]
pub struct GpuScene {
    /// Shared vertex pool ([`crate::scene::Vertex`]), in streams by what passes read.
    pub vertices: VertexStreams,
    /// Shared index pool (u32).
    pub indices: Arc<Buffer>,
    /// [`GpuInstance`] per scene instance, in scene order.
    pub instances: Arc<Buffer>,
    /// Each instance's record as the previous frame of the world had it, for motion vectors:
    /// kept by a changing world's renderer ([`GpuScene::add_previous_instances`]); `None` for a
    /// scene that never moves, whose previous transforms are its current ones
    /// ([`GpuScene::previous_instances`]).
    pub prev_instances: Option<Arc<Buffer>>,
    /// Each pool vertex's position (`vec3`) as the previous frame drew it, for motion vectors:
    /// the rest position, or for a posed instance's copy of its mesh the position of its
    /// previous pose (written by the world's deformation, `shaders/world/deform.comp`).
    pub prev_positions: Arc<Buffer>,
    /// [`GpuMaterial`] per material.
    pub materials: Arc<Buffer>,
    /// Instance ids grouped by draw group (face cull, mesh), each group in spatial order (Morton
    /// order of the instances' origins, equal codes in instance order).
    pub draw_instance_ids: Arc<Buffer>,
    /// One [`DrawIndexedIndirect`] per draw group (empty for a changing world's reserved groups).
    pub draw_commands: Arc<Buffer>,
    /// The number of commands of each face-cull region (read by `vkCmdDrawIndexedIndirectCount`).
    pub draw_count: Arc<Buffer>,
    /// Where each face cull's groups are, in every command list of this scene; their total is
    /// the number of draw groups (the most commands a frame can issue).
    pub regions: DrawRegions,
    /// [`super::cull_data::GpuCullRecord`] per slot (draw-list order).
    pub cull_records: Arc<Buffer>,
    /// [`super::cull_blocks::GpuBlockBound`] per block of cull slots, which the instance cull
    /// decides whole where it can. A changing world's slot updates mark their blocks to be
    /// tested slot by slot (`shaders/world/scatter.comp`); `None` once a world's scene grew.
    pub block_bounds: Option<Arc<Buffer>>,
    /// [`super::cull_data::GpuDrawGroup`] per draw group (empty for a changing world's reserved groups).
    pub draw_groups: Arc<Buffer>,
    /// The draw groups in the order of their slots ([`super::cull_data::slot_order`]): the
    /// order in which culled lists place their instance ids.
    pub group_order: Arc<Buffer>,
    /// Whether [`GpuScene::group_order`] differs from the groups' own order (a changing world
    /// whose groups grew in several regions): culling then takes each command's first instance
    /// from it.
    pub groups_out_of_slot_order: bool,
    /// [`super::cull_data::GpuGroupBounds`] per draw group (empty for a changing world's reserved groups): the local bounds that
    /// a changing world's moved instances get their cull bounds from.
    pub group_bounds: Arc<Buffer>,
    /// [`super::cull_data::GpuLodLevel`]s of the draw groups' meshes: the levels of detail a
    /// cull pass may choose (a changing world's meshes have none).
    pub lod_levels: Arc<Buffer>,
    /// Every mesh's clusters ([`super::cull_data::GpuCluster`]), read by the cluster pass.
    pub clusters: Arc<Buffer>,
    /// Where each mesh level's clusters are ([`super::cull_data::ClusterTables::ranges`]).
    pub cluster_ranges: Arc<Buffer>,
    /// The meshes with clusters by vertex offset ([`super::cull_data::ClusterTables::meshes`]).
    pub cluster_meshes: Arc<Buffer>,
    /// Entries of `cluster_meshes`.
    pub clustered_meshes: u32,
    /// The scene's textures, in size-class arrays (shared with the next upload of a changing
    /// world whose textures did not change).
    pub textures: Arc<GpuTextures>,
    /// Per instance: its mesh's first index and vertex offset (`uvec2`), for passes that rebuild
    /// a triangle from its id (the visibility buffer).
    pub instance_triangles: Arc<Buffer>,
    /// A changing world's user data ([`crate::scene::world::World::with_user_data`]):
    /// [`GpuScene::user_words`] words per slot, in slot order (an empty slot's are undefined);
    /// `None` without user data.
    pub user_data: Option<Arc<Buffer>>,
    /// Words of user data per slot (0: none).
    pub user_words: u32,
    /// Number of instances.
    pub instance_count: u32,
    /// The device's `maxStorageBufferRange`: the instance records' ranges are bound no wider,
    /// though their buffers may be, with room to grow ([`GpuScene::instance_binds`]).
    pub binding_range: u64,
    /// Triangles over all instances.
    pub triangles: u64,
    /// Triangles of the largest mesh (how many bits a triangle id needs).
    pub max_mesh_triangles: u32,
    /// Whether some material emits light or has an occlusion texture: without, the G-buffer
    /// passes leave their `emissive_occlusion` target unwritten and the lighting does not read it.
    pub emission_or_occlusion: bool,
    /// Whether some material is alpha-masked: only then do the geometry passes create and bind
    /// their alpha-tested pipelines, for the masked regions of their lists (the opaque regions
    /// always draw with pipelines whose depth test runs before shading).
    pub alpha_masks: bool,
    /// Whether some material samples a texture: without, no pass fetches texture coordinates
    /// and tangents ([`super::vertex_streams`]).
    pub textured: bool,
}

/// The unculled draw list: instances grouped by face cull, then by mesh, preserving instance
/// order in each group ([`super::face_cull`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DrawList {
    /// Instance ids, group after group.
    pub instance_ids: Vec<u32>,
    /// One command per non-empty group, `first_instance` pointing at its slice of `instance_ids`.
    pub commands: Vec<DrawIndexedIndirect>,
    /// The groups of each face cull.
    pub regions: DrawRegions,
}

impl DrawList {
    /// Groups every instance of `scene` by (face cull, mesh), each group in spatial order.
    pub fn all_instances(scene: &Scene) -> Self {
        let meshes = scene.meshes.len();
        let key = |inst: &crate::scene::Instance| FaceCull::of(scene, inst) as usize * meshes + inst.mesh as usize;
        let mut counts = vec![0u32; FACE_CULL_REGIONS * meshes];
        for inst in &scene.instances {
            counts[key(inst)] += 1;
        }
        let mut starts = Vec::with_capacity(counts.len());
        let mut total = 0u32;
        for &c in &counts {
            starts.push(total);
            total += c;
        }
        let mut cursor = starts.clone();
        let mut instance_ids = vec![0u32; scene.instances.len()];
        for (id, inst) in scene.instances.iter().enumerate() {
            let slot = &mut cursor[key(inst)];
            instance_ids[*slot as usize] = id as u32;
            *slot += 1;
        }
        // Within each group, spatial order (Morton order of the instances' origins, ties in
        // instance order): a cull workgroup's slots then lie close together, so they mostly
        // agree on the frustum and the Hi-Z paths instead of each spanning a strip of the scene.
        let keys = spatial_keys(scene);
        for (k, &count) in counts.iter().enumerate().filter(|(_, c)| **c > 1) {
            let slice = &mut instance_ids[starts[k] as usize..(starts[k] + count) as usize];
            slice.sort_unstable_by_key(|&id| (keys[id as usize], id));
        }
        let mut region_len = [0u32; FACE_CULL_REGIONS];
        let mut commands = Vec::new();
        for region in 0..FACE_CULL_REGIONS {
            let mut spare = 0;
            for k in region * meshes..(region + 1) * meshes {
                let count = counts[k];
                if count == 0 {
                    continue;
                }
                let mesh = &scene.meshes[k % meshes];
                spare += face_cull::lod_commands(mesh, region) - 1;
                commands.push(DrawIndexedIndirect {
                    index_count: mesh.index_count,
                    instance_count: count,
                    first_index: mesh.first_index,
                    vertex_offset: mesh.vertex_offset as i32,
                    first_instance: starts[k],
                });
            }
            // Room for one command per level of each group: empty groups after the region's
            // own, which a cull pass choosing levels of detail writes its commands into.
            let end = commands.last().map_or(0, |c| c.first_instance + c.instance_count);
            commands.extend((0..spare).map(|_| DrawIndexedIndirect { first_instance: end, ..Default::default() }));
            region_len[region] = commands.len() as u32 - region_len.iter().sum::<u32>();
        }
        Self { instance_ids, commands, regions: DrawRegions::from_lengths(region_len) }
    }
}

/// Refuses a scene with a mesh whose indices (relative to its vertex offset) reach past
/// `max_index`, the device's `maxDrawIndexedIndexValue` (at least 2^24 - 1; 2^32 - 1 where the
/// device draws the full 32-bit range, as NVIDIA's and lavapipe do): naming the mesh.
pub(crate) fn check_index_range(scene: &Scene, max_index: u32) -> crate::Result<()> {
    match scene.meshes.iter().find(|m| m.vertex_count > 0 && m.vertex_count - 1 > max_index) {
        Some(m) => Err(crate::Error::Invalid(format!(
            "mesh '{}' has {} vertices; this device draws meshes of at most {} (maxDrawIndexedIndexValue {max_index}): split it",
            m.name,
            m.vertex_count,
            max_index as u64 + 1
        ))),
        None => Ok(()),
    }
}

/// Morton code (21 bits per axis) of each instance's origin within the box of all origins.
pub(crate) fn spatial_keys(scene: &Scene) -> Vec<u64> {
    let origins = || scene.instances.iter().map(|i| i.transform.translation).filter(|t| t.is_finite());
    let lo = origins().fold(glam::DVec3::splat(f64::INFINITY), |a, b| a.min(b));
    let hi = origins().fold(glam::DVec3::splat(f64::NEG_INFINITY), |a, b| a.max(b));
    // All origins at one point (or none finite): every code 0, so instance order decides.
    let extent = (hi - lo).max_element();
    let scale = if extent > 0.0 && extent.is_finite() { ((1u64 << 21) - 1) as f64 / extent } else { 0.0 };
    let spread = |v: f64| -> u64 {
        // Bits of a 21-bit value, two zero bits between each.
        let mut x = (v.clamp(0.0, ((1u64 << 21) - 1) as f64)) as u64;
        x = (x | (x << 32)) & 0x1f00000000ffff;
        x = (x | (x << 16)) & 0x1f0000ff0000ff;
        x = (x | (x << 8)) & 0x100f00f00f00f00f;
        x = (x | (x << 4)) & 0x10c30c30c30c30c3;
        (x | (x << 2)) & 0x1249249249249249
    };
    scene
        .instances
        .iter()
        .map(|i| {
            let p = (i.transform.translation - lo) * scale;
            if !p.is_finite() {
                return u64::MAX;
            }
            spread(p.x) | (spread(p.y) << 1) | (spread(p.z) << 2)
        })
        .collect()
}

impl GpuScene {
    /// Device bytes of the scene's buffers and textures: what every view of a renderer shares.
    pub fn bytes(&self) -> u64 {
        let buffers = [
            &self.prev_positions,
            &self.indices,
            &self.instances,
            &self.materials,
            &self.draw_instance_ids,
            &self.draw_commands,
            &self.draw_count,
            &self.cull_records,
            &self.draw_groups,
            &self.group_bounds,
            &self.lod_levels,
            &self.clusters,
            &self.cluster_ranges,
            &self.cluster_meshes,
            &self.instance_triangles,
        ];
        let optional = [&self.prev_instances, &self.block_bounds];
        let optional: u64 = optional.iter().filter_map(|b| b.as_ref()).map(|b| b.size()).sum();
        buffers.iter().map(|b| b.size()).sum::<u64>() + self.vertices.bytes() + optional + self.textures.bytes()
    }

    /// The instance records of the world's previous frame ([`GpuScene::prev_instances`]), or the
    /// current ones for a scene that never moves.
    pub fn previous_instances(&self) -> &Buffer {
        self.prev_instances.as_deref().unwrap_or(&self.instances)
    }

    /// The binds of the instance records for a shader that names their first range `binding`
    /// (`shaders/common/instance_ranges.glsl`).
    pub fn instance_binds(&self, binding: u32) -> [Bind; instance_ranges::RANGES as usize] {
        instance_ranges::binds(&self.instances, binding, instance_ranges::INSTANCE_RANGE_BINDING, self.binding_range)
    }

    /// As [`GpuScene::instance_binds`], the previous records ([`GpuScene::previous_instances`]).
    pub fn previous_instance_binds(&self, binding: u32) -> [Bind; instance_ranges::RANGES as usize] {
        let previous = self.previous_instances();
        instance_ranges::binds(previous, binding, instance_ranges::PREV_INSTANCE_RANGE_BINDING, self.binding_range)
    }

    /// Makes [`GpuScene::prev_instances`], a buffer the size of [`GpuScene::instances`] with
    /// undefined contents: its owner copies the current records into it before any frame reads
    /// it (a changing world's renderer does at its next frame).
    pub fn add_previous_instances(&mut self, ctx: &GpuContext) -> crate::Result<()> {
        let desc = crate::gpu::BufferDesc {
            name: "previous instances",
            size: self.instances.size().max(std::mem::size_of::<GpuInstance>() as u64),
            // Carried into a larger successor when a changing world grows.
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            location: crate::gpu::MemoryLocation::GpuOnly,
        };
        self.prev_instances = Some(Arc::new(Buffer::new(ctx, &desc)?));
        Ok(())
    }

    /// Adds [`GpuScene::user_data`]: `words` words per slot, `data` in slot order, with room
    /// to grow; queued on `batch`.
    pub fn add_user_data(
        &mut self,
        ctx: &GpuContext,
        batch: &mut UploadBatch,
        words: u32,
        data: &[u32],
    ) -> crate::Result<()> {
        if words == 0 {
            return Ok(());
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let size = super::scene_growth::with_room(bytes.len() as u64);
        self.user_data = Some(Arc::new(batch.buffer_with_room(ctx, "user data", usage, bytes, size)?));
        self.user_words = words;
        Ok(())
    }

    /// Creates the device buffers and queues their contents on `batch`.
    pub fn upload(ctx: &GpuContext, scene: &Scene, batch: &mut UploadBatch) -> crate::Result<Self> {
        Self::upload_with(ctx, scene, DrawList::all_instances(scene), batch)
    }

    /// Like [`GpuScene::upload`], with the unculled draw list given (a changing world's slot
    /// layout, where `scene`'s instances are its slots).
    pub fn upload_with(
        ctx: &GpuContext,
        scene: &Scene,
        draws: DrawList,
        batch: &mut UploadBatch,
    ) -> crate::Result<Self> {
        Self::upload_inner(ctx, scene, draws, batch, None, false)
    }

    /// As [`GpuScene::upload_with`], every buffer with room to grow
    /// ([`super::scene_growth`]) and `textures` (the GPU textures of a scene with the same
    /// textures) taken instead of uploaded again: a changing world's scene.
    pub fn upload_with_room(
        ctx: &GpuContext,
        scene: &Scene,
        draws: DrawList,
        batch: &mut UploadBatch,
        textures: Option<Arc<GpuTextures>>,
    ) -> crate::Result<Self> {
        Self::upload_inner(ctx, scene, draws, batch, textures, true)
    }

    fn upload_inner(
        ctx: &GpuContext,
        scene: &Scene,
        draws: DrawList,
        batch: &mut UploadBatch,
        textures: Option<Arc<GpuTextures>>,
        room: bool,
    ) -> crate::Result<Self> {
        profiling::scope!("cullgraph::upload_scene");
        check_index_range(scene, ctx.caps().limits.max_draw_indexed_index_value)?;
        super::instance_ranges::check_instance_count(scene.instances.len() as u64, &ctx.caps().limits)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let usage = storage | vk::BufferUsageFlags::TRANSFER_SRC;
        let room_for = |bytes: usize| if room { super::scene_growth::with_room(bytes as u64) } else { 0 };
        // The per-instance tables are written straight into upload memory: a host copy of
        // them would be as large as the scene. A changing world copies the instance records to
        // its previous ones (motion vectors).
        let n = scene.instances.len();
        let instances = Arc::new(batch.buffer_filled(
            ctx,
            "instances",
            usage,
            n,
            room_for(n * std::mem::size_of::<GpuInstance>()),
            |first, out: &mut [GpuInstance]| {
                for (record, instance) in out.iter_mut().zip(&scene.instances[first..]) {
                    *record = GpuInstance::new(instance);
                }
            },
        )?);
        let (cull, group_of_slot) = super::cull_data::CullData::without_records(scene, &draws);
        // Readable back, for checks of the bounds a changing world's updates derive.
        let cull_records = Arc::new(batch.buffer_filled(
            ctx,
            "cull records",
            usage,
            draws.instance_ids.len(),
            room_for(draws.instance_ids.len() * std::mem::size_of::<super::cull_data::GpuCullRecord>()),
            |first, out: &mut [super::cull_data::GpuCullRecord]| {
                let slots = draws.instance_ids[first..].iter().zip(&group_of_slot[first..]);
                for (record, (&id, &group)) in out.iter_mut().zip(slots) {
                    *record = super::cull_data::cull_record(scene, &scene.instances[id as usize], group);
                }
            },
        )?);
        // A bound per block of slots, from the same records; a changing world's has room for a
        // block per slot its records have room for (those blocks' slots are all written by
        // the world's updates, which mark their blocks).
        let block_bounds = {
            let slots = draws.instance_ids.len();
            let block = super::cull_blocks::CULL_BLOCK as usize;
            let bound = std::mem::size_of::<super::cull_blocks::GpuBlockBound>();
            let record = std::mem::size_of::<super::cull_data::GpuCullRecord>();
            let room_bytes = match room {
                true => (cull_records.size() as usize / record).div_ceil(block) * bound,
                false => 0,
            };
            Some(Arc::new(batch.buffer_filled(
                ctx,
                "cull block bounds",
                usage,
                slots.div_ceil(block),
                room_bytes as u64,
                |first, out: &mut [super::cull_blocks::GpuBlockBound]| {
                    for (b, bound) in (first..).zip(out.iter_mut()) {
                        let range = b * block..((b + 1) * block).min(slots);
                        let slots = draws.instance_ids[range.clone()].iter().zip(&group_of_slot[range]);
                        *bound = super::cull_blocks::block_bound(slots.map(|(&id, &group)| {
                            super::cull_data::cull_record(scene, &scene.instances[id as usize], group)
                        }));
                    }
                },
            )?))
        };
        drop(group_of_slot);
        let instance_triangles = Arc::new(batch.buffer_filled(
            ctx,
            "instance triangle bases",
            usage,
            n,
            room_for(n * 8),
            |first, out: &mut [[u32; 2]]| {
                for (bases, instance) in out.iter_mut().zip(&scene.instances[first..]) {
                    let mesh = &scene.meshes[instance.mesh as usize];
                    *bases = [mesh.first_index, mesh.vertex_offset];
                }
            },
        )?);
        let textures = match textures {
            Some(textures) => textures,
            None => Arc::new(GpuTextures::upload(ctx, scene, batch)?),
        };
        let materials: Vec<GpuMaterial> =
            scene.materials.iter().map(|m| GpuMaterial::new(m, textures.placements())).collect();
        let cluster_tables = super::cull_data::cluster_tables(scene);
        let (group_order, out_of_order) =
            super::cull_data::slot_order(cull.groups.iter().map(|g| (g.first_slot, g.slot_count)));
        let count = draws.regions.len;
        let (positions, normals, surface) = super::vertex_streams::split(&scene.vertices);
        // Every scene buffer can be carried into a larger successor (a changing world's growth).
        let mut make = |name: &str, usage: vk::BufferUsageFlags, data: &[u8]| -> crate::Result<Arc<Buffer>> {
            let size = if room { super::scene_growth::with_room(data.len() as u64) } else { 0 };
            let usage = usage | storage | vk::BufferUsageFlags::TRANSFER_SRC;
            Ok(Arc::new(batch.buffer_with_room(ctx, name, usage, data, size)?))
        };
        let none = vk::BufferUsageFlags::empty();
        Ok(Self {
            vertices: VertexStreams {
                positions: make(
                    "vertex positions",
                    vk::BufferUsageFlags::VERTEX_BUFFER,
                    bytemuck::cast_slice(&positions),
                )?,
                normals: make("vertex normals", vk::BufferUsageFlags::VERTEX_BUFFER, bytemuck::cast_slice(&normals))?,
                surface: make("vertex surface", vk::BufferUsageFlags::VERTEX_BUFFER, bytemuck::cast_slice(&surface))?,
            },
            prev_positions: make("previous positions", none, bytemuck::cast_slice(&positions))?,
            indices: make("indices", vk::BufferUsageFlags::INDEX_BUFFER, bytemuck::cast_slice(&scene.indices))?,
            instances,
            prev_instances: None,
            materials: make("materials", none, bytemuck::cast_slice(&materials))?,
            draw_instance_ids: make("draw instance ids", none, bytemuck::cast_slice(&draws.instance_ids))?,
            draw_commands: make(
                "draw commands",
                vk::BufferUsageFlags::INDIRECT_BUFFER,
                bytemuck::cast_slice(&draws.commands),
            )?,
            draw_count: make("draw count", vk::BufferUsageFlags::INDIRECT_BUFFER, bytemuck::cast_slice(&count))?,
            cull_records,
            block_bounds,
            draw_groups: make("draw groups", none, bytemuck::cast_slice(&cull.groups))?,
            group_order: make("draw group order", none, bytemuck::cast_slice(&group_order))?,
            groups_out_of_slot_order: out_of_order,
            group_bounds: make("group bounds", none, bytemuck::cast_slice(&cull.bounds))?,
            lod_levels: make("levels of detail", none, bytemuck::cast_slice(&cull.lods))?,
            clusters: make("clusters", none, bytemuck::cast_slice(&cluster_tables.clusters))?,
            cluster_ranges: make("cluster ranges", none, bytemuck::cast_slice(&cluster_tables.ranges))?,
            cluster_meshes: make("clustered meshes", none, bytemuck::cast_slice(&cluster_tables.meshes))?,
            clustered_meshes: cluster_tables.clustered_meshes(),
            instance_triangles,
            regions: draws.regions,
            textures,
            user_data: None,
            user_words: 0,
            instance_count: scene.instances.len() as u32,
            binding_range: ctx.caps().limits.max_storage_buffer_range as u64,
            triangles: drawn_triangles(scene),
            max_mesh_triangles: max_mesh_triangles(scene),
            emission_or_occlusion: scene.has_emission_or_occlusion(),
            alpha_masks: scene.has_alpha_masks(),
            textured: scene.samples_textures(),
        })
    }
}

/// Triangles of the largest mesh of `scene`.
pub(crate) fn max_mesh_triangles(scene: &Scene) -> u32 {
    scene.meshes.iter().map(|m| m.index_count / 3).max().unwrap_or(0)
}

/// Triangles over the instances of `scene` (a changing world's empty slots draw none).
pub(crate) fn drawn_triangles(scene: &Scene) -> u64 {
    scene
        .instances
        .iter()
        .filter(|i| i.flags & crate::scene::FLAG_EMPTY_SLOT == 0)
        .map(|i| scene.meshes[i.mesh as usize].index_count as u64 / 3)
        .sum()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn meshes_past_the_devices_index_range_are_refused_by_name() {
        let mut scene = Scene::default();
        let tri = crate::scene::MeshData {
            positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        scene.add_mesh("small", &tri, "small").unwrap();
        scene.add_mesh("huge", &tri, "huge").unwrap();
        // As if the second had 2^24 + 1 vertices, on a device limited to 2^24 - 1.
        scene.meshes[1].vertex_count = (1 << 24) + 1;
        assert!(check_index_range(&scene, u32::MAX).is_ok());
        let err = check_index_range(&scene, (1 << 24) - 1).unwrap_err().to_string();
        assert!(err.contains("mesh 'huge' has 16777217 vertices") && err.contains("at most 16777216"), "{err}");
    }
    use crate::scene::{Instance, MeshData, Transform};
    use glam::{DVec3, Vec3};

    /// A scene of `meshes` one-triangle meshes and one material, no instances yet.
    pub(crate) fn triangle_meshes(meshes: usize) -> (Scene, Vec<u32>) {
        let mut scene = Scene::default();
        let tri = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        let ids = (0..meshes).map(|m| scene.add_mesh(&format!("m{m}"), &tri, "m").unwrap()).collect();
        scene.add_material(Default::default());
        (scene, ids)
    }

    #[test]
    fn draw_lists_keep_room_for_a_command_per_level_of_each_group() {
        let mut scene = Scene::default();
        let sphere = crate::scene::lod::tests::sphere(64, 128);
        let with = scene.add_mesh("with", &sphere, "with").unwrap();
        let without = scene.add_mesh("without", &MeshData { no_lod: true, ..sphere }, "without").unwrap();
        scene.add_material(Default::default());
        for mesh in [with, without] {
            scene.instances.push(Instance { transform: Default::default(), mesh, material: 0, flags: 0 });
        }
        let levels = scene.meshes[with as usize].lods.len();
        assert!(levels > 0);
        let draws = DrawList::all_instances(&scene);
        // Both groups, then one empty command per level past the full mesh.
        assert_eq!(draws.commands.len(), 2 + levels);
        assert_eq!(draws.regions.groups() as usize, super::face_cull::command_capacity(&scene));
        assert!(draws.commands[2..].iter().all(|c| c.instance_count == 0 && c.first_instance == 2));
    }

    /// Within a group, slots follow the Morton order of the instances' origins (a 4x4 grid
    /// created row by row comes out in Z order), and instances at the same origin keep their
    /// instance order; groups stay apart.
    #[test]
    fn groups_are_in_spatial_order_with_duplicates_in_instance_order() {
        let (mut scene, meshes) = triangle_meshes(2);
        let (mesh, other) = (meshes[0], meshes[1]);
        let at = |x: f64, z: f64| Transform { translation: DVec3::new(x, 0.0, z), ..Default::default() };
        for row in 0..4 {
            for col in 0..4 {
                scene.instances.push(Instance { transform: at(col as f64, row as f64), mesh, material: 0, flags: 0 });
            }
        }
        // Two more at the origin (16, 17) and one of another mesh (18).
        for m in [mesh, mesh, other] {
            scene.instances.push(Instance { transform: at(0.0, 0.0), mesh: m, material: 0, flags: 0 });
        }
        let draws = DrawList::all_instances(&scene);
        // Morton order interleaves x (bit 0) and z (bit 2): (0,0) (1,0) (0,1) (1,1) (2,0) ...
        let z_order = [0, 16, 17, 1, 4, 5, 2, 3, 6, 7, 8, 9, 12, 13, 10, 11, 14, 15];
        assert_eq!(draws.instance_ids[..18], z_order);
        assert_eq!(draws.instance_ids[18], 18);
        assert_eq!(draws.commands.len(), 2);
    }

    /// Degenerate layouts keep instance order: every origin at one point, and an origin that is
    /// not finite (sorted last; such a scene is refused at upload anyway).
    #[test]
    fn degenerate_origins_keep_instance_order() {
        let (mut scene, meshes) = triangle_meshes(1);
        let mesh = meshes[0];
        let at = |t: DVec3| Instance {
            transform: Transform { translation: t, ..Default::default() },
            mesh,
            material: 0,
            flags: 0,
        };
        scene.instances = vec![at(DVec3::splat(5.0)); 4];
        assert_eq!(DrawList::all_instances(&scene).instance_ids, [0, 1, 2, 3]);
        scene.instances[1] = at(DVec3::new(f64::NAN, 0.0, 0.0));
        scene.instances.push(at(DVec3::new(-1.0e7, 0.0, 1.0e7)));
        // The far one (4) has the largest z, the highest bit its code can set.
        assert_eq!(DrawList::all_instances(&scene).instance_ids, [0, 2, 3, 4, 1]);
    }
}
