//! Posed instances on the GPU ([`crate::scene::world::World::set_pose`]): each posed instance
//! draws its own copy of its mesh in the vertex pool, which `shaders/world/deform.comp` writes
//! from the shared rest mesh whenever the pose changes, at the start of the next recorded frame
//! (before the slot updates, which derive the instance's cull record from the bound of the pose
//! the same dispatch writes into its draw group). Everything after that (every geometry pass,
//! the visibility buffer's triangle fetches, the exact-visibility oracle) reads the deformed
//! copy as any other mesh.
//!
//! The deformation data (skin influences and morph offsets) of each deformable mesh is put in
//! one buffer the first time an instance of it is posed, and stays while the renderer lives;
//! a pose costs its joint matrices (48 bytes a joint) and morph weights per frame it changes.

use crate::error::Result;
use crate::gpu::{Bind, Buffer, BufferDesc, Edits, GpuContext, MemoryLocation, Pipeline, ShaderCompiler};
use crate::graph::FRAMES_IN_FLIGHT;
use crate::passes::shared::cull_data::GpuGroupBounds;
use crate::passes::shared::GpuScene;
use crate::scene::deform::MeshDeform;
use crate::scene::posing::Pose;
use crate::scene::Scene;
use std::collections::HashMap;
use std::sync::Arc;

/// The group of an entry that only refreshes the previous positions (`REFRESH` in
/// `shaders/world/deform.comp`).
const REFRESH: u32 = u32::MAX;

/// One instance's deformation, as `shaders/world/deform.comp` reads it (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Entry {
    src_vertex: u32,
    dst_vertex: u32,
    vertex_count: u32,
    data_offset: u32,
    params_offset: u32,
    joint_count: u32,
    target_count: u32,
    group: u32,
    bounds: GpuGroupBounds,
}

/// See the module documentation.
pub(super) struct Deformer {
    pipeline: Pipeline,
    /// Per deformable mesh posed so far, where its data starts in `data` (words).
    placed: HashMap<u32, u32>,
    data: Option<Arc<Buffer>>,
    data_words: u64,
    /// The deformations waiting for the next recorded frame (one per instance index), and
    /// their joint rows and weights.
    entries: Vec<Entry>,
    entry_of: HashMap<u32, usize>,
    params: Vec<f32>,
    /// The deformations the last recorded frame made, by instance index: those not deformed
    /// again get their previous positions refreshed (no motion once a pose stops changing).
    last: HashMap<u32, Entry>,
    /// Whether the next frame's deformations show no motion (the scene was uploaded again,
    /// its previous positions being the rest shape).
    still: bool,
    /// Per frame in flight, the host-visible buffers the entries and params are read from.
    segments: Vec<[Option<Buffer>; 2]>,
}

impl Deformer {
    pub(super) fn new(ctx: &GpuContext, shaders: &ShaderCompiler) -> Result<Self> {
        Ok(Self {
            pipeline: Pipeline::compute(ctx, "world deform", &shaders.compile("world/deform.comp", &[])?)?,
            placed: HashMap::new(),
            data: None,
            data_words: 0,
            entries: Vec::new(),
            entry_of: HashMap::new(),
            params: Vec::new(),
            last: HashMap::new(),
            still: false,
            segments: (0..FRAMES_IN_FLIGHT).map(|_| [None, None]).collect(),
        })
    }

    /// Queues instance index `index` deformed by `pose` into its copy of the mesh, the bounds
    /// of the pose going to draw group `group`. The source mesh's data is queued on `edits`
    /// the first time.
    pub(super) fn queue(
        &mut self,
        ctx: &GpuContext,
        edits: &mut Edits,
        scene: &Scene,
        index: u32,
        pose: &Pose,
        group: u32,
    ) -> Result<()> {
        let source = &scene.meshes[pose.source as usize];
        let Some(deform) = source.deform.as_deref() else { return Ok(()) };
        let data_offset = match self.placed.get(&pose.source) {
            Some(&at) => at,
            None => self.place(ctx, edits, pose.source, deform)?,
        };
        let own = &scene.meshes[pose.mesh as usize];
        let joint_count = if deform.is_skinned() { pose.joints.len() as u32 } else { 0 };
        let params_offset = self.params.len() as u32;
        for m in pose.joints.iter().take(joint_count as usize) {
            for r in 0..3 {
                self.params.extend([m.x_axis[r], m.y_axis[r], m.z_axis[r], m.w_axis[r]]);
            }
        }
        self.params.extend_from_slice(&pose.morph_weights);
        let entry = Entry {
            src_vertex: source.vertex_offset,
            dst_vertex: own.vertex_offset,
            vertex_count: source.vertex_count.min(own.vertex_count),
            data_offset,
            params_offset,
            joint_count,
            target_count: pose.morph_weights.len().min(deform.morph_targets.len()) as u32,
            group,
            bounds: GpuGroupBounds::of(own),
        };
        match self.entry_of.get(&index) {
            Some(&at) => self.entries[at] = entry,
            None => {
                self.entry_of.insert(index, self.entries.len());
                self.entries.push(entry);
            }
        }
        Ok(())
    }

    /// Puts the data of deformable mesh `mesh` in `data` (grown on the GPU where full); returns
    /// where it starts.
    fn place(&mut self, ctx: &GpuContext, edits: &mut Edits, mesh: u32, deform: &MeshDeform) -> Result<u32> {
        let mut words: Vec<u32> = Vec::new();
        if deform.is_skinned() {
            for (j, w) in deform.joints.iter().zip(&deform.weights) {
                words.push(j[0] as u32 | (j[1] as u32) << 16);
                words.push(j[2] as u32 | (j[3] as u32) << 16);
                words.extend(w.to_array().map(f32::to_bits));
            }
        }
        for target in &deform.morph_targets {
            for (i, d) in target.positions.iter().enumerate() {
                let n = target.normals.get(i).copied().unwrap_or_default();
                words.extend([d.x, d.y, d.z, n.x, n.y, n.z].map(f32::to_bits));
            }
        }
        let at = self.data_words;
        let end = (at + words.len() as u64) * 4;
        let held = self.data.as_ref().map_or(0, |b| b.size());
        if end > held {
            let desc = BufferDesc {
                name: "deformation data",
                size: crate::passes::shared::scene_growth::with_room(end),
                usage: ash::vk::BufferUsageFlags::STORAGE_BUFFER
                    | ash::vk::BufferUsageFlags::TRANSFER_SRC
                    | ash::vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            };
            let grown = Arc::new(Buffer::new(ctx, &desc)?);
            if let Some(old) = self.data.take() {
                let size = old.size();
                edits.carry(old, &grown, size);
            }
            self.data = Some(grown);
        }
        edits.write(self.data.as_ref().expect("made above"), at * 4, bytemuck::cast_slice(&words));
        self.data_words += words.len().max(1) as u64;
        let offset = u32::try_from(at).map_err(|_| {
            crate::Error::Invalid(format!("mesh {mesh}: the deformation data of posed meshes passed 2^32 words"))
        })?;
        self.placed.insert(mesh, offset);
        Ok(offset)
    }

    /// Whether deformations (or refreshes of last frame's) wait for the next frame.
    pub(super) fn pending(&self) -> bool {
        !self.entries.is_empty() || !self.last.is_empty()
    }

    /// Bytes the queued deformations upload.
    pub(super) fn queued_bytes(&self) -> u64 {
        (std::mem::size_of_val(self.entries.as_slice()) + std::mem::size_of_val(self.params.as_slice())) as u64
    }

    /// Records frame `k`'s (its slot of the frames in flight) deformations, and the refreshes
    /// of last frame's that were not deformed again; the caller orders them after earlier
    /// frames' use of the pool and before the slot updates.
    pub(super) fn record(
        &mut self,
        ctx: &GpuContext,
        cmd: ash::vk::CommandBuffer,
        k: usize,
        scene: &GpuScene,
    ) -> Result<()> {
        // The queue stays until the frame is recorded whole (`clear`), so a failed recording can
        // be recorded again.
        let mut list = self.entries.clone();
        // A copy freed since last frame may have given its vertices to one deformed now: a
        // refresh never touches vertices a deformation of this frame writes.
        let mut written: Vec<(u32, u32)> = list.iter().map(|e| (e.dst_vertex, e.dst_vertex + e.vertex_count)).collect();
        written.sort_unstable();
        // The copies written now are disjoint, so sorted by start their ends are sorted too:
        // of those starting before a range ends, the last reaches furthest.
        let overlaps = |e: &Entry| {
            let (start, end) = (e.dst_vertex, e.dst_vertex + e.vertex_count);
            let before_end = written.partition_point(|&(s, _)| s < end);
            before_end > 0 && written[before_end - 1].1 > start
        };
        list.extend(
            self.last
                .iter()
                .filter(|(index, e)| !self.entry_of.contains_key(index) && !overlaps(e))
                .map(|(_, e)| Entry { group: REFRESH, ..*e }),
        );
        self.last = self.entry_of.iter().map(|(&index, &at)| (index, list[at])).collect();
        let (Some(data), false) = (&self.data, list.is_empty()) else { return Ok(()) };
        let params: &[f32] = if self.params.is_empty() { &[0.0] } else { &self.params };
        let entries = super::world_sync::fill_segment(
            ctx,
            &mut self.segments[k][0],
            &format!("deform entries {k}"),
            bytemuck::cast_slice(&list),
        )?
        .handle();
        let params = super::world_sync::fill_segment(
            ctx,
            &mut self.segments[k][1],
            &format!("deform params {k}"),
            bytemuck::cast_slice(params),
        )?
        .handle();
        let most = list.iter().map(|e| e.vertex_count).max().unwrap_or(0);
        let limit = ctx.caps().limits.max_compute_work_group_count[1].max(1);
        self.pipeline.bind(cmd);
        self.pipeline.push_bindings(
            cmd,
            &[
                Bind::Buffer(0, entries),
                Bind::Buffer(1, params),
                Bind::Buffer(2, data.handle()),
                Bind::Buffer(3, scene.vertices.positions.handle()),
                Bind::Buffer(4, scene.group_bounds.handle()),
                Bind::Buffer(5, scene.prev_positions.handle()),
                Bind::Buffer(6, scene.vertices.normals.handle()),
                Bind::Buffer(7, scene.vertices.surface.handle()),
            ],
        );
        // A row of workgroups per instance, in as many dispatches as the device's rows allow.
        let count = list.len() as u32;
        let still = self.still as u32;
        self.still = false;
        for base in (0..count).step_by(limit as usize) {
            let rows = (count - base).min(limit);
            self.pipeline.push_constants(cmd, &[count, base, still]);
            // SAFETY: cmd recording with the deform pipeline bound.
            unsafe { ctx.device().cmd_dispatch(cmd, most.div_ceil(64).max(1), rows, 1) };
        }
        Ok(())
    }

    /// Forgets where the meshes' data is (the scene was uploaded again, and the edits that
    /// wrote the data may have gone with the batch it replaced): the next poses place it again.
    pub(super) fn forget_data(&mut self) {
        self.placed.clear();
        self.data_words = 0;
        self.last.clear();
        self.still = true;
    }

    /// Forgets the queued deformations (recorded).
    pub(super) fn clear(&mut self) {
        self.entries.clear();
        self.entry_of.clear();
        self.params.clear();
    }
}
