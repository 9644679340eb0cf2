//! Hi-Z build (kind `hiz_build`): the reversed-Z min pyramid of a (multisampled) depth buffer, in
//! compute, equal bit for bit to [`crate::cull::hiz::HiZPyramid`] from chain level 1 on.
//!
//! Chain level 0 is the depth (the minimum, i.e. farthest reversed-Z, sample of each pixel); level
//! `k + 1` is `max(1, size_k >> 1)` per axis and reduces the footprints of
//! `shaders/common/hiz.glsl` (2×2, plus the odd last row/column: 2×3, 3×2, 3×3). Min of floats is
//! exact, so any reduction order gives the oracle's bits.
//!
//! **The stored pyramid starts at chain level 1** ([`FIRST_STORED_LEVEL`], GLSL `HIZ_FIRST_LEVEL`):
//! the `hiz` image is [`pyramid_size`] = `max(1, w >> 1)` × `max(1, h >> 1)` and its mip `m`
//! holds chain level `m + 1`; it has at most [`pyramid_mip_count`] mips (chain length − 1). The
//! pass reduces the depth straight into mip 0 and never writes level 0, which would cost as much
//! traffic as reading the depth. A 1×1 depth has no level 1: its pyramid is one 1×1 texel holding
//! the depth's minimum (conservative: the last texel of a level covers everything up to the edge).
//! In a graph: `Image(format: R32_SFLOAT, size: Fixed("max(1, width / 2)", "max(1, height / 2)"),
//! mips: All)`.
//!
//! Two methods (setting `method`):
//!
//! - `single` (default, `shaders/hiz/hiz_build_single.comp`): the tiles of AMD's single-pass
//!   downsampler in one dispatch, the levels above the tiles included. Every level is a min over an
//!   aligned block of the depth — texel `x` of level `k` covers columns `[x·2^k, (x+1)·2^k)`,
//!   except the last texel of a level, which extends to the end of the row because halving folds
//!   the dropped column into it — so the pyramid is a tree and the texels of level 6 cut it into
//!   independent subtrees. Workgroup `g` (256 threads) owns the subtree of level-6 texel `g`: a
//!   64×64 tile of the depth, except that the last workgroup column (row) owns everything up to the
//!   right (bottom) edge, 64 to 127 pixels (these heavier tiles are scheduled first). The odd
//!   columns and rows that the halvings fold into edge texels therefore never leave the tile that
//!   reduces them: no halo, no reads of a neighbour's texels. Each thread reduces a 4×4 block of
//!   the depth in registers (four `textureGather`s, one per level-1 texel; the blocks on the
//!   depth's last column/row of level 2 read 8×8 clamped pixels and apply the fold, see the
//!   shader), stores its 2×2 level-1 texels and its level-2 texel, and levels 3..=6 of the tile go
//!   through shared memory (a barrier per level, one texel per thread reading at most 3×3). Levels
//!   7.. are merged: each tile `atomicMin`s the bits of its level-6 texel into the one texel of
//!   every higher level above it (in a small buffer), then counts itself done; the tile that
//!   finishes last copies those levels into their mips and resets the buffer for the next build. No
//!   subgroup operations, so no assumption on the subgroup size.
//!
//!   Why this shape (the measurements are in `docs/culling.md` and `docs/history.md`): merging
//!   levels 7.. with atomics in the tiles and a copy by the last one saves the second dispatch,
//!   its drain and its barriers; levels 3..=6 go through shared memory because reducing them
//!   serially from level 2 costs more than reading the whole depth; `textureGather` beats four
//!   `texelFetch`es. A build's dependency on the previous build's use of the merge buffer rides in
//!   the barrier the executor records before the pass anyway ([`PassNode::own_dependency`]), not
//!   in a barrier of its own. At 4K the pyramid is bound by reading the depth once at the
//!   device's texture rate, plus the hand-over after the depth pass.
//! - `per_mip` (baseline, `shaders/hiz/hiz_build_per_mip.comp`): one dispatch per level (level 1
//!   from the depth's footprints, then level `k + 1` from level `k` through storage-image mip
//!   views), with a barrier on the written mip between dispatches.
//!
//! The depth is read through a `sampler2D` (nearest, clamp to edge) or, for MSAA depth,
//! `sampler2DMS` (`texelFetch` of every sample): two shader variants chosen by the depth image's
//! sample count. The pipelines for a variant are created the first time a depth of that kind is
//! recorded (a pass normally sees only one).
//!
//! In the graph, the `depth` slot arrives in `SHADER_READ_ONLY_OPTIMAL` and `hiz` in `GENERAL`
//! (all mips); every mip is left written by compute in `GENERAL`. [`HizBuildPass::record_images`]
//! records the same commands for images that the caller owns (tests, embedding).

use crate::gpu::barrier::{cmd_barriers, image_barrier_raw, memory_barrier};
use crate::gpu::{
    Access, Bind, Buffer, BufferDesc, GpuContext, Image, MemoryLocation, Pipeline, Sampler, ShaderCompiler, Spirv,
};
use crate::graph::executor::PassContext;
use crate::graph::plan::PlannedPass;
use ash::vk;

/// Format of the pyramid.
pub use super::slots::HIZ_FORMAT;

/// Most pyramid mips the pass writes (chain levels 1..=16: a 65536-pixel axis).
pub const MAX_LEVELS: u32 = 16;

/// The chain level whose texels split the single-dispatch pyramid into workgroup tiles (64×64).
pub const TILE_LEVEL: u32 = 6;

use super::slots::slot;
pub use crate::cull::hiz::FIRST_STORED_LEVEL;
use crate::graph::{
    Creates, Extent, FormatRule, KindCheck, MipChain, NodeSetup, PassKind, PassKindInfo, PassNode, Pos, SettingDecl,
    SlotDecl, Stages, Usage,
};

/// Size of the pyramid (its mip 0, chain level 1) for a depth of size `depth`: `max(1, w >> 1)` ×
/// `max(1, h >> 1)`.
pub fn pyramid_size(depth: vk::Extent2D) -> vk::Extent2D {
    let s = crate::cull::hiz::stored_size(glam::UVec2::new(depth.width, depth.height));
    vk::Extent2D { width: s.x, height: s.y }
}

/// Mips of a full pyramid for a depth of size `depth`: the chain length − 1, at least 1.
pub fn pyramid_mip_count(depth: vk::Extent2D) -> u32 {
    crate::cull::hiz::stored_mip_count(glam::UVec2::new(depth.width, depth.height))
}

crate::choice! {
/// How the pyramid is built (setting `method`).
pub enum HizMethod {
    /// One dispatch for the whole pyramid (64×64-pixel tiles; the last one to finish writes the
    /// levels above the tiles, merged by all of them).
    Single = "single",
    /// One dispatch per level with barriers between (baseline).
    PerMip = "per_mip",
}
}

/// Push constants of `hiz_build_single.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SinglePush {
    base: [u32; 2],
    levels: u32,
}

/// Push constants of `hiz_build_per_mip.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PerMipPush {
    src_size: [u32; 2],
    dst_size: [u32; 2],
}

/// A shader compiled in `new`, its pipeline created on first use for each depth sample count
/// (specialization constant 0, `HIZ_SAMPLES`, so that the driver unrolls the loop over samples:
/// on an H100 at 1920x1080 that took the single method from 0.039 to 0.037 ms at 2x and the
/// per-mip one from 0.117 to 0.108 ms at 8x).
struct Lazy {
    spirv: Spirv,
    pipelines: Vec<(u32, Pipeline)>,
}

impl Lazy {
    fn new(spirv: Spirv) -> Self {
        Self { spirv, pipelines: Vec::new() }
    }

    fn get(&mut self, ctx: &GpuContext, name: &str, samples: u32) -> crate::Result<&Pipeline> {
        let at = match self.pipelines.iter().position(|(s, _)| *s == samples) {
            Some(at) => at,
            None => {
                let pipeline = Pipeline::compute_specialized(ctx, name, &self.spirv, &[samples])?;
                self.pipelines.push((samples, pipeline));
                self.pipelines.len() - 1
            }
        };
        Ok(&self.pipelines[at].1)
    }
}

/// The Hi-Z build pass.
pub struct HizBuildPass {
    name: String,
    method: HizMethod,
    /// Single: the whole pyramid; per-mip: chain level 1. Index 0 single-sample depth, 1 multisampled.
    from_depth: [Lazy; 2],
    /// Per-mip: chain level `k + 1` from level `k`.
    reduce: Option<Pipeline>,
    sampler: Sampler,
    /// Single method: the tiles' done counter, then chain levels 7.. merged by the tiles (the
    /// bits of their values), sized for the device's largest image. Between builds the counter
    /// is 0 and every level +inf: the last tile of a build resets what it used.
    above: Buffer,
    /// Whether `above` has been filled (recorded once, before the first build).
    above_filled: bool,
    /// The executor's barrier before this run already orders the previous build's use of
    /// `above` before this one's ([`PassNode::own_dependency`]).
    above_ordered: bool,
}

/// Entries of the single method's `above` buffer for a depth of up to `max_dim` pixels per axis:
/// the counter and chain levels 7..=[`MAX_LEVELS`].
fn above_entries(max_dim: u32) -> u64 {
    let base = glam::UVec2::splat(max_dim);
    1 + (TILE_LEVEL + 1..=MAX_LEVELS)
        .map(|k| crate::cull::hiz::level_size(base, k))
        .map(|s| u64::from(s.x) * u64::from(s.y))
        .sum::<u64>()
}

impl HizBuildPass {
    /// The pass of a graph node (setting `method`).
    pub fn new(ctx: &GpuContext, shaders: &ShaderCompiler, pass: &PlannedPass) -> crate::Result<Self> {
        Self::with_method(ctx, shaders, &pass.name, pass.choice("method")?)
    }

    /// A pass named `name` (debug names) building the pyramid with `method`.
    pub fn with_method(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        name: &str,
        method: HizMethod,
    ) -> crate::Result<Self> {
        let (path, extra): (&str, &[(&str, &str)]) = match method {
            HizMethod::Single => ("hiz/hiz_build_single.comp", &[]),
            HizMethod::PerMip => ("hiz/hiz_build_per_mip.comp", &[("HIZ_FROM_DEPTH", "1")]),
        };
        let variant = |msaa: bool| -> crate::Result<Lazy> {
            let mut defines = extra.to_vec();
            if msaa {
                defines.push(("HIZ_MSAA", "1"));
            }
            Ok(Lazy::new(shaders.compile(path, &defines)?))
        };
        let from_depth = [variant(false)?, variant(true)?];
        let reduce = match method {
            HizMethod::Single => None,
            HizMethod::PerMip => {
                let spirv = shaders.compile("hiz/hiz_build_per_mip.comp", &[])?;
                Some(Pipeline::compute(ctx, &format!("{name} (reduce)"), &spirv)?)
            }
        };
        let above = Buffer::new(
            ctx,
            &BufferDesc {
                name: &format!("{name} (levels above the tiles)"),
                size: above_entries(ctx.caps().limits.max_image_dimension2_d) * 4,
                usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                location: MemoryLocation::GpuOnly,
            },
        )?;
        Ok(Self {
            name: name.into(),
            method,
            from_depth,
            reduce,
            sampler: Sampler::nearest_clamp(ctx)?,
            above,
            above_filled: false,
            above_ordered: false,
        })
    }

    /// The method this pass uses.
    pub fn method(&self) -> HizMethod {
        self.method
    }

    /// Records the build of `hiz` from `depth`.
    ///
    /// `depth`: a depth image (any sample count) in `SHADER_READ_ONLY_OPTIMAL`, its writes visible
    /// to compute-shader reads. `hiz`: an [`HIZ_FORMAT`] storage image of [`pyramid_size`] (half
    /// the depth's size: mip `m` is chain level `m + 1`) with 1 to [`pyramid_mip_count`] mips (at
    /// most [`MAX_LEVELS`]) in `GENERAL`, whose previous accesses are ordered before
    /// compute-shader writes. Every mip is left written by compute shaders in `GENERAL`: the
    /// caller's barrier to the next reader has source [`Access::COMPUTE_WRITE`].
    ///
    /// The single method keeps a small buffer of its own between builds, which the first build
    /// recorded also fills: submit what this pass records in the order it was recorded.
    pub fn record_images(
        &mut self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        depth: &Image,
        hiz: &Image,
    ) -> crate::Result<()> {
        // Whether the executor's barrier covered `above`: for this build only, even one that fails.
        let above_ordered = std::mem::take(&mut self.above_ordered);
        let invalid = |m: String| crate::Error::Invalid(format!("pass '{}': {m}", self.name));
        let (e, he) = (depth.extent(), hiz.extent());
        let want = pyramid_size(vk::Extent2D { width: e.width, height: e.height });
        if (want.width, want.height) != (he.width, he.height) {
            return Err(invalid(format!(
                "the pyramid '{}' is {}x{}; it must be {}x{}, half the depth's size {}x{} (chain level 1: \
                 size Fixed(\"max(1, width / 2)\", \"max(1, height / 2)\") for a full-screen depth)",
                hiz.name(),
                he.width,
                he.height,
                want.width,
                want.height,
                e.width,
                e.height
            )));
        }
        if hiz.format() != HIZ_FORMAT {
            return Err(invalid(format!("the pyramid '{}' is {:?}, not {HIZ_FORMAT:?}", hiz.name(), hiz.format())));
        }
        let levels = hiz.mip_levels();
        let chain = pyramid_mip_count(vk::Extent2D { width: e.width, height: e.height });
        if levels > chain {
            return Err(invalid(format!(
                "the pyramid '{}' has {levels} mips; a {}x{} depth has {chain} levels below its own \
                 (chain levels 1..={chain}, down to 1x1)",
                hiz.name(),
                e.width,
                e.height
            )));
        }
        if levels > MAX_LEVELS {
            return Err(invalid(format!("{levels} mips; the pass writes at most {MAX_LEVELS}")));
        }
        let samples = depth.samples().as_raw().max(1);
        let base = [e.width, e.height];
        let variant = usize::from(samples > 1);
        let device = ctx.device();
        let depth_bind =
            Bind::Sampled(0, depth.sampled_view(), self.sampler.handle(), vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        match self.method {
            HizMethod::Single => {
                let tiles = crate::cull::hiz::level_size(glam::UVec2::from(base), TILE_LEVEL);
                if levels > TILE_LEVEL {
                    self.prepare_above(device, cmd, above_ordered);
                }
                let pipeline = self.from_depth[variant].get(ctx, &self.name, samples)?;
                let mut binds = vec![depth_bind, Bind::Buffer(18, self.above.handle())];
                binds.extend((0..MAX_LEVELS).map(|l| Bind::StorageImage(2 + l, hiz.mip_view(l.min(levels - 1)))));
                pipeline.bind(cmd);
                pipeline.push_bindings(cmd, &binds);
                pipeline.push_constants(cmd, &SinglePush { base, levels });
                // SAFETY: cmd recording with the pipeline bound and every binding pushed.
                unsafe { device.cmd_dispatch(cmd, tiles.x, tiles.y, 1) };
            }
            HizMethod::PerMip => {
                let size = |k: u32| crate::cull::hiz::level_size(glam::UVec2::from(base), k).to_array();
                let dispatch = |pipeline: &Pipeline, binds: &[Bind], push: PerMipPush| {
                    pipeline.bind(cmd);
                    pipeline.push_bindings(cmd, binds);
                    pipeline.push_constants(cmd, &push);
                    let [w, h] = push.dst_size;
                    // SAFETY: cmd recording with the pipeline bound and every binding pushed.
                    unsafe { device.cmd_dispatch(cmd, w.div_ceil(8), h.div_ceil(8), 1) };
                };
                let level1 = self.from_depth[variant].get(ctx, &self.name, samples)?;
                dispatch(
                    level1,
                    &[depth_bind, Bind::StorageImage(1, hiz.mip_view(0))],
                    PerMipPush { src_size: base, dst_size: size(1) },
                );
                let reduce = self.reduce.as_ref().expect("per-mip passes have a reduce pipeline");
                let storage_read = Access {
                    stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
                    access: vk::AccessFlags2::SHADER_STORAGE_READ,
                    layout: vk::ImageLayout::GENERAL,
                };
                for k in 1..levels {
                    let range = vk::ImageSubresourceRange::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .base_mip_level(k - 1)
                        .level_count(1)
                        .layer_count(1);
                    let barrier = image_barrier_raw(hiz.handle(), range, Access::COMPUTE_WRITE, storage_read);
                    cmd_barriers(device, cmd, &[], &[barrier]);
                    // Mip k holds chain level k + 1.
                    dispatch(
                        reduce,
                        &[Bind::StorageImage(0, hiz.mip_view(k - 1)), Bind::StorageImage(1, hiz.mip_view(k))],
                        PerMipPush { src_size: size(k), dst_size: size(k + 1) },
                    );
                }
            }
        }
        Ok(())
    }

    /// Records what the single method's merges into `above` need first: the buffer filled (the
    /// first time: counter 0, levels +inf), and the previous build's last tile done with it
    /// (unless the executor's barrier before the pass saw to that).
    fn prepare_above(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, ordered: bool) {
        if self.above_filled {
            if !ordered {
                cmd_barriers(device, cmd, &[memory_barrier(ABOVE_ACCESS, ABOVE_ACCESS)], &[]);
            }
            return;
        }
        // SAFETY: a buffer with TRANSFER_DST usage that no command has used yet; cmd recording.
        unsafe {
            device.cmd_fill_buffer(cmd, self.above.handle(), 4, vk::WHOLE_SIZE, f32::INFINITY.to_bits());
            device.cmd_fill_buffer(cmd, self.above.handle(), 0, 4, 0);
        }
        cmd_barriers(device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, ABOVE_ACCESS)], &[]);
        self.above_filled = true;
    }
}

/// How the single method's builds use `above`: compute-shader reads and writes (the merges, the
/// last tile's copy and reset).
const ABOVE_ACCESS: Access = Access::COMPUTE_WRITE;

impl PassNode for HizBuildPass {
    /// The first build fills `above`; later ones wait for the build before.
    fn replay_state(&self) -> Option<u64> {
        Some(u64::from(self.above_filled))
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let depth = rec.slots.required_image("depth")?;
        let hiz = rec.slots.required_image("hiz")?;
        self.record_images(rec.ctx, rec.cmd, depth, hiz)
    }

    /// The previous build's last tile before this build's merges: in the executor's barrier
    /// rather than one of the pass's own (H100: 1.2 µs less per build). The first build fills
    /// `above` and orders that itself.
    fn own_dependency(&mut self) -> Option<(Access, Access)> {
        self.above_ordered = self.method == HizMethod::Single && self.above_filled;
        self.above_ordered.then_some((ABOVE_ACCESS, ABOVE_ACCESS))
    }
}

/// The `hiz_build` pass kind.
pub struct HizBuildKind;

impl PassKind for HizBuildKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "hiz_build",
            doc: "builds the reversed-Z Hi-Z pyramid (minimum = farthest depth per footprint, conservative for every size) from (MSAA) depth",
            reads: vec![SlotDecl { multisample_ok: true, ..slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "depth, reduced across samples first") }],
            writes: vec![slot("hiz", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(HIZ_FORMAT), "the pyramid from chain level 1: mip 0 at half the depth's size (max(1, width / 2) x max(1, height / 2)), at most the levels down to 1x1, every mip written; created when the graph declares none").creates(Creates::image(HIZ_FORMAT, Extent::Of { slot: "depth", divisor: 2 }, MipChain::All))],
            settings: vec![SettingDecl::choice::<HizMethod>(
                "method",
                "one dispatch for the whole pyramid, or one dispatch per mip (baseline)",
            )],
            slots_from_shader: false,
        }
    }

    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        pyramid_error(check).into_iter().collect()
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(HizBuildPass::new(s.ctx, s.shaders, s.pass)?))
    }
}

/// The pyramid of a `hiz_build` pass must be half its depth's size: level 0 of the chain is not
/// stored.
fn pyramid_error(check: &KindCheck<'_>) -> Option<(Pos, String)> {
    let ((_, depth), (hiz_binding, hiz)) = (check.image_extent("depth")?, check.image_extent("hiz")?);
    let want: vk::Extent2D = pyramid_size(depth);
    if (hiz.width, hiz.height) == (want.width, want.height) {
        // (A pyramid of this size cannot have more mips than the depth has levels below its own.)
        return None;
    }
    let message = format!(
        "pass '{}': the pyramid '{}' is {}x{}; it must be {}x{}, half the depth's size {}x{} (size: \
         Fixed(\"max(1, width / 2)\", \"max(1, height / 2)\") for a full-screen depth)",
        check.pass.name,
        check.resource_name(hiz_binding),
        hiz.width,
        hiz.height,
        want.width,
        want.height,
        depth.width,
        depth.height
    );
    Some((hiz_binding.pos, message))
}
