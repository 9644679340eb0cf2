//! Lighting over the compressed G-buffer in compute (`lighting_compressed`): each block of a
//! pixel's list is shaded once with the tile's lights and weighted by the samples it covers.
//! It also reports the pool's counters and how many distinct surfaces the pixels hold
//! ([`counters`]), from which the kind's policy sizes the pool (its `pool` module).

pub mod counters;
pub(crate) mod pool;

use super::gbuffer::bound_samples;
use super::gbuffer_compressed::BoundGbuffer;
use super::lighting::LightingSettings;
use super::slots::{
    lighting_output_defines, lighting_settings, ms, slot, COUNTERS_BYTES, LIGHTING_OUTPUT_DOC, LIGHTING_OUTPUT_FORMATS,
};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::{
    Adaptation, CounterEntry, Counters, Creates, FormatRule, KindCheck, NodeSetup, PassKind, PassKindInfo, PassNode,
    Pos, SettingDecl, Stages, Usage,
};
use crate::passes::shared::shadow_variants::ShadowVariants;
use crate::passes::shared::ShadowMaps;
pub use counters::{GbufferCounters, GbufferPassStats};

/// The kind's name in RON.
pub(crate) const KIND: &str = "lighting_compressed";
use crate::passes::shared::SceneInputs;
use ash::vk;

/// Pool blocks a tile shades together unless the graph says otherwise (`shared_blocks`).
const DEFAULT_SHARED_BLOCKS: u32 = 512;
/// Tiles with at most this many pool blocks leave them to their pixels (`shared_min_blocks`).
const DEFAULT_SHARED_MIN_BLOCKS: u32 = 0;
/// Most `shared_blocks` allowed.
const MAX_SHARED_BLOCKS: u32 = 1024;
/// Shared memory per shared block (link, owner and pixel, half-float color) and for the rest of
/// the shader (light bits, depth range, counters), rounded up.
const SHARED_BYTES_PER_BLOCK: u32 = 16;
const SHARED_BYTES_OTHER: u32 = 1024;

/// Push constants of `lighting_compressed.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    settings: LightingSettings,
    pool_blocks: u32,
}

/// The `lighting_compressed` pass.
pub(crate) struct LightingCompressedPass {
    pipeline: ShadowVariants,
    stats_clear: Option<Pipeline>,
    sampler: Sampler,
    settings: LightingSettings,
}

/// Shared memory a tile takes to shade `shared_blocks` blocks together.
fn shared_bytes(shared_blocks: u32) -> u32 {
    shared_blocks * SHARED_BYTES_PER_BLOCK + SHARED_BYTES_OTHER
}

/// `shared_blocks` beyond the device's shared memory.
fn shared_memory_error(check: &KindCheck<'_>) -> Option<(Pos, String)> {
    let (limits, planned) = (check.limits?, check.planned?);
    let blocks = block_count_setting(planned, "shared_blocks").ok()?;
    let (bytes, limit) = (shared_bytes(blocks), limits.compute.max_shared_memory_bytes);
    (bytes > limit).then(|| {
        let at = check.pass.settings.iter().find(|s| s.name == "shared_blocks").map_or(check.pass.pos, |s| s.pos);
        let message = format!(
            "pass '{}': shared_blocks {blocks} needs about {bytes} bytes of shared memory; {} has {limit} \
             (maxComputeSharedMemorySize)",
            check.pass.name, limits.device
        );
        (at, message)
    })
}

/// Setting `name` of `pass`, a block count (its declared range keeps it within a u32).
fn block_count_setting(pass: &PlannedPass, name: &str) -> crate::Result<u32> {
    Ok(pass.int(name)?.clamp(0, u32::MAX as i64) as u32)
}

impl LightingCompressedPass {
    /// Compiles the shader for the sample count of the depth bound to `pass`.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let samples = bound_samples(plan, pass, "depth").to_string();
        let with_stats = pass.bindings.iter().any(|b| b.slot == "stats");
        let shared_blocks = block_count_setting(pass, "shared_blocks")?;
        let shared_bytes = shared_bytes(shared_blocks);
        let limit = ctx.caps().limits.max_compute_shared_memory_size;
        // Checked when the graph is compiled (shared_memory_error); a host's own compile may not have.
        if shared_bytes > limit {
            return Err(crate::Error::Invalid(format!(
                "pass '{}': shared_blocks {shared_blocks} needs about {shared_bytes} bytes of shared memory; this device has {limit}",
                pass.name
            )));
        }
        let shared_blocks = shared_blocks.to_string();
        let shared_min_blocks = format!("{}u", block_count_setting(pass, "shared_min_blocks")?);
        let mut defines = vec![
            ("SAMPLES", samples.as_str()),
            ("SHARED_BLOCKS", shared_blocks.as_str()),
            ("SHARED_MIN_BLOCKS", shared_min_blocks.as_str()),
        ];
        if pass.bindings.iter().any(|b| b.slot == "sample_claim") {
            defines.push(("SAMPLE_CLAIM", "1"));
        }
        if with_stats {
            defines.push(("WRITE_STATS", "1"));
        }
        defines.extend_from_slice(lighting_output_defines(plan, pass));
        let mut pipeline = ShadowVariants::compute(&pass.name, shaders, "lighting/lighting_compressed.comp", &defines)?;
        // Made now: a pipeline the device refuses fails the graph's build, not its first frame.
        pipeline.pick(ctx, ShadowMaps::default(), &mut Vec::new())?;
        let stats_clear = with_stats
            .then(|| -> crate::Result<Pipeline> {
                let spirv = shaders.compile("lighting/stats_clear.comp", &[])?;
                Ok(Pipeline::compute(ctx, &format!("{} stats clear", pass.name), &spirv)?)
            })
            .transpose()?;
        Ok(Self {
            pipeline,
            stats_clear,
            sampler: Sampler::nearest_clamp(ctx)?,
            settings: LightingSettings::from_plan(pass)?,
        })
    }
}

impl PassNode for LightingCompressedPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn samples_shadow_maps(&self) -> bool {
        true
    }

    fn live_settings(&self) -> &'static [&'static str] {
        LightingSettings::LIVE
    }

    fn apply_settings(&mut self, pass: &PlannedPass) -> crate::Result<()> {
        self.settings = LightingSettings::from_plan(pass)?;
        Ok(())
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let inputs = SceneInputs::of(rec)?;
        let slots = &rec.slots;
        let depth = slots.required_image("depth")?;
        let output = slots.required_image("output")?;
        let bound = BoundGbuffer::resolve(slots, depth, "lighting_compressed")?;
        let gbuffer = bound.buffer;
        let device = rec.ctx.device();
        let stats = slots.buffer("stats");
        if let (Some(clear), Some(stats)) = (&self.stats_clear, stats) {
            clear.bind(rec.cmd);
            clear.push_bindings(rec.cmd, &[Bind::Buffer(0, stats.handle())]);
            // SAFETY: cmd recording with the clear pipeline bound.
            unsafe { device.cmd_dispatch(rec.cmd, 1, 1, 1) };
            let rw = Access {
                stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
                access: vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
                layout: vk::ImageLayout::UNDEFINED,
            };
            cmd_barriers(device, rec.cmd, &[memory_barrier(Access::COMPUTE_WRITE, rw)], &[]);
        }
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let mut binds = vec![
            Bind::Sampled(0, depth.sampled_view(), self.sampler.handle(), read),
            Bind::Buffer(1, gbuffer.handle()),
            Bind::Buffer(7, bound.pool.handle()),
            Bind::Buffer(2, inputs.constants().handle()),
            Bind::Buffer(3, inputs.lights().handle()),
            Bind::StorageImage(4, output.view()),
        ];
        if let Some(stats) = stats {
            binds.push(Bind::Buffer(5, stats.handle()));
        }
        if let Some(claim) = bound.sample_claim {
            binds.push(Bind::Buffer(6, claim.handle()));
        }
        let push = Push { settings: self.settings, pool_blocks: bound.pool_blocks };
        let pipeline = self.pipeline.pick(rec.ctx, inputs.shadow_maps(), &mut binds)?;
        pipeline.dispatch_over(rec.cmd, &binds, bytemuck::bytes_of(&push), output.extent());
        Ok(())
    }
}

/// The `lighting_compressed` pass kind.
pub struct LightingCompressedKind;

impl PassKind for LightingCompressedKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: KIND,
            doc: "lights the compressed G-buffer in compute: every block shaded once with tile-culled point lights, tone-mapped, weighted by the samples it covers, averaged",
            reads: vec![
                ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "the MSAA depth (positions are rebuilt from each block's sample)")),
                slot("gbuffer", Usage::StorageBufferRead(Stages::Compute), true, FormatRule::Any, "the compressed G-buffer's header and heads"),
                slot("gbuffer_pool", Usage::StorageBufferRead(Stages::Compute), true, FormatRule::Any, "its pool"),
                slot("sample_claim", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "the samples gbuffer_compressed's fragments claimed (with a depth without stencil): the covered samples in one word instead of a read of every depth sample"),
            ],
            writes: vec![
                slot("output", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::OneOf(LIGHTING_OUTPUT_FORMATS), LIGHTING_OUTPUT_DOC),
                slot("stats", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "pool counters and a blocks-per-pixel histogram (created when unbound; read as `pass.stats`)").exactly(COUNTERS_BYTES).creates(Creates::buffer().always()).counters(Counters::ThisFrame),
            ],
            settings: {
                let mut settings = lighting_settings();
                settings.push(SettingDecl::int("shared_blocks", DEFAULT_SHARED_BLOCKS as i64, (0, MAX_SHARED_BLOCKS as i64), "pool blocks a 16x16 tile gathers and shades with all its invocations per round, in up to four rounds (0..=1024; 0: each pixel loops over its own list, the thesis's resolve)"));
                settings.push(SettingDecl::int("shared_min_blocks", DEFAULT_SHARED_MIN_BLOCKS as i64, (0, u32::MAX as i64), "a tile with at most this many pool blocks leaves them to their pixels' own loops (0: every tile shares its blocks, the fastest on the H100)"));
                settings
            },
            slots_from_shader: false,
        }
    }

    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let mut out = super::gbuffer_compressed::size_errors(check);
        out.extend(shared_memory_error(check));
        out
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(LightingCompressedPass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }

    fn decode_counters(&self, pass: &str, _slot: &str, bytes: &[u8]) -> Option<CounterEntry> {
        GbufferPassStats::entry(pass, bytes)
    }

    fn adaptation(&self) -> Option<Box<dyn Adaptation>> {
        Some(Box::new(pool::PoolAdaptation::default()))
    }
}
