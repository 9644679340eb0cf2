//! `cluster_cull`: the clusters ([`crate::scene::clusters`]) of the instances a culled list
//! draws, tested one by one, so that a visible instance draws only the parts of it that can
//! make a fragment.
//!
//! The pass reads a culled draw list (an `instance_cull` output) and writes two lists that
//! together draw what it would, less the clusters dropped:
//! - `pass_commands`/`pass_count`: the input list in its own layout, with each command whose
//!   level has clusters emptied (instance count 0); the others are drawn whole as before;
//! - `cluster_commands`/`cluster_count`: one command per surviving cluster (its index range,
//!   one instance), in three regions of equal size for the opaque face culls (back, front,
//!   none), each with its count;
//! - where bound, `masked_cluster_commands`/`masked_cluster_count`: the same for the instances
//!   of alpha-masked materials, which a geometry pass draws with its alpha-tested pipelines (a
//!   list of their own, sized by their own clusters). Unbound, masked instances are drawn whole.
//!
//! A geometry pass draws them all (its `cluster_commands`, `cluster_count` and masked slots)
//! with the input list's instance ids. A cluster is dropped when its bounding sphere is outside the
//! frustum, covers no sample position, faces away from the eye (its normal cone, for one-sided
//! materials on instances without shear or non-uniform scale), or lies behind the Hi-Z when one
//! is bound. Each test is conservative: the triangles dropped could make no fragment, so the
//! image is the one the input list draws (triangles of one instance in cluster order, but
//! survivors of different instances in the order the GPU finds them, so depth ties between
//! instances may resolve either way).
//!
//! Two steps (`shaders/cluster_cull/`): `cluster_prepare.comp`, one workgroup, walks the
//! commands in order and gives each clustered command a range of tasks (one per instance and
//! chunk of 64 clusters); `cluster_cull.comp`, dispatched indirectly, tests a task per
//! workgroup and appends the survivors.

use super::slots::{slot, COUNT_BYTES, DRAW_COMMANDS, DRAW_COUNTS, HIZ_FORMAT};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, Buffer, BufferDesc, GpuContext, MemoryLocation, Pipeline, Sampler};
use crate::graph::executor::PassContext;
use crate::graph::plan::Version;
use crate::graph::{
    CounterEntry, Counters, Creates, FormatRule, Growth, KindCheck, NodeSetup, PassKind, PassKindInfo, PassNode, Pos,
    Quantity, SlotDecl, Stages, Usage,
};
use crate::passes::gbuffer::LIST_SLOTS;
use crate::passes::shared::face_cull::{FaceCull, FACE_CULL_REGIONS};
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::SceneCounts;
use crate::passes::shared::SceneInputs;
use ash::vk;
use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

/// The kind's name in RON.
pub(crate) const KIND: &str = "cluster_cull";

/// The group of the frame's stats (and key of its JSON) that cluster passes report in.
pub const GROUP: &str = "clusters";

/// Bytes of one draw command.
const COMMAND_BYTES: u64 = 20;

/// Regions of a cluster list: the opaque face culls.
pub const CLUSTER_REGIONS: u64 = 3;

/// The quantity `clusters`: the most clusters the opaque instances (neither masked nor
/// transparent) may draw (each instance's mesh's richest level's).
pub const CLUSTERS: Quantity = Quantity {
    name: "clusters",
    doc: "clusters the opaque instances may draw in all (each at its mesh's level with the most clusters; 0 without clustered meshes)",
    count: |s| clusters_in(s, &FaceCull::OPAQUE),
    growth: Growth::Grows,
};

/// The quantity `masked_clusters`: the most clusters the instances of alpha-masked materials
/// may draw (each instance's mesh's richest level's).
pub const MASKED_CLUSTERS: Quantity = Quantity {
    name: "masked_clusters",
    doc: "clusters the instances of alpha-masked materials may draw in all (each at its mesh's level with the most clusters; 0 without clustered masked meshes)",
    count: |s| clusters_in(s, &FaceCull::MASKED),
    growth: Growth::Grows,
};

/// The clusters the instances of `regions` may draw in all (each at its mesh's level with the
/// most clusters), in the scene `s` counts.
fn clusters_in(s: &dyn std::any::Any, regions: &[FaceCull]) -> Option<u64> {
    let scene = SceneCounts::downcast(s)?.scene;
    let per_mesh: Vec<u64> =
        scene.meshes.iter().map(|m| crate::passes::shared::cull_data::mesh_clusters(m) as u64).collect();
    let counted = |i: &&crate::scene::Instance| regions.contains(&FaceCull::of(scene, i));
    Some(scene.instances.iter().filter(counted).map(|i| per_mesh.get(i.mesh as usize).copied().unwrap_or(0)).sum())
}

/// Bytes of the cluster list: one command per cluster in each of the three regions.
const CLUSTER_COMMANDS_BYTES: &str = "max(1, clusters) * 60";
/// Bytes of the masked instances' cluster list, alike.
const MASKED_CLUSTER_COMMANDS_BYTES: &str = "max(1, masked_clusters) * 60";
/// Bytes of the scratch: a header, then one record of 32 bytes per input command.
const SCRATCH_BYTES: &str = "32 + meshes * 32";
/// Words of the scratch header (`SCRATCH_HEADER_WORDS` in `cluster_common.glsl`).
const SCRATCH_HEADER_WORDS: u64 = 8;
/// The test step's largest dispatch (of 4 tasks a workgroup): its workgroups loop over the
/// tasks beyond, so the counters see one atomic per workgroup, not one per task.
const MAX_TEST_GROUPS: u32 = 4096;
/// Tasks one test workgroup takes at a time (`TASKS_PER_GROUP` in `cluster_cull.comp`).
const TASKS_PER_GROUP: u32 = 4;

/// One cluster pass's counters as the GPU writes them (48 bytes; `STAT_*` in
/// `cluster_common.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ClusterCounters {
    /// Clusters tested.
    pub tested: u32,
    /// Outside the frustum, or covering no sample position.
    pub frustum_culled: u32,
    /// Facing away from the eye.
    pub backfacing: u32,
    /// Behind the Hi-Z.
    pub occlusion_culled: u32,
    /// Clusters drawn.
    pub drawn: u32,
    /// Triangles of the clusters tested.
    pub triangles_tested: u32,
    /// Triangles of the clusters drawn.
    pub triangles_drawn: u32,
    /// Commands of levels without clusters, drawn whole.
    pub whole_commands: u32,
    /// Unused.
    pub pad: [u32; 4],
}

/// One cluster pass's figures in a frame, as reported (group [`GROUP`]).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ClusterPassStats {
    /// Pass name in the graph.
    pub pass: String,
    /// Clusters tested.
    pub tested: u32,
    /// Outside the frustum, or covering no sample position.
    pub frustum_culled: u32,
    /// Facing away from the eye.
    pub backfacing: u32,
    /// Behind the Hi-Z.
    pub occlusion_culled: u32,
    /// Clusters drawn.
    pub drawn: u32,
    /// Triangles of the clusters tested.
    pub triangles_tested: u64,
    /// Triangles of the clusters drawn.
    pub triangles_drawn: u64,
    /// Commands of levels without clusters, passed on whole.
    pub whole_commands: u32,
}

impl ClusterPassStats {
    /// From the counters of pass `pass`.
    pub fn new(pass: &str, c: &ClusterCounters) -> Self {
        Self {
            pass: pass.into(),
            tested: c.tested,
            frustum_culled: c.frustum_culled,
            backfacing: c.backfacing,
            occlusion_culled: c.occlusion_culled,
            drawn: c.drawn,
            triangles_tested: c.triangles_tested as u64,
            triangles_drawn: c.triangles_drawn as u64,
            whole_commands: c.whole_commands,
        }
    }

    /// Triangles the frame's cluster passes dropped (of instances drawn cluster by cluster).
    pub fn triangles_dropped(stats: &crate::stats::FrameStats) -> u64 {
        stats.entries::<Self>(GROUP).iter().map(|s| s.triangles_tested - s.triangles_drawn).sum()
    }
}

/// Push constants of `cluster_prepare.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PreparePush {
    region_first: [u32; FACE_CULL_REGIONS],
    region_len: [u32; FACE_CULL_REGIONS],
    max_groups: u32,
    tasks_per_group: u32,
    clustered_capacity: u32,
    clustered_meshes: u32,
    /// Regions whose commands are drawn cluster by cluster: 3 (the opaque ones) or 6 (the
    /// masked ones too).
    clustered_regions: u32,
}

/// Push constants of `cluster_cull.comp`: each list's region capacity.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TestPush {
    region_capacity: u32,
    masked_region_capacity: u32,
}

/// The `cluster_cull` pass.
struct ClusterCullPass {
    prepare: Pipeline,
    test: Pipeline,
    sampler: Sampler,
    /// The test step's dispatch size, copied out of the scratch (an indirect buffer the pass
    /// owns, so the graph's buffers need no indirect usage).
    dispatch: Buffer,
}

/// What the test step does with what the prepare step wrote: reads its dispatch size, and
/// reads and writes storage buffers.
const TEST_STEP: Access = Access {
    stage: vk::PipelineStageFlags2::from_raw(Access::INDIRECT.stage.as_raw() | Access::COMPUTE_WRITE.stage.as_raw()),
    access: vk::AccessFlags2::from_raw(Access::INDIRECT.access.as_raw() | Access::COMPUTE_WRITE.access.as_raw()),
    layout: vk::ImageLayout::UNDEFINED,
};

impl PassNode for ClusterCullPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    /// The prepare step overwrites the dispatch size that the last run's test step read.
    fn own_dependency(&mut self) -> Option<(Access, Access)> {
        Some((Access::INDIRECT, Access::COMPUTE_WRITE))
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let inputs = SceneInputs::of(rec)?;
        let scene = &inputs.scene;
        let slots = &rec.slots;
        let need = |slot: &str| slots.required_buffer(slot);
        let (commands, count, ids) = (need(LIST_SLOTS[0])?, need(LIST_SLOTS[1])?, need(LIST_SLOTS[2])?);
        let (pass_commands, pass_count) = (need("pass_commands")?, need("pass_count")?);
        let (cluster_commands, cluster_count) = (need("cluster_commands")?, need("cluster_count")?);
        // Both or neither (checked at load); the kind's pipelines were made for which.
        let masked = slots.buffer("masked_cluster_commands").zip(slots.buffer("masked_cluster_count"));
        let (scratch, stats) = (need("scratch")?, need("stats")?);
        let device = rec.ctx.device();
        let cmd = rec.cmd;
        let clustered_capacity = ((scratch.size() / 4).saturating_sub(SCRATCH_HEADER_WORDS) / 8).min(u32::MAX as u64);
        let push = PreparePush {
            region_first: scene.regions.first,
            region_len: scene.regions.len,
            max_groups: MAX_TEST_GROUPS,
            tasks_per_group: TASKS_PER_GROUP,
            clustered_capacity: clustered_capacity as u32,
            clustered_meshes: scene.clustered_meshes,
            clustered_regions: if masked.is_some() { 2 * CLUSTER_REGIONS as u32 } else { CLUSTER_REGIONS as u32 },
        };
        let mut binds = vec![
            Bind::Buffer(0, commands.handle()),
            Bind::Buffer(1, count.handle()),
            Bind::Buffer(2, scene.cluster_meshes.handle()),
            Bind::Buffer(3, scene.clusters.handle()),
            Bind::Buffer(6, scene.cluster_ranges.handle()),
            Bind::Buffer(7, pass_commands.handle()),
            Bind::Buffer(8, pass_count.handle()),
            Bind::Buffer(9, scratch.handle()),
            Bind::Buffer(10, cluster_count.handle()),
            Bind::Buffer(11, stats.handle()),
        ];
        if let Some((_, masked_count)) = masked {
            binds.push(Bind::Buffer(12, masked_count.handle()));
        }
        binds.push(Bind::Buffer(13, self.dispatch.handle()));
        rec.step("prepare");
        self.prepare.dispatch_over(cmd, &binds, bytemuck::bytes_of(&push), vk::Extent2D { width: 1, height: 1 });
        // Without clustered meshes the prepare step passed every command on whole: no test.
        if scene.clustered_meshes == 0 {
            return Ok(());
        }
        // The test step's dispatch size, its tasks in the scratch and its zeroed counts.
        cmd_barriers(device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, TEST_STEP)], &[]);
        let capacity = TestPush {
            region_capacity: region_capacity(cluster_commands),
            masked_region_capacity: masked.map_or(0, |(commands, _)| region_capacity(commands)),
        };
        let mut binds = vec![
            Bind::Buffer(0, inputs.constants().handle()),
            Bind::Buffer(2, commands.handle()),
            Bind::Buffer(3, ids.handle()),
            Bind::Buffer(4, scene.clusters.handle()),
            Bind::Buffer(5, scratch.handle()),
            Bind::Buffer(6, cluster_commands.handle()),
            Bind::Buffer(7, cluster_count.handle()),
            Bind::Buffer(8, stats.handle()),
        ];
        binds.extend(scene.instance_binds(1));
        if let Some((masked_commands, masked_count)) = masked {
            binds.extend([Bind::Buffer(10, masked_commands.handle()), Bind::Buffer(11, masked_count.handle())]);
        }
        if let Some(hiz) = slots.image("hiz") {
            binds.push(Bind::Sampled(9, hiz.view(), self.sampler.handle(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL));
        }
        rec.step("test");
        self.test.bind(cmd);
        self.test.push_bindings(cmd, &binds);
        self.test.push_constant_bytes(cmd, bytemuck::bytes_of(&capacity));
        // SAFETY: cmd recording with the test pipeline bound; the dispatch size was written above.
        unsafe { device.cmd_dispatch_indirect(cmd, self.dispatch.handle(), 0) };
        Ok(())
    }
}

/// The `cluster_cull` pass kind.
pub struct ClusterCullKind;

impl PassKind for ClusterCullKind {
    fn info(&self) -> PassKindInfo {
        let read = |name, doc| slot(name, Usage::StorageBufferRead(Stages::Compute), true, FormatRule::Any, doc);
        let write = |name, doc| {
            slot(name, Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, doc)
                .required()
                .creates(Creates::buffer())
        };
        // Written before it is read in each run.
        let scratch = |name, doc| {
            slot(name, Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, doc)
                .creates(Creates::buffer().always())
        };
        PassKindInfo {
            name: KIND,
            doc: "tests the clusters of the instances a culled list draws (frustum, sample coverage, normal cone, Hi-Z) and writes the list again with those instances drawn cluster by cluster, one command per surviving cluster",
            reads: vec![
                // As large as instance_cull makes them: the pass reads every command its counts
                // name, and the ids its commands name.
                read(LIST_SLOTS[0], "the culled list's commands").at_least("meshes * 20").content(DRAW_COMMANDS),
                read(LIST_SLOTS[1], "their number per region").at_least(COUNT_BYTES).content(DRAW_COUNTS),
                read(LIST_SLOTS[2], "its instance ids (the geometry pass draws both lists with them)").at_least("instances * 4"),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid to test the clusters against (none: frustum, coverage and cones only)"),
            ],
            writes: vec![
                write("pass_commands", "the culled list's commands, those drawn cluster by cluster emptied").at_least("meshes * 20").content(DRAW_COMMANDS),
                write("pass_count", "their number per region (the input's)").at_least(COUNT_BYTES).content(DRAW_COUNTS),
                write("cluster_commands", "one command per surviving cluster, in three equal regions: back, front and no face culling").at_least(CLUSTER_COMMANDS_BYTES),
                write("cluster_count", "the surviving clusters of each region").at_least("16"),
                slot("masked_cluster_commands", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "where bound, with `masked_cluster_count`: the same for the instances of alpha-masked materials (unbound: they are drawn whole)").creates(Creates::buffer()).at_least(MASKED_CLUSTER_COMMANDS_BYTES),
                slot("masked_cluster_count", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "the surviving masked clusters of each region (with `masked_cluster_commands`)").creates(Creates::buffer()).at_least("16"),
                scratch("scratch", "the clustered commands and their test tasks (created when unbound)").at_least(SCRATCH_BYTES),
                scratch("stats", "counters of this pass (created when unbound; read as `pass.stats`)").exactly("48").counters(Counters::ThisFrame),
            ],
            settings: vec![],
            slots_from_shader: false,
        }
    }

    fn quantities(&self) -> Vec<Quantity> {
        vec![CLUSTERS, MASKED_CLUSTERS]
    }

    fn validate(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let mut errors = Vec::new();
        // The clusters are projected with this frame's camera: last frame's pyramid would need
        // last frame's (and could drop what became visible since).
        if let Some(b) = check.binding("hiz").filter(|b| b.version == Version::Previous) {
            errors.push((
                b.pos,
                format!(
                    "pass '{}' ({KIND}): `hiz` must be this frame's pyramid, not '{}.prev' (clusters are tested with this frame's camera)",
                    check.pass.name,
                    check.resource_name(b)
                ),
            ));
        }
        errors.extend(masked_pair_error(check, check.pass.name.as_str()));
        errors
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        let bound = |slot: &str| s.pass.bindings.iter().any(|b| b.slot == slot);
        let mut defines: Vec<(&str, &str)> = Vec::new();
        if bound("hiz") {
            defines.push(("HAS_HIZ", "1"));
        }
        let masked: &[(&str, &str)] = if bound("masked_cluster_commands") { &[("MASKED", "1")] } else { &[] };
        defines.extend(masked);
        // The coverage test knows the standard sample positions only.
        if crate::passes::instance_cull::standard_sample_locations(s.ctx) {
            defines.push(("SMALL_OBJECTS", "1"));
        }
        let prepare = s.shaders.compile("cluster_cull/cluster_prepare.comp", masked)?;
        let test = s.shaders.compile("cluster_cull/cluster_cull.comp", &defines)?;
        let dispatch = Buffer::new(
            s.ctx,
            &BufferDesc {
                name: &format!("{} dispatch", s.pass.name),
                size: 16,
                usage: vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        Ok(Box::new(ClusterCullPass {
            prepare: Pipeline::compute(s.ctx, &format!("{} prepare", s.pass.name), &prepare)?,
            test: Pipeline::compute(s.ctx, &format!("{} test", s.pass.name), &test)?,
            sampler: Sampler::nearest_clamp(s.ctx)?,
            dispatch,
        }))
    }

    fn decode_counters(&self, pass: &str, _slot: &str, bytes: &[u8]) -> Option<CounterEntry> {
        let c: ClusterCounters = bytemuck::try_pod_read_unaligned(bytes).ok()?;
        let value = serde_json::to_value(ClusterPassStats::new(pass, &c)).ok()?;
        Some(CounterEntry { group: GROUP, value, draws: None })
    }
}

/// What a geometry pass needs to draw a cluster list: its regions' capacity.
pub fn region_capacity(cluster_commands: &Buffer) -> u32 {
    (cluster_commands.size() / COMMAND_BYTES / CLUSTER_REGIONS).min(u32::MAX as u64) as u32
}

/// What is wrong with a pass's masked cluster slots (`masked_cluster_commands` and
/// `masked_cluster_count`), if anything: one bound without the other.
pub(crate) fn masked_pair_error(check: &KindCheck<'_>, pass: &str) -> Option<(Pos, String)> {
    let [commands, count] = MASKED_LIST_SLOTS.map(|s| check.binding(s));
    match (commands, count) {
        (Some(b), None) | (None, Some(b)) => Some((
            b.pos,
            format!("pass '{pass}': `masked_cluster_commands` and `masked_cluster_count` are bound together"),
        )),
        _ => None,
    }
}

/// The slots of the masked instances' cluster list.
pub(crate) const MASKED_LIST_SLOTS: [&str; 2] = ["masked_cluster_commands", "masked_cluster_count"];

/// Records the draws of a cluster list (`commands`, `count`): one `vkCmdDrawIndexedIndirectCount`
/// per region, with its cull mode (`regions`: [`FaceCull::OPAQUE`] for the opaque instances'
/// list, [`FaceCull::MASKED`] for the masked ones', each list's regions in that order). Inside
/// a rendering scope with a geometry pipeline bound whose cull mode is dynamic (one that
/// alpha-tests for the masked list).
pub fn record_cluster_draws(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    commands: &Buffer,
    count: &Buffer,
    regions: [FaceCull; 3],
) {
    let capacity = region_capacity(commands);
    if capacity == 0 || count.size() < 4 * CLUSTER_REGIONS {
        return;
    }
    for (r, face_cull) in regions.into_iter().enumerate() {
        let r = r as u64;
        // SAFETY: cmd is recording inside a rendering scope; the buffers outlive its execution.
        unsafe {
            ctx.device().cmd_set_cull_mode(cmd, face_cull.mode());
            ctx.device().cmd_draw_indexed_indirect_count(
                cmd,
                commands.handle(),
                r * capacity as u64 * COMMAND_BYTES,
                count.handle(),
                r * 4,
                capacity,
                COMMAND_BYTES as u32,
            );
        }
    }
}

/// The clusters a cluster list drew, from host copies of its commands and counts and of its
/// list's instance ids: (instance id, first index of the cluster's range) each, region after
/// region.
pub(crate) fn clusters_drawn(ids: &[u32], commands: &[u8], counts: &[u8]) -> Vec<(u32, u32)> {
    let stride = std::mem::size_of::<DrawIndexedIndirect>();
    let commands: Vec<DrawIndexedIndirect> = commands.chunks_exact(stride).map(bytemuck::pod_read_unaligned).collect();
    let counts: Vec<u32> = counts.chunks_exact(4).map(bytemuck::pod_read_unaligned).collect();
    let capacity = commands.len() / CLUSTER_REGIONS as usize;
    let mut out = Vec::new();
    for (r, &count) in counts.iter().take(CLUSTER_REGIONS as usize).enumerate() {
        for c in &commands[r * capacity..r * capacity + (count as usize).min(capacity)] {
            if let Some(&id) = ids.get(c.first_instance as usize) {
                out.push((id, c.first_index));
            }
        }
    }
    out
}

/// The slot declarations a geometry pass adds to draw a cluster list.
pub(crate) fn cluster_list_slots() -> [SlotDecl; 4] {
    [
        slot(
            "cluster_commands",
            Usage::Indirect,
            false,
            FormatRule::Any,
            "a cluster_cull pass's cluster list, drawn after the draw list with its instance ids",
        ),
        slot("cluster_count", Usage::Indirect, false, FormatRule::Any, "its counts per region (with cluster_commands)")
            .at_least("16"),
        slot(
            "masked_cluster_commands",
            Usage::Indirect,
            false,
            FormatRule::Any,
            "a cluster_cull pass's list of the alpha-masked instances' clusters, drawn with the alpha-tested pipelines",
        ),
        slot(
            "masked_cluster_count",
            Usage::Indirect,
            false,
            FormatRule::Any,
            "its counts per region (with masked_cluster_commands)",
        )
        .at_least("16"),
    ]
}
