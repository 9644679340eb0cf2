//! The compressed G-buffer geometry pass (thesis `000` §4.3, paper `002`): the culled lists are
//! drawn again over the finished MSAA depth with depth EQUAL, a stencil bit per sample and
//! post-depth coverage, and each fragment writes one 16-byte block: the pixel's head when it
//! owns sample 0, otherwise a pool block pushed on the pixel's list.
//!
//! With a depth format without stencil and a `sample_claim` buffer ([`SampleOwner::Claim`])
//! the fragments claim their samples with an atomic OR on a byte per pixel instead of the
//! stencil test: the depth takes 4 instead of 8 bytes per sample on NVIDIA. Coplanar ties go
//! to the first fragment in draw order where the claims run in an ordered sample interlock
//! (`claim_order` `draw`, or `auto` on a device that has one), otherwise to whichever fragment
//! claims first.
//!
//! The `gbuffer` buffer holds a 16-byte header (pool blocks asked for, fragments and samples
//! dropped because the pool was full) and `width * height` head blocks; the `gbuffer_pool`
//! buffer holds the pool. Both store 32-byte pairs of blocks
//! (`shaders/gbuffer/compressed_gbuffer.glsl`). Two buffers keep each binding within
//! `maxStorageBufferRange` at 3840x2160 on devices that address 128 MiB per binding (lavapipe):
//! the heads take 133 MB there (within 128 MiB), heads and pool together 199 MB. The pool's size sets its blocks;
//! links have 26 bits, so at most 2^26 - 1 pool blocks are used whatever the size.

use super::gbuffer::{bound_image, record_geometry, DrawSource, GeometryShaders};
use super::slots::{ms, redraw_list_slots, slot, AA_MASK_FORMAT};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, GpuContext, Pipeline, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::validated::ResourceDesc;
use crate::graph::{
    Choice, Creates, DrawList, DrawOrder, FormatRule, KindCheck, NodeSetup, PassKind, PassKindInfo, PassNode, Pos,
    SettingDecl, SettingDefault, Stages, Usage,
};
use crate::passes::lighting_compressed::pool::POOL_SETTING;
use crate::passes::shared::face_cull::FaceCull;
use crate::passes::shared::lazy_pipeline::LazyPipeline;
use crate::passes::shared::vertex_streams::VertexFetch;
use crate::passes::shared::SceneInputs;
use ash::vk;

/// Bytes of the header before the blocks.
pub const HEADER_BYTES: u64 = 16;
/// Bytes of one pair of blocks.
pub const PAIR_BYTES: u64 = 32;
/// Pool blocks one link can address (a 26-bit index; 0 is the null link).
pub const MAX_POOL_BLOCKS: u64 = (1 << 26) - 1;

/// Bytes of the `gbuffer` buffer (header and heads) for `pixels` pixels.
pub fn heads_bytes(pixels: u64) -> u64 {
    HEADER_BYTES + pixels.div_ceil(2) * PAIR_BYTES
}

/// Pool blocks a `gbuffer_pool` buffer of `bytes` holds, within the links' 26-bit index.
pub fn pool_blocks(bytes: u64) -> u64 {
    (bytes / PAIR_BYTES * 2).min(MAX_POOL_BLOCKS)
}

/// An error when a `gbuffer` buffer of `bytes` cannot hold the heads of `pixels` pixels.
pub fn check_heads(bytes: u64, pixels: u64) -> Result<(), String> {
    let need = heads_bytes(pixels);
    if bytes < need {
        return Err(format!(
            "the gbuffer buffer holds {bytes} bytes; the header and {pixels} head blocks take {need} (size: 16 + \
             ceil_div(width * height, 2) * 32)"
        ));
    }
    Ok(())
}

/// Bytes of the `sample_claim` buffer: one byte per pixel, in whole words.
pub fn sample_claim_bytes(pixels: u64) -> u64 {
    pixels.div_ceil(4) * 4
}

/// Most samples per pixel the `sample_claim` byte can hold.
pub const MAX_CLAIM_SAMPLES: u32 = 8;

/// How `gbuffer_compressed` makes each covered sample pass for exactly one fragment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleOwner {
    /// A stencil bit per sample, tested `== 0` and incremented: the first fragment in draw
    /// order wins (deterministic). Needs a depth format with stencil.
    Stencil,
    /// An atomic OR on the `sample_claim` buffer (a byte per pixel): the first fragment to
    /// claim wins, which is the first in draw order only when the claims run in an ordered
    /// sample interlock (`claim_order`). Needs a depth format without stencil and at most
    /// [`MAX_CLAIM_SAMPLES`] samples.
    Claim,
}

impl SampleOwner {
    /// The rule for a depth image of `format` with `samples` samples, with or without a
    /// `sample_claim` buffer bound; an error (without the pass's name) for the combinations
    /// that would leave samples undecided or decide them twice.
    pub fn for_depth(format: vk::Format, samples: u32, claim_bound: bool) -> Result<Self, String> {
        let stencil = crate::gpu::image::aspect_of(format).contains(vk::ImageAspectFlags::STENCIL);
        let name = crate::graph::formats::name(format);
        match (stencil, claim_bound) {
            (true, false) => Ok(Self::Stencil),
            (true, true) => Err(format!(
                "\"sample_claim\" is bound but the depth format {name} has stencil, which already decides each sample's \
                 fragment: remove sample_claim, or use a depth format without stencil (D32_SFLOAT)"
            )),
            (false, false) => Err(format!(
                "the depth format {name} has no stencil to decide each sample's fragment: bind a \"sample_claim\" \
                 buffer in writes (size: ceil_div(width * height, 4) * 4) or use a depth format with stencil \
                 (D32_SFLOAT_S8_UINT)"
            )),
            (false, true) if samples > MAX_CLAIM_SAMPLES => Err(format!(
                "\"sample_claim\" keeps one byte per pixel, so at most {MAX_CLAIM_SAMPLES} samples; the depth has {samples}"
            )),
            (false, true) => Ok(Self::Claim),
        }
    }
}

/// The compressed G-buffer bound to a pass's `gbuffer` and `gbuffer_pool` slots, for an image
/// the size of `depth`, and the `sample_claim` buffer when one is bound.
pub struct BoundGbuffer<'a> {
    /// The header and heads.
    pub buffer: &'a crate::gpu::Buffer,
    /// The pool.
    pub pool: &'a crate::gpu::Buffer,
    /// Pixels (head blocks).
    pub pixels: u64,
    /// Pool blocks, within the 26-bit index.
    pub pool_blocks: u32,
    /// The samples the fragments claimed (one byte per pixel), when the graph binds it.
    pub sample_claim: Option<&'a crate::gpu::Buffer>,
}

impl<'a> BoundGbuffer<'a> {
    /// Resolves the `gbuffer` slot of pass `kind` against `depth`; a clear error when the buffer
    /// is missing or too small.
    pub fn resolve(
        slots: &crate::graph::executor::SlotBindings<'a>,
        depth: &crate::gpu::Image,
        kind: &str,
    ) -> crate::Result<Self> {
        let invalid = |m: String| crate::Error::Invalid(format!("{kind}: {m}"));
        let buffer = slots.buffer("gbuffer").ok_or_else(|| invalid("no gbuffer buffer bound".into()))?;
        let pool = slots.buffer("gbuffer_pool").ok_or_else(|| invalid("no gbuffer_pool buffer bound".into()))?;
        let extent = depth.extent();
        let pixels = extent.width as u64 * extent.height as u64;
        check_heads(buffer.size(), pixels).map_err(invalid)?;
        let sample_claim = slots.buffer("sample_claim");
        if let Some(claim) = sample_claim {
            if claim.size() < sample_claim_bytes(pixels) {
                return Err(invalid(format!(
                    "sample_claim holds {} bytes; {pixels} pixels need {} (ceil_div(width * height, 4) * 4)",
                    claim.size(),
                    sample_claim_bytes(pixels)
                )));
            }
        }
        Ok(Self { buffer, pool, pixels, pool_blocks: pool_blocks(pool.size()) as u32, sample_claim })
    }
}

/// Push constants of `gbuffer_compressed.frag`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CompressedPush {
    width: u32,
    height: u32,
    pool_blocks: u32,
    aa_region: u32,
    aa_region_size: f32,
    aa_max_distance: f32,
    aa_object_flags: u32,
}

/// Selective anti-aliasing (paper `002` §5): where pixels may keep more than one block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelectiveAa {
    /// 0 everywhere, 1 inside a centered ellipse, 2 inside a centered rectangle.
    pub region: u32,
    /// The region's size as a fraction of the screen's width and height.
    pub region_size: f32,
    /// Pixels of surfaces farther than this keep one block (0: no limit).
    pub max_distance: f32,
    /// Instances flagged `FLAG_NO_AA` keep one block.
    pub object_flags: bool,
}

impl SelectiveAa {
    /// From a pass's settings.
    pub fn from_plan(pass: &PlannedPass) -> crate::Result<Self> {
        Ok(Self {
            region: pass.choice::<AaRegion>("aa_region")? as u32,
            region_size: pass.real("aa_region_size")? as f32,
            max_distance: pass.real("aa_max_depth_distance")? as f32,
            object_flags: pass.flag("aa_object_flags")?,
        })
    }
}

crate::choice! {
    /// Where pixels may keep more than one block (setting `aa_region`).
    pub enum AaRegion {
        /// Everywhere.
        All = "all",
        /// Inside a centered ellipse.
        Ellipse = "ellipse",
        /// Inside a centered rectangle.
        Rectangle = "rectangle",
    }
}

crate::choice! {
    /// Who wins an exactly coplanar tie of sample claims (setting `claim_order`).
    pub enum ClaimOrder {
        /// Draw order where the device has the interlock, else arrival.
        Auto = "auto",
        /// The first fragment in draw order (an ordered sample interlock).
        Draw = "draw",
        /// The first to claim.
        Arrival = "arrival",
    }
}

/// What the device lacks for the pass: post-depth coverage, and for claims in draw order the
/// ordered sample interlock (no device: nothing to say yet).
fn device_error(check: &KindCheck<'_>) -> Option<(Pos, String)> {
    let (limits, planned) = (check.limits?, check.planned?);
    let pass = check.pass;
    if !limits.has("post_depth_coverage") {
        let message = format!(
            "pass '{}' (gbuffer_compressed) needs VK_EXT_post_depth_coverage, which is not enabled on {} (not \
             supported, or not among a host's `enabled_device_extensions`)",
            pass.name, limits.device
        );
        return Some((pass.pos, message));
    }
    let draw_order = planned.choice::<ClaimOrder>("claim_order").ok()? == ClaimOrder::Draw;
    if draw_order && check.binding("sample_claim").is_some() && !limits.has("fragment_shader_sample_interlock") {
        let at = pass.settings.iter().find(|s| s.name == "claim_order").map_or(pass.pos, |s| s.pos);
        let message = format!(
            "pass '{}': claim_order \"draw\" needs VK_EXT_fragment_shader_interlock with \
             fragmentShaderSampleInterlock, which is not enabled on {}; \"arrival\" needs nothing",
            pass.name, limits.device
        );
        return Some((at, message));
    }
    None
}

/// Whether the sample claims of `pass` run in draw order (its `claim_order` setting): `draw`
/// needs the device's ordered sample interlock, `auto` uses it where there is one.
fn claims_in_draw_order(ctx: &GpuContext, pass: &PlannedPass) -> Result<bool, String> {
    let interlock = ctx.caps().sample_interlock;
    match pass.choice::<ClaimOrder>("claim_order").map_err(|e| e.to_string())? {
        ClaimOrder::Arrival => return Ok(false),
        ClaimOrder::Auto => {
            let order = if interlock { "draw" } else { "arrival (no ordered sample interlock)" };
            tracing::info!("pass '{}': claim_order auto: {order} on {}", pass.name, ctx.caps().name);
            return Ok(interlock);
        }
        ClaimOrder::Draw => {}
    }
    if !interlock {
        return Err(format!(
            "claim_order \"draw\" needs VK_EXT_fragment_shader_interlock with fragmentShaderSampleInterlock, which \
             is not enabled on {} (not supported, or not among a host's `enabled_device_extensions`); \"arrival\" \
             needs nothing, and msaa_compressed.ron's stencil also decides ties in draw order",
            ctx.caps().name
        ));
    }
    Ok(true)
}

/// The `gbuffer_compressed` pass.
pub struct GbufferCompressedPass {
    /// The geometry pass by `[extras][textured]` (created when first used): `extras` for scenes
    /// with emission or occlusion (without, occlusion is 1 and emission none: the texture reads
    /// and the emissive encoding cost the pass time on every fragment, for nothing where no
    /// material has them); `textured` for scenes where a material samples a texture (without,
    /// no texture coordinates or tangents are fetched and no sampling is compiled).
    draws: [[LazyPipeline; 2]; 2],
    clear: Pipeline,
    /// Samples are claimed in `sample_claim` (no stencil).
    claim: bool,
    aa: SelectiveAa,
    sampler: crate::gpu::Sampler,
}

impl GbufferCompressedPass {
    /// Creates the pipelines for the depth image bound to `pass`.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let invalid = |m: String| crate::Error::Invalid(format!("pass '{}': {m}", pass.name));
        if !ctx.caps().post_depth_coverage {
            return Err(invalid(format!(
                "gbuffer_compressed needs VK_EXT_post_depth_coverage, which is not enabled on {} (not supported, or \
                 not among a host's `enabled_device_extensions`)",
                ctx.caps().name
            )));
        }
        let depth = bound_image(plan, pass, "depth").ok_or_else(|| invalid("no depth image bound".into()))?;
        let bound = |slot: &str| pass.bindings.iter().any(|b| b.slot == slot);
        // Graph loading checks this too; a plan built another way gets the same error here.
        let owner = SampleOwner::for_depth(depth.0, depth.1.as_raw(), bound("sample_claim")).map_err(invalid)?;
        let mut buffers = Vec::new();
        if owner == SampleOwner::Claim {
            buffers.push(("SAMPLE_CLAIM", "1"));
        }
        let mut defines = buffers.clone();
        if owner == SampleOwner::Claim && claims_in_draw_order(ctx, pass).map_err(invalid)? {
            defines.push(("CLAIM_IN_DRAW_ORDER", "1"));
        }
        if bound("aa_mask") {
            defines.push(("AA_MASK", "1"));
        }
        let draw = |extras: bool, textured: bool| -> crate::Result<LazyPipeline> {
            let mut defines = defines.clone();
            if !extras {
                defines.push(("NO_EMISSION_OCCLUSION", "1"));
            }
            if !textured {
                defines.push(("NO_TEXTURES", "1"));
            }
            let fragment = Some(("gbuffer/gbuffer_compressed.frag", defines.as_slice()));
            let fetch = VertexFetch { normals: true, surface: textured };
            let compiled = GeometryShaders::compile(shaders, &[], fetch, fragment, &[], depth, true)?;
            Ok(LazyPipeline::geometry(&pass.name, compiled))
        };
        let draws = [[draw(false, false)?, draw(false, true)?], [draw(true, false)?, draw(true, true)?]];
        let clear = Pipeline::compute(
            ctx,
            &format!("{} clear", pass.name),
            &shaders.compile("gbuffer/gbuffer_compressed_clear.comp", &buffers)?,
        )?;
        Ok(Self {
            draws,
            clear,
            claim: owner == SampleOwner::Claim,
            aa: SelectiveAa::from_plan(pass)?,
            sampler: crate::gpu::Sampler::nearest_clamp(ctx)?,
        })
    }
}

impl PassNode for GbufferCompressedPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let slots = &rec.slots;
        let depth = slots.required_image("depth")?;
        let bound = BoundGbuffer::resolve(slots, depth, "gbuffer_compressed")?;
        let (gbuffer, pixels, extent) = (bound.buffer, bound.pixels, depth.extent());
        let device = rec.ctx.device();
        let head_pairs = pixels.div_ceil(2) as u32;
        let claim_words = pixels.div_ceil(4) as u32;
        let claim = if self.claim {
            Some(bound.sample_claim.ok_or_else(|| {
                crate::Error::Invalid(
                    "gbuffer_compressed: no sample_claim buffer bound (the depth has no stencil)".into(),
                )
            })?)
        } else {
            None
        };
        let mut clear_binds = vec![Bind::Buffer(0, gbuffer.handle())];
        if let Some(claim) = claim {
            clear_binds.push(Bind::Buffer(2, claim.handle()));
        }
        rec.step("clear");
        self.clear.bind(rec.cmd);
        self.clear.push_bindings(rec.cmd, &clear_binds);
        self.clear.push_constants(rec.cmd, &[head_pairs, claim_words]);
        // SAFETY: cmd recording with the clear pipeline bound.
        unsafe { device.cmd_dispatch(rec.cmd, head_pairs.div_ceil(256).max(1), 1, 1) };
        let fragment_rw = Access {
            stage: vk::PipelineStageFlags2::FRAGMENT_SHADER,
            access: vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            layout: vk::ImageLayout::UNDEFINED,
        };
        cmd_barriers(device, rec.cmd, &[memory_barrier(Access::COMPUTE_WRITE, fragment_rw)], &[]);
        rec.step("draw");
        let push = CompressedPush {
            width: extent.width,
            height: extent.height,
            pool_blocks: bound.pool_blocks,
            aa_region: self.aa.region,
            aa_region_size: self.aa.region_size,
            aa_max_distance: self.aa.max_distance,
            aa_object_flags: self.aa.object_flags as u32,
        };
        let inputs = SceneInputs::of(rec)?;
        let scene = &inputs.scene;
        let lists = DrawSource::redraw_lists(slots, scene)?;
        let mut extra = vec![Bind::Buffer(4, gbuffer.handle()), Bind::Buffer(6, bound.pool.handle())];
        if let Some(claim) = claim {
            extra.push(Bind::Buffer(7, claim.handle()));
        }
        if let Some(mask) = slots.image("aa_mask") {
            extra.push(Bind::Sampled(
                5,
                mask.sampled_view(),
                self.sampler.handle(),
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            ));
        }
        let draw = &mut self.draws[scene.emission_or_occlusion as usize][scene.textured as usize];
        // Its depth test is EQUAL against a depth that already has the masks' holes: every
        // region draws with the one pipeline, which never discards.
        record_geometry(
            rec.ctx,
            rec.cmd,
            &[(draw.get(rec.ctx)?, &FaceCull::DRAWN)],
            scene,
            &lists,
            inputs.constants(),
            &[],
            depth,
            vk::AttachmentLoadOp::LOAD,
            &extra,
            bytemuck::bytes_of(&push),
        );
        Ok(())
    }
}

/// The kind's name in RON.
pub const KIND: &str = "gbuffer_compressed";

/// The header and a head block per pixel, two 16-byte blocks per 32-byte pair.
const HEADS_BYTES: &str = "16 + ceil_div(width * height, 2) * 32";
/// `pool_fraction` blocks per pixel, two 16-byte blocks per 32-byte pair.
const POOL_BYTES: &str = "ceil_div(ceil(width * height * pool_fraction), 2) * 32";
/// A byte of claimed samples per pixel, in whole words.
const CLAIM_BYTES: &str = "ceil_div(width * height, 4) * 4";

/// The `gbuffer_compressed` pass kind.
pub struct GbufferCompressedKind;

impl PassKind for GbufferCompressedKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: KIND,
            doc: "the compressed G-buffer geometry pass: redraws the lists with depth EQUAL, stencil first-fragment-wins (or, without stencil, atomic sample claims) and post-depth coverage, writing one 16-byte block per pixel plus pooled blocks for the other distinct surfaces of edge pixels, in per-pixel linked lists",
            reads: {
                let mut reads = redraw_list_slots();
                reads.push(slot("aa_mask", Usage::Sampled(Stages::Fragment), false, FormatRule::Exact(AA_MASK_FORMAT), "selective AA: only pixels whose mask is not 0 keep more than one block (an aa_edges pass makes it)"));
                reads
            },
            writes: vec![
                ms(slot("depth", Usage::DepthAttachmentLoad, true, FormatRule::Depth, "the finished MSAA depth: with stencil (its stencil is written), or without stencil and a sample_claim buffer")),
                slot("gbuffer", Usage::StorageBufferWrite(Stages::ComputeFragment), true, FormatRule::Any, "header and a head block per pixel").at_least(HEADS_BYTES).creates(Creates::buffer()),
                slot("gbuffer_pool", Usage::StorageBufferWrite(Stages::Fragment), true, FormatRule::Any, "the pool of blocks for the other surfaces of edge pixels, 16 bytes a block, `pool_fraction` blocks per pixel (at most 2^26 - 1 blocks are used)").creates(Creates::buffer_of(POOL_BYTES)),
                slot("sample_claim", Usage::StorageBufferWrite(Stages::ComputeFragment), false, FormatRule::Any, "with a depth format without stencil: the samples already claimed, one byte per pixel (at most 8 samples)").at_least(CLAIM_BYTES).creates(Creates::buffer()),
            ],
            settings: vec![
                SettingDecl::choice::<AaRegion>("aa_region", "selective AA: only pixels inside this screen region (centered, aa_region_size of the screen) keep more than one block"),
                SettingDecl::real("aa_region_size", 0.6, (0.0, 1.0e6), "size of the AA region as a fraction of the screen's width and height"),
                SettingDecl::real("aa_max_depth_distance", 0.0, (0.0, f64::MAX), "selective AA: pixels farther than this distance keep one block (0: no limit)"),
                SettingDecl::flag("aa_object_flags", false, "selective AA: instances flagged no-AA keep one block"),
                SettingDecl::real(POOL_SETTING, 0.5, (0.0, 7.0), "pool blocks per pixel of the pool the pass creates (beyond it, edge samples fall to the head; 7 holds every sample of 8x but the head's); a kind's adaptation may change it from the lighting's counters"),
                SettingDecl { name: "claim_order", default: SettingDefault::Choice(<ClaimOrder as Choice>::WORDS), range: None, doc: "with sample_claim: who wins an exactly coplanar tie. draw: the first fragment in draw order, as the stencil decides, through an ordered sample interlock (needs VK_EXT_fragment_shader_interlock); arrival: the first to claim, which may change from run to run and so flicker; auto: draw where the device has the interlock, else arrival. Refused on a pass whose depth has stencil (the stencil decides, in draw order)" },
            ],
            slots_from_shader: false,
        }
    }

    fn validate(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        sample_owner_error(check).into_iter().collect()
    }

    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let mut out = size_errors(check);
        out.extend(device_error(check));
        out
    }

    fn draw_list(&self) -> Option<DrawList> {
        Some(DrawList { slots: super::gbuffer::LIST_SLOTS, order: DrawOrder::Regions, cluster_slots: &[] })
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(GbufferCompressedPass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }
}

/// A `gbuffer` buffer too small for a head block per pixel of the depth, or a `sample_claim`
/// buffer too small for a byte per pixel, at the binding.
pub(crate) fn size_errors(check: &KindCheck<'_>) -> Vec<(Pos, String)> {
    let Some((_, extent)) = check.image_extent("depth") else { return Vec::new() };
    let pixels = extent.width as u64 * extent.height as u64;
    let bytes_of = |slot: &str| {
        let binding = check.binding(slot)?;
        match check.resolved.get(binding.resource)? {
            crate::graph::Resolved::Buffer(bytes) => Some((binding, *bytes)),
            _ => None,
        }
    };
    let at = |binding: &crate::graph::PassBinding, message: String| {
        (binding.pos, format!("pass '{}' ({}): {message}", check.pass.name, check.pass.kind))
    };
    let mut out = Vec::new();
    if let Some((binding, bytes)) = bytes_of("gbuffer") {
        out.extend(check_heads(bytes, pixels).err().map(|m| at(binding, m)));
    }
    if let Some((binding, bytes)) = bytes_of("sample_claim") {
        if bytes < sample_claim_bytes(pixels) {
            let need = sample_claim_bytes(pixels);
            let message = format!(
                "sample_claim holds {bytes} bytes; {pixels} pixels need {need} (size: ceil_div(width * height, 4) * 4)"
            );
            out.push(at(binding, message));
        }
    }
    out
}

/// A depth format and `sample_claim` binding that leave no way, or two ways, to decide each
/// sample's fragment ([`SampleOwner`]), or a claim order the pass would ignore.
fn sample_owner_error(check: &KindCheck<'_>) -> Option<(Pos, String)> {
    let pass = check.pass;
    let depth = check.binding("depth")?;
    let ResourceDesc::Image { format, .. } = check.graph.resources[depth.resource].desc else { return None };
    if !crate::graph::formats::is_depth(format) {
        return None; // reported as a format error
    }
    let claim = check.binding("sample_claim");
    let count = check.samples.get(depth.resource).copied().unwrap_or(1);
    match SampleOwner::for_depth(format, count, claim.is_some()) {
        // At the binding to change: the claim buffer when there is one, else the depth.
        Err(message) => {
            Some((claim.map_or(depth.pos, |c| c.pos), format!("pass '{}' (gbuffer_compressed): {message}", pass.name)))
        }
        // A claim order the pass would ignore is refused rather than dropped silently.
        Ok(SampleOwner::Stencil) => pass.settings.iter().find(|s| s.name == "claim_order").map(|order| {
            let message = format!(
                "pass '{}' (gbuffer_compressed): claim_order applies to sample claims, but the depth has \
                 stencil, which settles ties in draw order: remove claim_order",
                pass.name
            );
            (order.pos, message)
        }),
        Ok(SampleOwner::Claim) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bytes of a `gbuffer_pool` buffer of `blocks` blocks, as the shipped graphs size it.
    fn pool_bytes(blocks: u64) -> u64 {
        blocks.div_ceil(2) * PAIR_BYTES
    }

    #[test]
    fn pool_sizes_respect_the_26_bit_index() {
        assert_eq!(heads_bytes(3), 16 + 2 * 32);
        assert!(check_heads(heads_bytes(101), 101).is_ok());
        assert!(check_heads(heads_bytes(101) - 1, 101).unwrap_err().contains("take 1648"));
        assert_eq!(pool_blocks(pool_bytes(50)), 50);
        assert_eq!(pool_blocks(pool_bytes(51)), 52); // the odd pair's spare block
        assert_eq!(pool_blocks(27), 0);
        // 8K at 8x: the buffer could hold more, the index cannot.
        let pixels = 7680 * 4320;
        assert_eq!(pool_blocks(pool_bytes(7 * pixels)), MAX_POOL_BLOCKS);
    }

    /// The shipped compressed graphs' buffers at 3840x2160 each fit a 128 MiB binding
    /// (lavapipe's maxStorageBufferRange), with the shipped pool of half a block per pixel.
    #[test]
    fn every_binding_fits_128_mib_at_4k() {
        let pixels = 3840 * 2160;
        assert!(heads_bytes(pixels) <= 1 << 27, "{}", heads_bytes(pixels));
        assert!(pool_bytes(pixels / 2) <= 1 << 27);
    }

    /// Whether `spirv` has an instruction `opcode` whose operand `operand` (counted from the
    /// first word after the opcode) is `value`.
    fn has_instruction(spirv: &[u32], opcode: u32, operand: usize, value: u32) -> bool {
        let mut at = 5; // after the header
        while at < spirv.len() {
            let (count, op) = ((spirv[at] >> 16) as usize, spirv[at] & 0xFFFF);
            if op == opcode && spirv.get(at + 1 + operand) == Some(&value) {
                return true;
            }
            at += count.max(1);
        }
        false
    }

    /// Every variant of the geometry pass's shader compiles, the draw-order claims among them,
    /// which lavapipe never builds (it has no interlock); only they declare the interlock, and
    /// an ordered one.
    #[test]
    fn every_fragment_shader_variant_compiles() {
        const OP_CAPABILITY: u32 = 17;
        const OP_EXECUTION_MODE: u32 = 16;
        const SAMPLE_INTERLOCK: u32 = 5363; // capability FragmentShaderSampleInterlockEXT
        const SAMPLE_INTERLOCK_ORDERED: u32 = 5368; // execution mode SampleInterlockOrderedEXT
        let shaders = ShaderCompiler::new(crate::gpu::ShaderRoot::Embedded).unwrap();
        let variants: [&[(&str, &str)]; 4] = [
            &[],
            &[("SAMPLE_CLAIM", "1")],
            &[("SAMPLE_CLAIM", "1"), ("CLAIM_IN_DRAW_ORDER", "1")],
            &[("SAMPLE_CLAIM", "1"), ("CLAIM_IN_DRAW_ORDER", "1"), ("AA_MASK", "1")],
        ];
        for defines in variants {
            let spirv = shaders.compile("gbuffer/gbuffer_compressed.frag", defines).unwrap();
            let ordered = defines.iter().any(|d| d.0 == "CLAIM_IN_DRAW_ORDER");
            assert_eq!(has_instruction(&spirv, OP_CAPABILITY, 0, SAMPLE_INTERLOCK), ordered, "{defines:?}");
            // Ordered: fragments covering a sample claim it in primitive order.
            assert_eq!(has_instruction(&spirv, OP_EXECUTION_MODE, 1, SAMPLE_INTERLOCK_ORDERED), ordered, "{defines:?}");
        }
    }

    #[test]
    fn stencil_or_claim_decides_each_sample_never_both_nor_neither() {
        let (d32s8, d32) = (vk::Format::D32_SFLOAT_S8_UINT, vk::Format::D32_SFLOAT);
        assert_eq!(SampleOwner::for_depth(d32s8, 8, false), Ok(SampleOwner::Stencil));
        assert_eq!(SampleOwner::for_depth(d32, 8, true), Ok(SampleOwner::Claim));
        assert!(SampleOwner::for_depth(d32, 4, false).unwrap_err().contains("bind a \"sample_claim\" buffer"));
        assert!(SampleOwner::for_depth(d32s8, 4, true).unwrap_err().contains("has stencil"));
        assert!(SampleOwner::for_depth(d32, 16, true).unwrap_err().contains("at most 8 samples"));
    }
}
