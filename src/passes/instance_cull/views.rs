//! Several views culled together: one test dispatch reads each slot's record once and tests it
//! against every view (choosing each view's level of detail in its own pixels), and one compact
//! dispatch places every view's survivors (a workgroup per block, for every view with survivors
//! in it). Each view keeps its own scratch, decision bits, counts, visibility and
//! draw lists, reached through their device addresses in a table (`shaders/cull/cull_views.glsl`).

use super::{blocks_of, step_barrier, InstanceCullPass, CULL_SUPERBLOCK};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, Buffer, BufferDesc, GpuContext, MemoryLocation, Pipeline, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::{PassNode, FRAMES_IN_FLIGHT};
use crate::passes::shared::gpu_types::{FrameConstants, GpuCullView};
use crate::passes::shared::SceneInputs;
use ash::vk;

/// The most views one dispatch culls (`MAX_CULL_VIEWS` in `cull_views.glsl`): their pyramids
/// are an array of samplers indexed by constants. More views take more dispatches.
pub const MAX_TOGETHER: usize = 16;

/// Addresses per view in the table (`ViewBuffers`).
const TABLE_WORDS: usize = 15;

/// Tables kept: one per frame modulo frames in flight and the two copies of history, as many
/// as a frame's commands are kept for replay (`graph::executor::replay`), whose tables then
/// still hold their addresses.
const TABLE_RING: usize = 2 * FRAMES_IN_FLIGHT;

/// What the test step reads of each view's constants (`ViewCull` in `instance_cull.comp`,
/// scalar layout), as a uniform buffer: gathered on the GPU out of each view's constants
/// (`cull_view_gather.comp`), so that the recorded commands hold nothing of the cameras and a
/// frame can be replayed.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ViewCull {
    cull_view: GpuCullView,
    prev_cull_view: GpuCullView,
    eye_hi: [f32; 4],
    eye_lo: [f32; 4],
    prev_eye_hi: [f32; 4],
    prev_eye_lo: [f32; 4],
    lod_view: GpuCullView,
    lod_eye_offset: [f32; 4],
}

impl ViewCull {
    /// The runs of a view's [`ViewCull`] in its [`FrameConstants`], in words (first word there,
    /// first word here, words), as `cull_view_gather.comp` takes them: each a run both layouts
    /// hold in one order.
    fn runs() -> [[u32; 4]; 4] {
        use std::mem::{offset_of, size_of};
        let run = |from: usize, at: usize, bytes: usize| [(from / 4) as u32, (at / 4) as u32, (bytes / 4) as u32, 0];
        [
            run(offset_of!(FrameConstants, cull_view), offset_of!(ViewCull, cull_view), 2 * size_of::<GpuCullView>()),
            run(offset_of!(FrameConstants, eye_hi), offset_of!(ViewCull, eye_hi), 32),
            run(offset_of!(FrameConstants, prev_eye_hi), offset_of!(ViewCull, prev_eye_hi), 32),
            run(offset_of!(FrameConstants, lod_view), offset_of!(ViewCull, lod_view), size_of::<GpuCullView>() + 16),
        ]
    }
}

// The last run takes the level-of-detail view and the eye offset after it as one.
const _: () = assert!(
    std::mem::offset_of!(FrameConstants, lod_eye_offset)
        == std::mem::offset_of!(FrameConstants, lod_view) + std::mem::size_of::<GpuCullView>()
        && std::mem::offset_of!(ViewCull, lod_eye_offset)
            == std::mem::offset_of!(ViewCull, lod_view) + std::mem::size_of::<GpuCullView>()
);

/// What `cull_view_gather.comp` takes as push constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GatherPush {
    views: u32,
    table_words: u32,
    view_words: u32,
    runs: u32,
    run: [[u32; 4]; 4],
}

/// The pipelines and tables of culling several views at once, made on first use.
pub(super) struct Together {
    test: Pipeline,
    /// Where each view's slots of each level start (levels of detail only).
    levels: Option<Pipeline>,
    compact: Pipeline,
    /// Gathers the views' culling constants (`cull_view_gather.comp`).
    gather: Pipeline,
    /// Per kept frame ([`TABLE_RING`]), one table and one buffer of culling constants per
    /// dispatch of the frame.
    tables: Vec<Vec<(Buffer, Buffer)>>,
}

impl Together {
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        name: &str,
        defines: &[(String, String)],
    ) -> crate::Result<Self> {
        let with = |extra: &[(&str, &str)]| -> Vec<(String, String)> {
            let mut all = defines.to_vec();
            all.extend(extra.iter().map(|(k, v)| (k.to_string(), v.to_string())));
            all
        };
        let compile = |file: &str, defines: Vec<(String, String)>| -> crate::Result<crate::gpu::Spirv> {
            let refs: Vec<(&str, &str)> = defines.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
            Ok(shaders.compile(file, &refs)?)
        };
        let test_spirv = compile("cull/instance_cull.comp", with(&[("MULTI_VIEW", "1")]))?;
        let defined = |name: &str| defines.iter().any(|(k, _)| k == name);
        let multi_view = ("MULTI_VIEW".to_string(), "1".to_string());
        let mut compact_defines = vec![multi_view.clone()];
        for name in ["VISIBLE_OUT", "LOD"].into_iter().filter(|n| defined(n)) {
            compact_defines.push((name.into(), "1".into()));
        }
        let compact_spirv = compile("cull/cull_compact.comp", compact_defines)?;
        let levels = match defined("LOD") {
            true => Some(Pipeline::compute(
                ctx,
                &format!("{name} (levels, views)"),
                &compile("cull/cull_levels.comp", vec![multi_view])?,
            )?),
            false => None,
        };
        let gather_spirv = compile("cull/cull_view_gather.comp", Vec::new())?;
        Ok(Self {
            test: Pipeline::compute(ctx, &format!("{name} (test, views)"), &test_spirv)?,
            levels,
            compact: Pipeline::compute(ctx, &format!("{name} (compact, views)"), &compact_spirv)?,
            gather: Pipeline::compute(ctx, &format!("{name} (view constants, views)"), &gather_spirv)?,
            tables: (0..TABLE_RING).map(|_| Vec::new()).collect(),
        })
    }

    /// The table and the culling constants of dispatch `chunk` of frame `frame`, made on first
    /// use.
    fn table(&mut self, ctx: &GpuContext, frame: u64, chunk: usize) -> crate::Result<&mut (Buffer, Buffer)> {
        let ring = &mut self.tables[(frame % TABLE_RING as u64) as usize];
        while ring.len() <= chunk {
            let host = |name, size, usage| {
                Buffer::new(ctx, &BufferDesc { name, size, usage, location: MemoryLocation::CpuToGpu })
            };
            ring.push((
                host("cull view table", (MAX_TOGETHER * TABLE_WORDS * 8) as u64, vk::BufferUsageFlags::STORAGE_BUFFER)?,
                host(
                    "cull view constants",
                    (MAX_TOGETHER * std::mem::size_of::<ViewCull>()) as u64,
                    vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
                )?,
            ));
        }
        Ok(&mut ring[chunk])
    }
}

/// One view's addresses, in `ViewBuffers` order; `None` when one it needs has none.
fn addresses(rec: &PassContext<'_>, node: &InstanceCullPass) -> crate::Result<Option<[u64; TABLE_WORDS]>> {
    let scratch = node.scratch.as_ref().expect("ensured before");
    let frame = SceneInputs::of(rec)?;
    let optional = |slot: &str| rec.slots.buffer(slot).map_or(Some(0), Buffer::device_address);
    let required = |slot: &str| rec.slots.buffer(slot).and_then(Buffer::device_address);
    let words = [
        frame.constants().device_address(),
        scratch.group_counts.device_address(),
        scratch.scan.device_address(),
        scratch.draw_bits.device_address(),
        optional("visibility_prev"),
        optional("visibility"),
        required("draw_instance_ids"),
        required("draw_commands"),
        required("draw_count"),
        required("stats"),
        optional("visible_ids"),
        optional("list_commands"),
        optional("list_count"),
        optional("list_stats"),
        match &scratch.level_bits {
            Some(bits) => bits.device_address(),
            None => Some(0),
        },
    ];
    let mut out = [0u64; TABLE_WORDS];
    for (o, w) in out.iter_mut().zip(words) {
        match w {
            Some(address) => *o = address,
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

impl InstanceCullPass {
    /// Records this pass for every view of `contexts` (`others` being the nodes of
    /// `contexts[1..]`), at most [`MAX_TOGETHER`] per dispatch pair; one at a time when some
    /// buffer has no address.
    pub(super) fn record_views(
        &mut self,
        contexts: &[PassContext<'_>],
        others: &mut [&mut (dyn PassNode + 'static)],
    ) -> crate::Result<()> {
        let ctx = contexts[0].ctx;
        let cmd = contexts[0].cmd;
        let scene = &SceneInputs::of(&contexts[0])?.scene;
        let (slots, groups) = (scene.instance_count, scene.regions.groups());
        let mut nodes: Vec<&mut InstanceCullPass> = Vec::with_capacity(contexts.len());
        // SAFETY of the casts: `together_key` equal means the same kind, whose nodes are this type.
        let mut rest: Vec<&mut InstanceCullPass> = others
            .iter_mut()
            .map(|n| {
                n.as_any_mut().and_then(|a| a.downcast_mut::<InstanceCullPass>()).ok_or_else(|| {
                    crate::Error::Invalid("instance_cull: a pass recorded together is of another kind".into())
                })
            })
            .collect::<crate::Result<_>>()?;
        nodes.push(self);
        nodes.append(&mut rest);
        let device = ctx.device();
        let mut fresh = false;
        // `nodes[i]` records for `contexts[i]`, whose runtime counts its own frames.
        for (node, context) in nodes.iter_mut().zip(contexts) {
            node.ensure_scratch(ctx, slots, groups, context.frame.frame)?;
            let scratch = node.scratch.as_mut().expect("ensured above");
            if scratch.fresh {
                // SAFETY: cmd recording; the buffers are the pass's own.
                unsafe {
                    device.cmd_fill_buffer(cmd, scratch.scan.handle(), 0, vk::WHOLE_SIZE, 0);
                    device.cmd_fill_buffer(cmd, scratch.group_counts.handle(), 0, vk::WHOLE_SIZE, 0);
                }
                if let Some(list) = &scratch.block_list {
                    super::clear_block_list(device, cmd, list.handle());
                }
                scratch.fresh = false;
                fresh = true;
            }
        }
        if fresh {
            cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::COMPUTE_WRITE)], &[]);
        }
        let mut tables = Vec::with_capacity(contexts.len());
        for (rec, node) in contexts.iter().zip(nodes.iter()) {
            match addresses(rec, node)? {
                Some(t) => tables.push(t),
                // A buffer without an address (a host's): each view on its own.
                None => {
                    for (rec, node) in contexts.iter().zip(nodes.iter_mut()) {
                        node.record(rec)?;
                    }
                    return Ok(());
                }
            }
        }
        // Last frame's run of this pass used the same scratch.
        step_barrier(ctx, cmd);
        let blocks = blocks_of(slots);
        let superblocks = blocks.div_ceil(CULL_SUPERBLOCK);
        let settings = nodes[0].settings.clone();
        let lead = &mut nodes[0];
        if lead.together.is_none() {
            return Err(crate::Error::Invalid(
                "instance_cull: the pipelines of culling views together are missing".into(),
            ));
        }
        let frame = contexts[0].frame.frame;
        for (chunk, range) in
            (0..contexts.len()).step_by(MAX_TOGETHER).map(|s| s..(s + MAX_TOGETHER).min(contexts.len())).enumerate()
        {
            let n = range.len();
            let together = lead.together.as_mut().expect("checked above");
            let words: Vec<u64> = tables[range.clone()].iter().flatten().copied().collect();
            let (table, constants) = together.table(ctx, frame, chunk)?;
            // The addresses are the same whenever this frame's commands are (a replay runs
            // them again): they are written once per recording, into a table of its own.
            table.write_bytes(0, bytemuck::cast_slice(&words))?;
            let (table, constants) = (table.handle(), constants.handle());
            // The views' culling constants as the host wrote them for the frame that executes:
            // after an earlier frame's test read the uniform buffer, before this one's.
            let uniform_read = Access {
                stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
                access: vk::AccessFlags2::UNIFORM_READ,
                layout: vk::ImageLayout::UNDEFINED,
            };
            cmd_barriers(device, cmd, &[memory_barrier(uniform_read, Access::COMPUTE_WRITE)], &[]);
            let view_words = (std::mem::size_of::<ViewCull>() / 4) as u32;
            let push = GatherPush {
                views: n as u32,
                table_words: TABLE_WORDS as u32,
                view_words,
                runs: 4,
                run: ViewCull::runs(),
            };
            together.gather.bind(cmd);
            together.gather.push_bindings(cmd, &[Bind::Buffer(0, table), Bind::Buffer(1, constants)]);
            together.gather.push_constant_bytes(cmd, bytemuck::bytes_of(&push));
            // SAFETY: cmd recording with the pipeline bound.
            unsafe { device.cmd_dispatch(cmd, (n as u32 * view_words).div_ceil(64), 1, 1) };
            let gathered = Access { access: Access::COMPUTE_WRITE.access | uniform_read.access, ..uniform_read };
            cmd_barriers(device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, gathered)], &[]);
            let mut test_binds = vec![
                Bind::Buffer(0, scene.cull_records.handle()),
                Bind::Buffer(2, scene.draw_groups.handle()),
                Bind::Buffer(10, table),
                Bind::Buffer(11, constants),
            ];
            let lod = together.levels.is_some();
            if lod {
                test_binds.push(Bind::Buffer(12, scene.lod_levels.handle()));
            }
            // Every element of the pyramid array is bound: the views' own, then the first again.
            let hiz: Vec<_> = contexts[range.clone()].iter().filter_map(|rec| rec.slots.image("hiz")).collect();
            if hiz.len() == n {
                for element in 0..MAX_TOGETHER {
                    let image = hiz[element.min(n - 1)];
                    test_binds.push(Bind::SampledAt(
                        9,
                        element as u32,
                        image.view(),
                        lead.sampler.handle(),
                        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    ));
                }
            }
            // The last word: no block decided whole (views culled together test every slot).
            let push: [u32; 9] = [
                slots,
                superblocks,
                groups,
                settings.occluder_distance.to_bits(),
                settings.occluder_size.to_bits(),
                settings.occluder_triangles,
                n as u32,
                settings.lod_threshold.to_bits(),
                0,
            ];
            contexts[0].step("test");
            together.test.bind(cmd);
            together.test.push_bindings(cmd, &test_binds);
            together.test.push_constants(cmd, &push);
            // SAFETY: cmd recording with the pipeline bound.
            unsafe { crate::gpu::line_dispatch::cmd_dispatch_line(device, cmd, &ctx.caps().limits, blocks) };
            step_barrier(ctx, cmd);
            if let Some(levels) = &together.levels {
                contexts[0].step("levels");
                levels.bind(cmd);
                levels.push_bindings(cmd, &[Bind::Buffer(1, table)]);
                levels.push_constants(cmd, &[slots, superblocks]);
                // Workgroup v: view v.
                // SAFETY: cmd recording with the pipeline bound.
                unsafe { device.cmd_dispatch(cmd, n as u32, 1, 1) };
                step_barrier(ctx, cmd);
            }
            contexts[0].step("compact");
            together.compact.bind(cmd);
            let mut compact_binds = vec![
                Bind::Buffer(2, scene.draw_groups.handle()),
                Bind::Buffer(3, scene.draw_instance_ids.handle()),
                Bind::Buffer(14, table),
                Bind::Buffer(16, scene.group_order.handle()),
            ];
            if lod {
                compact_binds.push(Bind::Buffer(15, scene.lod_levels.handle()));
            }
            together.compact.push_bindings(cmd, &compact_binds);
            let mut push = vec![slots, groups, superblocks];
            push.extend(scene.regions.first);
            push.extend([n as u32, scene.groups_out_of_slot_order as u32]);
            together.compact.push_constant_bytes(cmd, bytemuck::cast_slice(&push));
            // Workgroup v < n writes view v's commands, workgroup n + b places block b of every
            // view with survivors there.
            // SAFETY: as above.
            unsafe { crate::gpu::line_dispatch::cmd_dispatch_line(device, cmd, &ctx.caps().limits, n as u32 + blocks) };
        }
        Ok(())
    }
}
