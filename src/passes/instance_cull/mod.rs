//! The instance-cull pass (ICR/HOCR in one): tests every instance's world bound against the
//! frustum and, when a Hi-Z pyramid is bound, the conservative occlusion test, then compacts the
//! survivors in slot order into one slice per draw group, with a
//! `VkDrawIndexedIndirectCommand` per non-empty group and a draw count for
//! `vkCmdDrawIndexedIndirectCount`. No CPU readback anywhere.
//!
//! Two dispatches (`shaders/cull/`): `instance_cull.comp` (one thread per slot decides; each
//! block stores its decision bits and survivor count, adds its counts to its superblock's record
//! and each group's survivors to the group's count) and `cull_compact.comp` (workgroup 0 writes
//! the commands from the group counts; every other workgroup sums the counts before its block and
//! writes its survivors' instance ids in slot order). No workgroup ever waits for another: Vulkan
//! does not promise that such waits make progress (a decoupled look-back hangs on lavapipe).
//! Nothing is cleared between runs: the compact step zeroes the group counts and the next run's
//! half of the superblock records (see `cull_common.glsl`).
//!
//! Where the scene has a bound per block of 256 slots (`crate::passes::shared::cull_blocks`),
//! a third dispatch comes first, the block step (one
//! invocation per block, `BLOCK_STEP` in `instance_cull.comp`): a block wholly outside the
//! frustum, or wholly inside it and behind the Hi-Z, gets what the test step would have written
//! for it, and the others are listed. The test step then runs only the listed blocks: dispatched
//! with their number (`vkCmdDispatchIndirect`) from `LISTED_DISPATCH_FROM_BLOCKS` blocks on, else
//! a workgroup per block, those past the number returning at once. The compact step zeroes the
//! number for the next run.
//!
//! Both kernels combine values with subgroup operations (basic, vote, arithmetic and ballot in
//! compute shaders, which Vulkan 1.3 devices commonly have), never assuming a subgroup size.
//!
//! Last frame's visible set as the early draw list: with `visible_ids`, `list_commands`,
//! `list_count` and `list_stats` bound, the late phase also compacts its visible slots' instance
//! ids per group (in slot order) and writes that list's commands, count and counters. The next
//! frame's early draw reads them as they are (`.prev` of those history buffers): there is no
//! early cull pass at all. This is the two-phase scheme as stated (draw last frame's visible
//! set); it saves the early test over every slot and then the early pass's own dispatch, whose
//! cost is mostly fixed latency. Instances that left the frustum since last frame are drawn and
//! clipped: they cannot change the image.
//!
//! The thesis's atomic append (`compaction: "atomic"`) is kept as a measured variant:
//! `cull_init.comp` then the test step appending with atomics; its order within a group varies
//! from run to run.

pub mod counters;
mod views;

use super::slots::{
    slot, COMMANDS_BYTES, COUNTERS_BYTES, COUNT_BYTES, DRAW_COMMANDS, DRAW_COUNTS, HIZ_FORMAT, IDS_BYTES,
    INSTANCE_BITS, INSTANCE_IDS,
};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, Buffer, BufferDesc, GpuContext, MemoryLocation, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::PlannedPass;
use crate::graph::{
    Choice, CounterEntry, Counters, Creates, FormatRule, KindCheck, NodeSetup, PassKind, PassKindInfo, PassNode, Pos,
    SettingDecl, Stages, Usage,
};
use crate::passes::shared::instance_ranges::most_instances;
use crate::passes::shared::SceneInputs;
use ash::vk;
pub use counters::{CullCounters, CullPassStats};
use std::sync::atomic::{AtomicU32, Ordering};

/// The kind's name in RON.
pub(crate) const KIND: &str = "instance_cull";

/// The largest `lod_threshold`, in pixels: past it every level is as good as any other.
pub const MAX_LOD_THRESHOLD: f64 = 1.0e6;

/// The slot of the counters of the list the late phase writes for the next frame.
pub(crate) const LIST_STATS_SLOT: &str = "list_stats";

/// Slots per block of the prefix sum (`CULL_BLOCK` in `cull_common.glsl`).
pub(crate) const CULL_BLOCK: u32 = crate::passes::shared::cull_blocks::CULL_BLOCK;

crate::choice! {
    /// Which instances a cull pass draws (setting `phase`).
    pub enum Phase {
        /// Every survivor.
        All = "all",
        /// Last frame's visible ones.
        Early = "early",
        /// The newly visible ones (and this frame's visibility).
        Late = "late",
        /// The chosen occluders.
        Occluders = "occluders",
        /// All but the occluders.
        Rest = "rest",
    }
}

crate::choice! {
    /// The world bound a cull pass tests (setting `bound`).
    pub enum Bound {
        /// The axis-aligned box.
        Box = "box",
        /// The sphere.
        Sphere = "sphere",
    }
}

crate::choice! {
    /// The occlusion footprint (setting `hiz_test`).
    pub enum HizTest {
        /// At most 2x2 texels.
        Coarse = "coarse",
        /// Up to 3x3 texels one level finer (culls more).
        Finer = "finer",
    }
}

crate::choice! {
    /// The camera the occlusion test projects with (setting `hiz_view`).
    pub enum HizView {
        /// This frame's.
        Current = "current",
        /// Last frame's (a test against last frame's pyramid).
        Previous = "previous",
    }
}

crate::choice! {
    /// How survivors are compacted (setting `compaction`).
    pub enum Compaction {
        /// A prefix sum in slot order (the unculled draw order).
        Ordered = "ordered",
        /// The thesis's atomic append (order varies; measured only).
        Atomic = "atomic",
    }
}

impl Phase {
    /// The shader's define for this phase.
    fn define(self) -> &'static str {
        match self {
            Phase::All => "PHASE_ALL",
            Phase::Early => "PHASE_EARLY",
            Phase::Late => "PHASE_LATE",
            Phase::Occluders => "PHASE_OCCLUDERS",
            Phase::Rest => "PHASE_REST",
        }
    }
}

/// The pass's settings, from the graph.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CullSettings {
    /// Which instances it draws.
    pub phase: Phase,
    /// Test the frustum.
    pub frustum: bool,
    /// Cull bounds that cover no sample position (with the frustum test).
    pub small_objects: bool,
    /// The bound tested.
    pub bound: Bound,
    /// The occlusion footprint.
    pub hiz_test: HizTest,
    /// The camera of the occlusion test.
    pub hiz_view: HizView,
    /// The compaction.
    pub compaction: Compaction,
    /// Occluder choice: farthest distance.
    pub occluder_distance: f32,
    /// Occluder choice: smallest projected radius over the view height.
    pub occluder_size: f32,
    /// Occluder choice: meshes this cheap are candidates without the occluder flag (0: none).
    pub occluder_triangles: u32,
    /// The largest error, in pixels, a level of detail may show (0: always the full mesh).
    pub lod_threshold: f32,
}

impl CullSettings {
    /// Reads the planned pass's settings (validation filled every default).
    pub fn from_plan(pass: &PlannedPass) -> crate::Result<Self> {
        Ok(Self {
            phase: pass.choice("phase")?,
            frustum: pass.flag("frustum")?,
            small_objects: pass.flag("small_objects")?,
            bound: pass.choice("bound")?,
            hiz_test: pass.choice("hiz_test")?,
            hiz_view: pass.choice("hiz_view")?,
            compaction: pass.choice("compaction")?,
            occluder_distance: pass.real("occluder_distance")? as f32,
            occluder_size: pass.real("occluder_size")? as f32,
            // The declared range keeps it within a u32.
            occluder_triangles: pass.int("occluder_triangles")?.clamp(0, u32::MAX as i64) as u32,
            lod_threshold: pass.real("lod_threshold")? as f32,
        })
    }

    /// Whether the pass chooses levels of detail.
    pub fn lod(&self) -> bool {
        self.lod_threshold > 0.0
    }

    /// Why these settings cannot choose levels of detail, if they cannot: the atomic append has
    /// no order to place levels in.
    pub fn lod_error(&self) -> Option<String> {
        (self.lod() && self.compaction == Compaction::Atomic).then(|| {
            format!(
                "a level-of-detail threshold ({} px) needs ordered compaction; this pass has atomic compaction",
                self.lod_threshold
            )
        })
    }

    /// Why these settings cannot write the next frame's early draw list, if they cannot: only
    /// the late phase with ordered compaction writes it.
    pub fn list_error(&self) -> Option<String> {
        (self.phase != Phase::Late || self.compaction == Compaction::Atomic).then(|| {
            format!(
                "the next frame's early draw list (`visible_ids`, `list_commands`, `list_count`) is written by the \
                 late phase with ordered compaction; this pass is phase \"{}\" with {} compaction",
                self.phase.word(),
                self.compaction.word()
            )
        })
    }
}

/// Scratch memory sized for one scene.
struct Scratch {
    slots: u32,
    groups: u32,
    /// Run numbers, two halves of superblock records, survivors and visible slots per block
    /// (`cull_common.glsl`).
    scan: Buffer,
    /// One bit per slot: drawn by this pass.
    draw_bits: Buffer,
    /// With levels of detail: each slot's level, as three bit planes.
    level_bits: Option<Buffer>,
    /// Survivors of each draw group, then visible slots of each (zero between runs).
    group_counts: Buffer,
    /// With a block step: the blocks it leaves to the test step (`BlockList` in
    /// `instance_cull.comp`).
    block_list: Option<Buffer>,
    /// Whether the scan buffer still needs its first clear.
    fresh: bool,
}

/// The instance-cull pass.
pub(crate) struct InstanceCullPass {
    settings: CullSettings,
    test: Pipeline,
    compact: Option<Pipeline>,
    /// Before the test step, where the scene has block bounds: decides the blocks of slots
    /// that their bounds decide, and lists the others for the test step.
    blocks: Option<Pipeline>,
    /// With levels of detail: where each superblock's slots of each level start, between the
    /// test and the compact steps.
    levels: Option<Pipeline>,
    init: Option<Pipeline>,
    sampler: Sampler,
    scratch: Option<Scratch>,
    /// Scratch buffers replaced at a frame (the scene's slots or groups changed), kept until the
    /// frames that used them can no longer be executing.
    retired_scratch: Vec<(u64, Scratch)>,
    /// The test step's variant: with equal ones (and settings), passes of several views are
    /// culled together.
    defines: Vec<(String, String)>,
    /// The pipelines of culling several views in one dispatch, where the device gives buffers
    /// addresses (ordered compaction only).
    together: Option<views::Together>,
}

impl InstanceCullPass {
    /// Compiles the variant the pass's settings and bindings ask for.
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler, pass: &PlannedPass) -> crate::Result<Self> {
        let settings = CullSettings::from_plan(pass)?;
        let ops = ctx.caps().subgroup_compute_ops;
        let needed = vk::SubgroupFeatureFlags::BASIC
            | vk::SubgroupFeatureFlags::VOTE
            | vk::SubgroupFeatureFlags::ARITHMETIC
            | vk::SubgroupFeatureFlags::BALLOT;
        if !ops.contains(needed) {
            return Err(crate::Error::Invalid(format!(
                "pass '{}': instance_cull needs subgroup operations {needed:?} in compute shaders; the device has {ops:?}",
                pass.name
            )));
        }
        let bound = |slot: &str| pass.bindings.iter().any(|b| b.slot == slot);
        let invalid = |m: &str| crate::Error::Invalid(format!("pass '{}': {m}", pass.name));
        if let Some((_, message)) = list_binding_error(bound) {
            return Err(invalid(&message));
        }
        let visible_out = bound("visible_ids");
        // Checked when the graph is compiled too (a setting may come from a parameter).
        if let Some(message) = settings.list_error().filter(|_| visible_out) {
            return Err(invalid(&message));
        }
        if let Some(message) = settings.lod_error() {
            return Err(invalid(&message));
        }
        let atomic = settings.compaction == Compaction::Atomic;
        let mut defines: Vec<(&str, &str)> = vec![(settings.phase.define(), "1")];
        let flags = [
            (!settings.frustum, "NO_FRUSTUM"),
            // The sample positions tested are Vulkan's standard ones.
            (settings.frustum && settings.small_objects && standard_sample_locations(ctx), "SMALL_OBJECTS"),
            (settings.bound == Bound::Sphere, "BOUND_SPHERE"),
            (settings.hiz_test == HizTest::Finer, "HIZ_FINER"),
            (settings.hiz_view == HizView::Previous, "HIZ_PREV_VIEW"),
            (bound("hiz"), "HAS_HIZ"),
            (bound("visibility_prev"), "HAS_VIS_PREV"),
            (bound("visibility"), "WRITE_VIS"),
            (atomic, "ATOMIC_APPEND"),
            (visible_out, "VISIBLE_OUT"),
            (settings.lod(), "LOD"),
            // A block of slots decided whole (its slots' records unread) where the scene has
            // block bounds: every test whose outcome a block's bound implies for its slots.
            (block_tests(&settings, atomic), "BLOCK_BOUNDS"),
        ];
        defines.extend(flags.iter().filter(|(on, _)| *on).map(|(_, name)| (*name, "1")));
        let name = |step: &str| format!("{} ({step})", pass.name);
        let test = Pipeline::compute(ctx, &name("test"), &shaders.compile("cull/instance_cull.comp", &defines)?)?;
        let compute = |step: &str, file: &str, defines: &[(&str, &str)]| -> crate::Result<Pipeline> {
            Ok(Pipeline::compute(ctx, &name(step), &shaders.compile(file, defines)?)?)
        };
        let blocks = match block_tests(&settings, atomic) {
            true => Some(compute(
                "blocks",
                "cull/instance_cull.comp",
                &[defines.as_slice(), &[("BLOCK_STEP", "1")]].concat(),
            )?),
            false => None,
        };
        let (compact, init) = if atomic {
            (None, Some(compute("init", "cull/cull_init.comp", &[])?))
        } else {
            let defines: Vec<(&str, &str)> =
                [(visible_out, "VISIBLE_OUT"), (settings.lod(), "LOD"), (block_tests(&settings, atomic), "BLOCK_LIST")]
                    .iter()
                    .filter(|(on, _)| *on)
                    .map(|(_, d)| (*d, "1"))
                    .collect();
            (Some(compute("compact", "cull/cull_compact.comp", &defines)?), None)
        };
        let levels = match settings.lod() {
            true => Some(compute("levels", "cull/cull_levels.comp", &[])?),
            false => None,
        };
        let defines: Vec<(String, String)> = defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        let together = match ctx.caps().buffer_addresses && !atomic {
            true => Some(views::Together::new(ctx, shaders, &pass.name, &defines)?),
            false => None,
        };
        Ok(Self {
            settings,
            test,
            compact,
            blocks,
            levels,
            init,
            sampler: Sampler::nearest_clamp(ctx)?,
            scratch: None,
            retired_scratch: Vec::new(),
            defines,
            together,
        })
    }

    /// Scratch buffers for `slots` instances and `groups` draw groups at frame `frame` (created
    /// on first use, and made anew when the scene's counts change: the ones replaced are kept
    /// until the frames in flight that use them have completed).
    fn ensure_scratch(&mut self, ctx: &GpuContext, slots: u32, groups: u32, frame: u64) -> crate::Result<()> {
        self.retired_scratch.retain(|(replaced, _)| frame < replaced + crate::graph::FRAMES_IN_FLIGHT as u64);
        if self.scratch.as_ref().is_none_or(|s| s.slots != slots || s.groups != groups) {
            if let Some(old) = self.scratch.take() {
                self.retired_scratch.push((frame, old));
            }
            let blocks = blocks_of(slots) as u64;
            let buffer = |name: &str, size: u64, usage: vk::BufferUsageFlags| {
                Buffer::new(
                    ctx,
                    &BufferDesc {
                        name,
                        size,
                        usage: usage | vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuOnly,
                    },
                )
            };
            let storage = |name: &str, size: u64| buffer(name, size, vk::BufferUsageFlags::empty());
            let superblocks = blocks.div_ceil(CULL_SUPERBLOCK as u64);
            let lod = self.levels.is_some();
            // With levels of detail: more words per superblock record, a count per list, block
            // and level after the block counts, and a group count per level.
            let (superblock_words, level_words, levels) = match lod {
                // Counts per list, block and level, then starts per superblock, list and level.
                true => (SUPERBLOCK_WORDS_LOD, 2 * (blocks + superblocks) * LOD_LEVELS, LOD_LEVELS),
                false => (SUPERBLOCK_WORDS, 0, 1),
            };
            let bit_words = blocks * (CULL_BLOCK as u64 / 32);
            self.scratch = Some(Scratch {
                slots,
                groups,
                scan: storage(
                    "cull scan state",
                    (SCAN_HEADER_WORDS + 2 * superblocks * superblock_words + 2 * blocks + level_words) * 4,
                )?,
                draw_bits: storage("cull draw bits", bit_words * 4)?,
                level_bits: match lod {
                    true => Some(storage("cull level bits", LOD_PLANES * bit_words * 4)?),
                    false => None,
                },
                // Per list and level each group's count, then (groups out of slot order) its
                // first instance.
                group_counts: storage("cull group counts", 4 * levels * groups.max(1) as u64 * 4)?,
                block_list: match self.blocks.is_some() {
                    // Its first words are the test step's dispatch size.
                    true => Some(buffer("cull block list", (4 + blocks) * 4, vk::BufferUsageFlags::INDIRECT_BUFFER)?),
                    false => None,
                },
                fresh: true,
            });
        }
        Ok(())
    }
}

/// The late phase's bindings for the next frame's early draw list, written together (with its
/// counters, `list_stats`, which the kind creates with them).
pub(crate) const LIST_SLOTS: [&str; 3] = ["visible_ids", "list_commands", "list_count"];

/// What is wrong with an instance_cull pass's draw-list bindings, if anything: the slot to point
/// at (empty: the pass itself) and the message. Graph loading reports it at that binding; the
/// pass checks it again when it is built.
pub(crate) fn list_binding_error(bound: impl Fn(&str) -> bool) -> Option<(&'static str, String)> {
    let first_bound = LIST_SLOTS.iter().copied().find(|s| bound(s))?;
    if let Some(missing) = LIST_SLOTS.iter().find(|s| !bound(s)) {
        return Some((
            first_bound,
            format!(
                "the next frame's early draw list is written whole: `{missing}` is missing (bind {} together)",
                LIST_SLOTS.map(|s| format!("`{s}`")).join(", ")
            ),
        ));
    }
    if !bound("visibility") {
        return Some((
            "visible_ids",
            "`visible_ids` needs `visibility` bound: the late phase that writes this frame's visibility writes the list"
                .into(),
        ));
    }
    None
}

/// Words before the superblock records in the scan buffer (`SCRATCH_HEADER`).
const SCAN_HEADER_WORDS: u64 = 8;
/// Words of one superblock record (`SUPER_WORDS`).
const SUPERBLOCK_WORDS: u64 = 8;
/// Words of one superblock record with levels of detail (`SUPER_WORDS` with `LOD`).
const SUPERBLOCK_WORDS_LOD: u64 = 24;
/// Levels a pass choosing levels of detail counts (`LOD_LEVELS` with `LOD`).
const LOD_LEVELS: u64 = crate::scene::MAX_LOD_LEVELS as u64;
/// Bit planes of a slot's level (`LOD_PLANES`).
const LOD_PLANES: u64 = 3;

/// Blocks of `CULL_BLOCK` slots (test workgroups): at least one, so that an empty scene still
/// writes an empty draw list.
/// Whether the device rasterizes at Vulkan's standard sample positions, the ones the
/// small-object test knows.
pub(crate) fn standard_sample_locations(ctx: &GpuContext) -> bool {
    // SAFETY: valid handles.
    let properties = unsafe { ctx.instance().get_physical_device_properties(ctx.physical_device()) };
    properties.limits.standard_sample_locations == vk::TRUE
}

/// Whether a test step of `settings` decides blocks of slots whole where the scene has block
/// bounds (`BLOCK_BOUNDS`): box bounds tested against the frustum, in every phase but the early
/// one (which tests only last frame's visible slots, so a block's count would not be its
/// slots').
fn block_tests(settings: &CullSettings, atomic: bool) -> bool {
    settings.frustum && settings.bound == Bound::Box && settings.phase != Phase::Early && !atomic
}

fn blocks_of(slots: u32) -> u32 {
    slots.div_ceil(CULL_BLOCK).max(1)
}

/// Workgroups that place the survivors of a single view's blocks (`place_blocks` in
/// `cull_compact.comp`), each every `COMPACT_PLACERS`-th block: enough to spread the blocks that
/// hold survivors, few enough that the launch does not cost more than reading the blocks'
/// counts (a workgroup per block took 0.26 ms at 10^8 instances on an H200).
const COMPACT_PLACERS: u32 = 2048;

/// Blocks per superblock (`CULL_SUPERBLOCK` in `cull_common.glsl`).
pub(crate) const CULL_SUPERBLOCK: u32 = 64;

/// Compute writes before compute reads and writes of the next step.
/// From how many blocks of slots the test step is dispatched with the number the block step
/// listed (indirect) instead of a workgroup per block. Below it the barrier that an indirect
/// read needs costs more than launching the unlisted workgroups (`docs/culling.md`, "Blocks
/// decided by their bounds", has the measurements).
const LISTED_DISPATCH_FROM_BLOCKS: u32 = 16_384;

/// `LISTED_DISPATCH_FROM_BLOCKS`, or what a test set.
static LISTED_DISPATCH_FROM: AtomicU32 = AtomicU32::new(LISTED_DISPATCH_FROM_BLOCKS);

/// Dispatches every following cull test step of this process with the listed number of blocks
/// from `blocks` blocks on (`None`: from the default again), so that tests cover both dispatches
/// on small scenes. Results do not depend on it.
#[doc(hidden)]
pub fn set_listed_dispatch_from_for_tests(blocks: Option<u32>) {
    LISTED_DISPATCH_FROM.store(blocks.unwrap_or(LISTED_DISPATCH_FROM_BLOCKS), Ordering::Relaxed);
}

/// Whether a test step over `blocks` blocks takes its dispatch size from the block step's list:
/// where there are enough blocks, and one row of workgroups holds them all (the list's size is
/// a row).
fn listed_dispatch(ctx: &GpuContext, blocks: u32) -> bool {
    blocks >= LISTED_DISPATCH_FROM.load(Ordering::Relaxed)
        && crate::gpu::line_dispatch::grid(blocks, &ctx.caps().limits).1 == 1
}

/// What the test step does with the block step's list: reads its size as the dispatch's
/// (indirect) and its entries in the shader.
const LISTED_BLOCKS_READ: Access = Access {
    stage: vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags2::DRAW_INDIRECT.as_raw(),
    ),
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
            | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw()
            | vk::AccessFlags2::INDIRECT_COMMAND_READ.as_raw(),
    ),
    layout: vk::ImageLayout::GENERAL,
};

/// Records the first clear of a block list (`BlockList` in `instance_cull.comp`): no block
/// listed, and the rest of the test step's dispatch size (1, 1).
pub(super) fn clear_block_list(device: &ash::Device, cmd: vk::CommandBuffer, list: vk::Buffer) {
    // SAFETY: cmd recording; the list is the pass's own, at least four words long, and the
    // caller orders these transfers against its other uses.
    unsafe {
        device.cmd_fill_buffer(cmd, list, 0, 4, 0);
        device.cmd_fill_buffer(cmd, list, 4, 8, 1);
        device.cmd_fill_buffer(cmd, list, 12, vk::WHOLE_SIZE, 0);
    }
}

fn step_barrier(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    cmd_barriers(ctx.device(), cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);
}

impl PassNode for InstanceCullPass {
    /// The scratch buffers its commands name (made anew when the slots or groups change), and
    /// whether they still need their first clear.
    fn replay_state(&self) -> Option<u64> {
        use ash::vk::Handle;
        Some(self.scratch.as_ref().map_or(0, |s| s.scan.handle().as_raw().wrapping_mul(2) | u64::from(s.fresh)))
    }

    fn together_key(&self) -> Option<u64> {
        use std::hash::{Hash, Hasher};
        self.together.as_ref()?;
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        self.defines.hash(&mut hasher);
        let s = &self.settings;
        // Views culled together take one threshold (each chooses levels in its own pixels).
        (s.occluder_distance.to_bits(), s.occluder_size.to_bits(), s.occluder_triangles, s.lod_threshold.to_bits())
            .hash(&mut hasher);
        Some(hasher.finish())
    }

    fn record_together(
        &mut self,
        contexts: &[PassContext<'_>],
        others: &mut [&mut (dyn PassNode + 'static)],
    ) -> crate::Result<()> {
        self.record_views(contexts, others)
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(self)
    }

    /// A pass that chooses levels of detail takes another threshold as it is (a push constant,
    /// 0 drawing every mesh whole); one that chooses none is made again to choose them.
    fn live_settings(&self) -> &'static [&'static str] {
        match self.levels.is_some() {
            true => &["lod_threshold"],
            false => &[],
        }
    }

    fn apply_settings(&mut self, pass: &PlannedPass) -> crate::Result<()> {
        self.settings.lod_threshold = pass.real("lod_threshold")? as f32;
        Ok(())
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let (ctx, cmd, frame) = (rec.ctx, rec.cmd, SceneInputs::of(rec)?);
        let scene = &frame.scene;
        let slots = scene.instance_count;
        let groups = scene.regions.groups();
        let most = most_instances(ctx.caps().limits.max_storage_buffer_range as u64);
        if slots as u64 > most {
            return Err(crate::Error::Invalid(format!(
                "instance_cull culls at most {most} instances on this device (its cull records are bound whole, \
                 maxStorageBufferRange); the scene has {slots}"
            )));
        }
        let need = |slot: &str| rec.slots.required_buffer(slot);
        let (commands, draw_count) = (need("draw_commands")?, need("draw_count")?);
        let (draw_ids, stats) = (need("draw_instance_ids")?, need("stats")?);
        self.ensure_scratch(ctx, slots, groups, rec.frame.frame)?;
        let device = ctx.device();
        let scratch = self.scratch.as_mut().expect("ensured above");
        if scratch.fresh {
            // Run number, superblock records and group counts to zero: once, before the first
            // run (each run's compact step leaves what the next one adds to at zero).
            // SAFETY: cmd recording; the buffers are the pass's own.
            unsafe {
                device.cmd_fill_buffer(cmd, scratch.scan.handle(), 0, vk::WHOLE_SIZE, 0);
                device.cmd_fill_buffer(cmd, scratch.group_counts.handle(), 0, vk::WHOLE_SIZE, 0);
                if let Some(list) = &scratch.block_list {
                    clear_block_list(device, cmd, list.handle());
                }
            }
            cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::COMPUTE_WRITE)], &[]);
            scratch.fresh = false;
        }
        // Last frame's run of this pass used the same scratch.
        step_barrier(ctx, cmd);
        let scratch = self.scratch.as_ref().expect("ensured above");
        let blocks = blocks_of(slots);
        let superblocks = blocks.div_ceil(CULL_SUPERBLOCK);

        let mut test_binds = vec![
            Bind::Buffer(0, scene.cull_records.handle()),
            Bind::Buffer(1, frame.constants().handle()),
            Bind::Buffer(2, scene.draw_groups.handle()),
        ];
        if let Some(prev) = rec.slots.buffer("visibility_prev") {
            test_binds.push(Bind::Buffer(7, prev.handle()));
        }
        if let Some(vis) = rec.slots.buffer("visibility") {
            test_binds.push(Bind::Buffer(8, vis.handle()));
        }
        if let Some(hiz) = rec.slots.image("hiz") {
            test_binds.push(Bind::Sampled(
                9,
                hiz.view(),
                self.sampler.handle(),
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            ));
        }
        if let Some(level_bits) = &scratch.level_bits {
            test_binds.extend([Bind::Buffer(12, scene.lod_levels.handle()), Bind::Buffer(13, level_bits.handle())]);
        }
        // Without block bounds (a changing world's grown scene) the pass tests every slot, and the binding
        // only needs some buffer.
        if let Some(list) = &scratch.block_list {
            let block_bounds = scene.block_bounds.as_ref().unwrap_or(&scene.cull_records);
            test_binds.extend([Bind::Buffer(14, block_bounds.handle()), Bind::Buffer(15, list.handle())]);
        }
        #[repr(C)]
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        struct TestPush {
            slot_count: u32,
            superblocks: u32,
            group_count: u32,
            occluder_distance: f32,
            occluder_size: f32,
            occluder_triangles: u32,
            view_count: u32,
            lod_threshold: f32,
            block_test: u32,
        }
        let push = TestPush {
            slot_count: slots,
            superblocks,
            group_count: groups,
            occluder_distance: self.settings.occluder_distance,
            occluder_size: self.settings.occluder_size,
            occluder_triangles: self.settings.occluder_triangles,
            view_count: 1,
            lod_threshold: self.settings.lod_threshold,
            block_test: u32::from(scene.block_bounds.is_some() && self.blocks.is_some()),
        };

        if let Some(init) = &self.init {
            rec.step("init");
            init.bind(cmd);
            init.push_bindings(
                cmd,
                &[
                    Bind::Buffer(0, scene.draw_groups.handle()),
                    Bind::Buffer(1, commands.handle()),
                    Bind::Buffer(2, draw_count.handle()),
                    Bind::Buffer(3, stats.handle()),
                ],
            );
            let mut push = vec![groups];
            push.extend(scene.regions.first);
            init.push_constant_bytes(cmd, bytemuck::cast_slice(&push));
            // SAFETY: cmd recording with the pipeline bound.
            unsafe { device.cmd_dispatch(cmd, groups.div_ceil(256).max(1), 1, 1) };
            step_barrier(ctx, cmd);
            test_binds.extend([
                Bind::Buffer(3, scene.draw_instance_ids.handle()),
                Bind::Buffer(4, draw_ids.handle()),
                Bind::Buffer(5, commands.handle()),
                Bind::Buffer(6, stats.handle()),
            ]);
        } else {
            test_binds.extend([
                Bind::Buffer(4, scratch.group_counts.handle()),
                Bind::Buffer(5, scratch.scan.handle()),
                Bind::Buffer(6, scratch.draw_bits.handle()),
            ]);
        }
        if let (Some(blocks_step), true) = (&self.blocks, push.block_test != 0) {
            rec.step("blocks");
            blocks_step.bind(cmd);
            blocks_step.push_bindings(cmd, &test_binds);
            blocks_step.push_constants(cmd, &push);
            // SAFETY: cmd recording with the pipeline bound; one invocation per block.
            unsafe {
                crate::gpu::line_dispatch::cmd_dispatch_line(device, cmd, &ctx.caps().limits, blocks.div_ceil(256))
            };
            // The test step reads the listed blocks, and its dispatch size if it takes it.
            let test_reads = if listed_dispatch(ctx, blocks) { LISTED_BLOCKS_READ } else { Access::COMPUTE_WRITE };
            cmd_barriers(device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, test_reads)], &[]);
        }
        rec.step("test");
        self.test.bind(cmd);
        self.test.push_bindings(cmd, &test_binds);
        self.test.push_constants(cmd, &push);
        let listed = scratch.block_list.as_ref().filter(|_| push.block_test != 0 && listed_dispatch(ctx, blocks));
        match listed {
            // A workgroup per listed block: the dispatch size is the list's first three words.
            // SAFETY: as above; the block step wrote the size, and the barrier made it visible.
            Some(list) => unsafe { device.cmd_dispatch_indirect(cmd, list.handle(), 0) },
            // A workgroup per block (those past the listed number, if any, return at once).
            // SAFETY: as above.
            None => unsafe { crate::gpu::line_dispatch::cmd_dispatch_line(device, cmd, &ctx.caps().limits, blocks) },
        }
        if self.compact.is_some() {
            step_barrier(ctx, cmd);
        }
        if let Some(levels) = &self.levels {
            rec.step("levels");
            levels.bind(cmd);
            levels.push_bindings(cmd, &[Bind::Buffer(0, scratch.scan.handle())]);
            levels.push_constants(cmd, &[slots, superblocks]);
            // SAFETY: as above.
            unsafe { device.cmd_dispatch(cmd, 1, 1, 1) };
            step_barrier(ctx, cmd);
        }

        if let Some(compact) = &self.compact {
            rec.step("compact");
            compact.bind(cmd);
            let mut compact_binds = vec![
                Bind::Buffer(0, scratch.draw_bits.handle()),
                Bind::Buffer(1, scratch.scan.handle()),
                Bind::Buffer(2, scene.draw_groups.handle()),
                Bind::Buffer(3, scene.draw_instance_ids.handle()),
                Bind::Buffer(4, draw_ids.handle()),
                Bind::Buffer(5, scratch.group_counts.handle()),
                Bind::Buffer(6, commands.handle()),
                Bind::Buffer(7, draw_count.handle()),
                Bind::Buffer(8, stats.handle()),
                Bind::Buffer(16, scene.group_order.handle()),
            ];
            if let Some(list) = &scratch.block_list {
                compact_binds.push(Bind::Buffer(17, list.handle()));
            }
            let optional = [
                (9, rec.slots.buffer("visibility").filter(|_| rec.slots.buffer("visible_ids").is_some())),
                (10, rec.slots.buffer("visible_ids")),
                (11, rec.slots.buffer("list_commands")),
                (12, rec.slots.buffer("list_count")),
                (13, rec.slots.buffer("list_stats")),
            ];
            compact_binds.extend(optional.iter().filter_map(|(b, buf)| buf.map(|buf| Bind::Buffer(*b, buf.handle()))));
            if let Some(level_bits) = &scratch.level_bits {
                compact_binds
                    .extend([Bind::Buffer(14, scene.lod_levels.handle()), Bind::Buffer(15, level_bits.handle())]);
            }
            compact.push_bindings(cmd, &compact_binds);
            let placers = blocks.min(COMPACT_PLACERS);
            let mut push = vec![slots, groups, superblocks];
            push.extend(scene.regions.first);
            push.extend([placers, scene.groups_out_of_slot_order as u32]);
            compact.push_constant_bytes(cmd, bytemuck::cast_slice(&push));
            // Workgroup 0 writes the commands, workgroup 1 + p places every placers-th block from
            // block p on.
            // SAFETY: as above.
            unsafe { crate::gpu::line_dispatch::cmd_dispatch_line(device, cmd, &ctx.caps().limits, placers + 1) };
        }
        Ok(())
    }
}

/// The `instance_cull` pass kind.
pub struct InstanceCullKind;

impl PassKind for InstanceCullKind {
    fn info(&self) -> PassKindInfo {
        let write = |name, doc| slot(name, Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, doc);
        let list = Creates::buffer().history();
        PassKindInfo {
            name: KIND,
            doc: "tests every instance's world bound (frustum, optionally Hi-Z occlusion) and compacts the survivors per draw group in slot order (the unculled draw order) into draw commands for vkCmdDrawIndexedIndirectCount",
            reads: vec![
                slot("visibility_prev", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "last frame's visibility bits (early and late phases)").at_least(INSTANCE_BITS),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid to test against (none: frustum only)"),
            ],
            writes: vec![
                write("draw_commands", "one command per draw group").required().at_least(COMMANDS_BYTES).creates(Creates::buffer()).content(DRAW_COMMANDS),
                write("draw_count", "number of commands of each region: back, front and none for opaque then for masked materials, then transparent").required().at_least(COUNT_BYTES).creates(Creates::buffer()).content(DRAW_COUNTS),
                write("draw_instance_ids", "survivors, one slice per draw group").required().at_least(IDS_BYTES).creates(Creates::buffer()).content(INSTANCE_IDS),
                write("visibility", "this frame's visibility bits (late phase; history: the next frame reads `.prev`)").at_least(INSTANCE_BITS).creates(list),
                write("visible_ids", "late phase, with `visibility`: instance ids of this frame's visible slots, one slice per draw group: the next frame's early draw list, which that frame draws as it is with no cull pass (history; the draw binds `.prev`)").at_least(IDS_BYTES).creates(list).content(INSTANCE_IDS),
                write("list_commands", "late phase, with `visible_ids`: the commands of that list (history)").at_least(COMMANDS_BYTES).creates(list).content(DRAW_COMMANDS),
                write("list_count", "late phase, with `visible_ids`: their number per face-cull region (history)").at_least(COUNT_BYTES).creates(list).content(DRAW_COUNTS),
                write("list_stats", "late phase, with `visible_ids`: that list's counters, reported as the next frame's early draw (created with `visible_ids`)").exactly(COUNTERS_BYTES).creates(list.with("visible_ids")).counters(Counters::NextFramesList { count_slot: "list_count" }),
                write("stats", "counters of this pass (created when unbound; read as `pass.stats`)").exactly(COUNTERS_BYTES).creates(Creates::buffer().always()).counters(Counters::ThisFrame),
            ],
            settings: vec![
                SettingDecl::choice::<Phase>("phase", "which instances the pass draws: all survivors; last frame's visible ones (early); newly visible ones (late); chosen occluders; all but the occluders"),
                SettingDecl::flag("frustum", true, "test against the view frustum (false: keep everything, the no-cull baseline)"),
                SettingDecl::flag("small_objects", false, "with the frustum test: also cull an instance whose screen bound covers no sample position of the standard 1, 2, 4 and 8-sample patterns, which could make no fragment (the image does not change; counted as frustum-culled). Off by default: it pays where many instances are specks, and costs the city's late cull a fifth (docs/culling.md)"),
                SettingDecl::choice::<Bound>("bound", "world bound tested: axis-aligned box or sphere"),
                SettingDecl::choice::<HizTest>("hiz_test", "occlusion footprint: at most 2x2 texels, or up to 3x3 one level finer (culls more)"),
                SettingDecl::choice::<HizView>("hiz_view", "project with this frame's camera, or last frame's (a test against last frame's pyramid)"),
                SettingDecl::choice::<Compaction>("compaction", "prefix-sum compaction in slot order (the unculled draw order), or the thesis's atomic append (order varies, measured only)"),
                SettingDecl::real("occluder_distance", 200.0, (0.0, f64::MAX), "occluders phase: farthest distance of an occluder's bound"),
                SettingDecl::real("occluder_size", 0.02, (0.0, f64::MAX), "occluders phase: smallest projected radius, as a fraction of the view height"),
                SettingDecl::int("occluder_triangles", 1024, (0, u32::MAX as i64), "occluders phase: instances of meshes with at most this many triangles are candidates too, besides those flagged as occluders (0: flagged ones only)"),
                SettingDecl::real("lod_threshold", 0.0, (0.0, MAX_LOD_THRESHOLD), "levels of detail: each instance it draws takes the coarsest level of its mesh whose error, projected conservatively from the nearest point of its bound, is at most this many pixels (0: always the full mesh, today's image bit for bit)"),
            ],
            slots_from_shader: false,
        }
    }

    fn validate(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        // The late phase writes the next frame's early draw list whole: ids, commands, count
        // and counters, with the visibility.
        let pass = check.pass;
        let Some((slot, message)) = list_binding_error(|slot| check.binding(slot).is_some()) else {
            return Vec::new();
        };
        let pos = check.binding(slot).map_or(pass.pos, |b| b.pos);
        vec![(pos, format!("pass '{}' ({KIND}): {message}", pass.name))]
    }

    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let pass = check.pass;
        let mut out = Vec::new();
        if let Some(planned) = check.planned {
            match CullSettings::from_plan(planned) {
                Ok(settings) => {
                    if let Some(visible) = check.binding("visible_ids") {
                        out.extend(settings.list_error().map(|m| (visible.pos, format!("pass '{}': {m}", pass.name))));
                    }
                    out.extend(settings.lod_error().map(|m| (pass.pos, format!("pass '{}': {m}", pass.name))));
                }
                Err(e) => out.push((pass.pos, e.to_string())),
            }
        }
        let instances = check.quantities.and_then(|q| q.get("instances")).unwrap_or(0);
        if let Some(limits) = check.limits {
            let most = most_instances(limits.max_storage_buffer_range);
            if instances > most {
                let message = format!(
                    "pass '{}' ({KIND}) culls at most {most} instances on {} (its cull records are bound whole, \
                     maxStorageBufferRange); the scene has {instances}",
                    pass.name, limits.device
                );
                out.push((pass.pos, message));
            }
        }
        if check.limits.is_some_and(|l| !l.has("subgroup_compute")) {
            let message = format!(
                "pass '{}' ({KIND}) needs basic, vote, arithmetic and ballot subgroup operations in compute shaders, \
                 which {} does not have",
                pass.name,
                check.limits.map_or("", |l| l.device.as_str())
            );
            out.push((pass.pos, message));
        }
        out
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(InstanceCullPass::new(s.ctx, s.shaders, s.pass)?))
    }

    fn decode_counters(&self, pass: &str, _slot: &str, bytes: &[u8]) -> Option<CounterEntry> {
        CullPassStats::entry(pass, bytes)
    }
}
