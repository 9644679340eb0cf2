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

use super::slots::{sized, slot, COMMANDS_BYTES, COUNTERS_BYTES, COUNT_BYTES, HIZ_FORMAT, IDS_BYTES};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, Buffer, BufferDesc, GpuContext, MemoryLocation, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::{PassContext, LIST_COUNT_SLOT, LIST_STATS_SLOT};
use crate::graph::plan::PlannedPass;
use crate::graph::{
    FormatRule, KindCheck, MinBytes, NodeSetup, PassKind, PassKindInfo, PassNode, Pos, SettingDecl, SettingDefault,
    Stages, Usage,
};
use crate::passes::shared::face_cull::DRAW_COUNT_BYTES;
use crate::passes::shared::SceneInputs;
use ash::vk;

/// Slots per block of the prefix sum (`CULL_BLOCK` in `cull_common.glsl`).
pub const CULL_BLOCK: u32 = 256;

/// The pass's settings, from the graph.
#[derive(Clone, Debug, PartialEq)]
pub struct CullSettings {
    /// `all`, `early`, `late`, `occluders` or `rest`.
    pub phase: String,
    /// Test the frustum.
    pub frustum: bool,
    /// Test boxes (true) or spheres.
    pub boxes: bool,
    /// The finer Hi-Z footprint.
    pub finer: bool,
    /// Project with last frame's camera.
    pub previous_view: bool,
    /// Atomic append instead of ordered compaction.
    pub atomic: bool,
    /// Occluder choice: farthest distance.
    pub occluder_distance: f32,
    /// Occluder choice: smallest projected radius over the view height.
    pub occluder_size: f32,
    /// Occluder choice: meshes this cheap are candidates without the occluder flag (0: none).
    pub occluder_triangles: u32,
}

impl CullSettings {
    /// Reads the planned pass's settings (validation filled every default).
    pub fn from_plan(pass: &PlannedPass) -> crate::Result<Self> {
        Ok(Self {
            phase: pass.choice_setting("phase")?.to_string(),
            frustum: pass.bool_setting("frustum")?,
            boxes: pass.choice_setting("bound")? == "box",
            finer: pass.choice_setting("hiz_test")? == "finer",
            previous_view: pass.choice_setting("hiz_view")? == "previous",
            atomic: pass.choice_setting("compaction")? == "atomic",
            occluder_distance: pass.float_setting("occluder_distance")? as f32,
            occluder_size: pass.float_setting("occluder_size")? as f32,
            occluder_triangles: pass.float_setting("occluder_triangles")?.clamp(0.0, u32::MAX as f64) as u32,
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
    /// Survivors of each draw group, then visible slots of each (zero between runs).
    group_counts: Buffer,
    /// Where the counters go when the graph binds no `stats` buffer.
    own_stats: Buffer,
    /// Whether the scan buffer still needs its first clear.
    fresh: bool,
}

/// The instance-cull pass.
pub struct InstanceCullPass {
    /// The pass's name in the graph, for messages.
    name: String,
    settings: CullSettings,
    test: Pipeline,
    compact: Option<Pipeline>,
    init: Option<Pipeline>,
    sampler: Sampler,
    scratch: Option<Scratch>,
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
        // What the bindings cannot say (a setting may come from a parameter): checked here.
        if visible_out && (settings.phase != "late" || settings.atomic) {
            return Err(invalid(
                "the next frame's early draw list (`visible_ids`, `list_*`) is written by the late phase, with ordered compaction",
            ));
        }
        let phase = format!("PHASE_{}", settings.phase.to_uppercase());
        let mut defines: Vec<(&str, &str)> = vec![(phase.as_str(), "1")];
        let flags = [
            (!settings.frustum, "NO_FRUSTUM"),
            (!settings.boxes, "BOUND_SPHERE"),
            (settings.finer, "HIZ_FINER"),
            (settings.previous_view, "HIZ_PREV_VIEW"),
            (bound("hiz"), "HAS_HIZ"),
            (bound("visibility_prev"), "HAS_VIS_PREV"),
            (bound("visibility"), "WRITE_VIS"),
            (settings.atomic, "ATOMIC_APPEND"),
            (visible_out, "VISIBLE_OUT"),
        ];
        defines.extend(flags.iter().filter(|(on, _)| *on).map(|(_, name)| (*name, "1")));
        let name = |step: &str| format!("{} ({step})", pass.name);
        let test = Pipeline::compute(ctx, &name("test"), &shaders.compile("cull/instance_cull.comp", &defines)?)?;
        let compute = |step: &str, file: &str, defines: &[(&str, &str)]| -> crate::Result<Pipeline> {
            Ok(Pipeline::compute(ctx, &name(step), &shaders.compile(file, defines)?)?)
        };
        let (compact, init) = if settings.atomic {
            (None, Some(compute("init", "cull/cull_init.comp", &[])?))
        } else {
            let defines: &[(&str, &str)] = if visible_out { &[("VISIBLE_OUT", "1")] } else { &[] };
            (Some(compute("compact", "cull/cull_compact.comp", defines)?), None)
        };
        Ok(Self {
            name: pass.name.clone(),
            settings,
            test,
            compact,
            init,
            sampler: Sampler::nearest_clamp(ctx)?,
            scratch: None,
        })
    }

    /// Scratch buffers for `slots` instances and `groups` draw groups (created on first use).
    fn ensure_scratch(&mut self, ctx: &GpuContext, slots: u32, groups: u32) -> crate::Result<()> {
        if self.scratch.as_ref().is_none_or(|s| s.slots != slots || s.groups != groups) {
            let blocks = blocks_of(slots) as u64;
            let storage = |name: &str, size: u64| {
                Buffer::new(
                    ctx,
                    &BufferDesc {
                        name,
                        size,
                        usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                        location: MemoryLocation::GpuOnly,
                    },
                )
            };
            let superblocks = blocks.div_ceil(CULL_SUPERBLOCK as u64);
            self.scratch = Some(Scratch {
                slots,
                groups,
                scan: storage(
                    "cull scan state",
                    (SCAN_HEADER_WORDS + 2 * superblocks * SUPERBLOCK_WORDS + 2 * blocks) * 4,
                )?,
                draw_bits: storage("cull draw bits", blocks * (CULL_BLOCK as u64 / 32) * 4)?,
                group_counts: storage("cull group counts", 2 * groups.max(1) as u64 * 4)?,
                own_stats: storage("cull stats (unbound)", 64)?,
                fresh: true,
            });
        }
        Ok(())
    }
}

/// The late phase's bindings for the next frame's early draw list, written together.
pub const LIST_SLOTS: [&str; 4] = ["visible_ids", "list_commands", LIST_COUNT_SLOT, LIST_STATS_SLOT];

/// What is wrong with an instance_cull pass's draw-list bindings, if anything: the slot to point
/// at (empty: the pass itself) and the message. Graph loading reports it at that binding; the
/// pass checks it again when it is built.
pub fn list_binding_error(bound: impl Fn(&str) -> bool) -> Option<(&'static str, String)> {
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

/// Blocks of `CULL_BLOCK` slots (test workgroups): at least one, so that an empty scene still
/// writes an empty draw list.
fn blocks_of(slots: u32) -> u32 {
    slots.div_ceil(CULL_BLOCK).max(1)
}

/// Why a draw count takes 16 bytes (graphs written before face culling declared 4).
const COUNT_RULE: &str =
    "one count per region: back, front, none and transparent; graphs before transparency declared 12, before face culling 4";

/// Blocks per superblock (`CULL_SUPERBLOCK` in `cull_common.glsl`).
pub const CULL_SUPERBLOCK: u32 = 64;

/// Compute writes before compute reads and writes of the next step.
fn step_barrier(ctx: &GpuContext, cmd: vk::CommandBuffer) {
    cmd_barriers(ctx.device(), cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);
}

impl PassNode for InstanceCullPass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let (ctx, cmd, frame) = (rec.ctx, rec.cmd, SceneInputs::of(rec)?);
        let scene = &frame.scene;
        let slots = scene.instance_count;
        let groups = scene.regions.groups();
        if slots as usize > crate::passes::shared::cull_data::MAX_CULL_SLOTS {
            return Err(crate::Error::Invalid(format!(
                "instance_cull handles at most {} instances per pass; the scene has {slots}",
                crate::passes::shared::cull_data::MAX_CULL_SLOTS
            )));
        }
        let need = |slot: &str| {
            rec.slots
                .buffer(slot)
                .ok_or_else(|| crate::Error::Invalid(format!("instance_cull: nothing bound to '{slot}'")))
        };
        let (commands, draw_count) = (need("draw_commands")?, need("draw_count")?);
        let draw_ids = need("draw_instance_ids")?;
        let (ids_bytes, commands_bytes) = (slots as u64 * 4, groups as u64 * 20);
        let sizes = [
            ("draw_commands", Some(commands), commands_bytes, "meshes * 20"),
            ("draw_instance_ids", Some(draw_ids), ids_bytes, "instances * 4"),
            ("visible_ids", rec.slots.buffer("visible_ids"), ids_bytes, "instances * 4"),
            ("list_commands", rec.slots.buffer("list_commands"), commands_bytes, "meshes * 20"),
            ("draw_count", Some(draw_count), DRAW_COUNT_BYTES, COUNT_RULE),
            ("list_count", rec.slots.buffer("list_count"), DRAW_COUNT_BYTES, COUNT_RULE),
            ("list_stats", rec.slots.buffer("list_stats"), 64, "64"),
        ];
        for (slot, buffer, need, rule) in sizes {
            if let Some(buffer) = buffer.filter(|b| b.size() < need) {
                return Err(crate::Error::Invalid(format!(
                    "pass '{}' (instance_cull): {slot} needs {need} bytes ({rule}); got {}",
                    self.name,
                    buffer.size()
                )));
            }
        }
        self.ensure_scratch(ctx, slots, groups)?;
        let device = ctx.device();
        let scratch = self.scratch.as_mut().expect("ensured above");
        if scratch.fresh {
            // Run number, superblock records and group counts to zero: once, before the first
            // run (each run's compact step leaves what the next one adds to at zero).
            // SAFETY: cmd recording; the buffers are the pass's own.
            unsafe {
                device.cmd_fill_buffer(cmd, scratch.scan.handle(), 0, vk::WHOLE_SIZE, 0);
                device.cmd_fill_buffer(cmd, scratch.group_counts.handle(), 0, vk::WHOLE_SIZE, 0);
            }
            cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::COMPUTE_WRITE)], &[]);
            scratch.fresh = false;
        }
        // Last frame's run of this pass used the same scratch.
        step_barrier(ctx, cmd);
        let scratch = self.scratch.as_ref().expect("ensured above");
        let stats = rec.slots.buffer("stats").unwrap_or(&scratch.own_stats);
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
        #[repr(C)]
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        struct TestPush {
            slot_count: u32,
            superblocks: u32,
            group_count: u32,
            occluder_distance: f32,
            occluder_size: f32,
            occluder_triangles: u32,
        }
        let push = TestPush {
            slot_count: slots,
            superblocks,
            group_count: groups,
            occluder_distance: self.settings.occluder_distance,
            occluder_size: self.settings.occluder_size,
            occluder_triangles: self.settings.occluder_triangles,
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
            let [first0, first1, first2, first3] = scene.regions.first;
            init.push_constants(cmd, &[groups, first0, first1, first2, first3]);
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
        rec.step("test");
        self.test.bind(cmd);
        self.test.push_bindings(cmd, &test_binds);
        self.test.push_constants(cmd, &push);
        // SAFETY: as above.
        unsafe { device.cmd_dispatch(cmd, blocks, 1, 1) };
        if self.compact.is_some() {
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
            ];
            let optional = [
                (9, rec.slots.buffer("visibility").filter(|_| rec.slots.buffer("visible_ids").is_some())),
                (10, rec.slots.buffer("visible_ids")),
                (11, rec.slots.buffer("list_commands")),
                (12, rec.slots.buffer("list_count")),
                (13, rec.slots.buffer("list_stats")),
            ];
            compact_binds.extend(optional.iter().filter_map(|(b, buf)| buf.map(|buf| Bind::Buffer(*b, buf.handle()))));
            compact.push_bindings(cmd, &compact_binds);
            let [first0, first1, first2, first3] = scene.regions.first;
            compact.push_constants(cmd, &[slots, groups, superblocks, first0, first1, first2, first3]);
            // Workgroup 0 writes the commands, workgroup 1 + b places block b.
            // SAFETY: as above.
            unsafe { device.cmd_dispatch(cmd, blocks + 1, 1, 1) };
        }
        Ok(())
    }
}

/// The `instance_cull` pass kind.
pub struct InstanceCullKind;

impl PassKind for InstanceCullKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "instance_cull",
            doc: "tests every instance's world bound (frustum, optionally Hi-Z occlusion) and compacts the survivors per draw group in slot order (the unculled draw order) into draw commands for vkCmdDrawIndexedIndirectCount",
            reads: vec![
                sized(slot("visibility_prev", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "last frame's visibility bits (early and late phases)"), MinBytes::InstanceBits),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid to test against (none: frustum only)"),
            ],
            writes: vec![
                sized(slot("draw_commands", Usage::StorageBufferWrite(Stages::Compute), true, FormatRule::Any, "one command per draw group (size: meshes * 20)"), COMMANDS_BYTES),
                sized(slot("draw_count", Usage::StorageBufferWrite(Stages::Compute), true, FormatRule::Any, "number of commands of each face-cull region (16 bytes)"), COUNT_BYTES),
                sized(slot("draw_instance_ids", Usage::StorageBufferWrite(Stages::Compute), true, FormatRule::Any, "survivors, one slice per draw group (size: instances * 4)"), IDS_BYTES),
                sized(slot("visibility", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "this frame's visibility bits (late phase)"), MinBytes::InstanceBits),
                sized(slot("visible_ids", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visibility`: instance ids of this frame's visible slots, one slice per draw group: the next frame's early draw list, which that frame draws as it is with no cull pass (size: instances * 4, history; the draw binds `.prev`)"), IDS_BYTES),
                sized(slot("list_commands", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visible_ids`: the commands of that list (size: meshes * 20, history)"), COMMANDS_BYTES),
                sized(slot("list_count", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visible_ids`: their number per face-cull region (size: 16, history)"), COUNT_BYTES),
                sized(slot("list_stats", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visible_ids`: that list's counters, reported as the next frame's early draw (size: 64, history)"), COUNTERS_BYTES),
                sized(slot("stats", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "counters of this pass (size: 64)"), COUNTERS_BYTES),
            ],
            settings: vec![
                SettingDecl { name: "phase", default: SettingDefault::Choice(&["all", "early", "late", "occluders", "rest"]), range: None, doc: "which instances the pass draws: all survivors; last frame's visible ones (early); newly visible ones (late); chosen occluders; all but the occluders" },
                SettingDecl { name: "frustum", default: SettingDefault::Bool(true), range: None, doc: "test against the view frustum (false: keep everything, the no-cull baseline)" },
                SettingDecl { name: "bound", default: SettingDefault::Choice(&["box", "sphere"]), range: None, doc: "world bound tested: axis-aligned box or sphere" },
                SettingDecl { name: "hiz_test", default: SettingDefault::Choice(&["coarse", "finer"]), range: None, doc: "occlusion footprint: at most 2x2 texels, or up to 3x3 one level finer (culls more)" },
                SettingDecl { name: "hiz_view", default: SettingDefault::Choice(&["current", "previous"]), range: None, doc: "project with this frame's camera, or last frame's (a test against last frame's pyramid)" },
                SettingDecl { name: "compaction", default: SettingDefault::Choice(&["ordered", "atomic"]), range: None, doc: "prefix-sum compaction in slot order (the unculled draw order), or the thesis's atomic append (order varies, measured only)" },
                SettingDecl { name: "occluder_distance", default: SettingDefault::Float(200.0), range: None, doc: "occluders phase: farthest distance of an occluder's bound" },
                SettingDecl { name: "occluder_size", default: SettingDefault::Float(0.02), range: None, doc: "occluders phase: smallest projected radius, as a fraction of the view height" },
                SettingDecl { name: "occluder_triangles", default: SettingDefault::Int(1024), range: Some((0.0, u32::MAX as f64)), doc: "occluders phase: instances of meshes with at most this many triangles are candidates too, besides those flagged as occluders (0: flagged ones only)" },
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
        vec![(pos, format!("pass '{}' (instance_cull): {message}", pass.name))]
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(InstanceCullPass::new(s.ctx, s.shaders, s.pass)?))
    }
}
