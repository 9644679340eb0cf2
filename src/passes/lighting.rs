//! Deferred lighting in compute: sun, point lights, sky ambient (scaled by ambient occlusion)
//! and emission over the G-buffer, written as linear HDR colour into an RGBA16F storage image
//! that the `tonemap` pass maps to the display.

use super::slots::{
    lighting_output_defines, lighting_settings, ms, slot, DebugView, EMISSIVE_OCCLUSION_SLOT_DOC,
    GBUFFER_ALBEDO_FORMAT, GBUFFER_EMISSIVE_OCCLUSION_FORMAT, GBUFFER_NORMAL_FORMATS, LIGHTING_OUTPUT_DOC,
    LIGHTING_OUTPUT_FORMATS, NORMAL_SLOT_DOC,
};
use crate::gpu::{Bind, Buffer, GpuContext, Image, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::{FormatRule, NodeSetup, PassKind, PassKindInfo, PassNode, Stages, Usage};
use crate::passes::gbuffer::{bound_image, normal_defines};
use crate::passes::shared::shadow_variants::ShadowVariants;
use crate::passes::shared::{SceneInputs, ShadowMaps};
use ash::vk;

/// What the pass reads and writes.
pub struct LightingInputs<'a> {
    /// Depth, in `SHADER_READ_ONLY_OPTIMAL`.
    pub depth: &'a Image,
    /// Albedo/metallic, in `SHADER_READ_ONLY_OPTIMAL`.
    pub albedo: &'a Image,
    /// Normal/roughness, in `SHADER_READ_ONLY_OPTIMAL`.
    pub normal: &'a Image,
    /// Emissive/occlusion, in `SHADER_READ_ONLY_OPTIMAL`, when the pass was created with it and
    /// the geometry passes wrote it (the scene has emission or occlusion).
    pub emissive_occlusion: Option<&'a Image>,
    /// Frame constants.
    pub frame: &'a Buffer,
    /// Point lights.
    pub lights: &'a Buffer,
    /// The shadow maps.
    pub shadow_maps: ShadowMaps,
    /// Output, in `GENERAL`.
    pub output: &'a Image,
}

/// Push constants of `lighting.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightingSettings {
    /// The exposure the tonemap pass applies: pixels with several surfaces are resolved in
    /// tone-mapped space with it.
    pub exposure: f32,
    /// 0 lit, 1 normals, 2 albedo, 3 depth, 4 samples (`DEBUG_VIEW_*` in `scene.glsl`).
    pub debug_view: u32,
    /// 1: cull point lights per 16x16 tile; 0: every light for every pixel.
    pub light_tiles: u32,
}

impl LightingSettings {
    /// The settings that are push constants, which a lighting pass takes without being made
    /// again ([`crate::graph::PassNode::live_settings`]).
    pub const LIVE: &'static [&'static str] = &["exposure", "debug_view", "light_tiles"];

    /// From the pass's graph settings (`exposure`, `debug_view`, `light_tiles`).
    pub fn from_plan(pass: &PlannedPass) -> crate::Result<Self> {
        let exposure = pass.real("exposure")? as f32;
        // The variants' order is `DEBUG_VIEW_*`'s.
        let debug_view = pass.choice::<DebugView>("debug_view")? as u32;
        let light_tiles = pass.flag("light_tiles")?;
        Ok(Self { exposure, debug_view, light_tiles: light_tiles as u32 })
    }
}

/// The lighting pass.
pub struct LightingPass {
    pipeline: ShadowVariants,
    /// With an `emissive_occlusion` image bound: the pipelines that read it, used while the
    /// scene has emission or occlusion (the geometry passes write it only then), created when
    /// first used.
    extras_pipeline: Option<ShadowVariants>,
    sampler: Sampler,
    settings: LightingSettings,
}

impl LightingPass {
    /// Compiles the shader for G-buffer images of `samples` samples whose normal image has
    /// `normal_format` (one of [`crate::passes::slots::GBUFFER_NORMAL_FORMATS`]), with an
    /// emissive/occlusion image or without, writing linear HDR colour (`hdr`) or the
    /// tone-mapped image, and creates the pipeline.
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        samples: vk::SampleCountFlags,
        normal_format: vk::Format,
        emissive_occlusion: bool,
        hdr: bool,
    ) -> crate::Result<Self> {
        let samples = samples.as_raw().max(1).to_string();
        let mut defines = vec![("SAMPLES", samples.as_str())];
        defines.extend_from_slice(normal_defines(Some(normal_format)));
        if hdr {
            defines.push(("HDR_OUTPUT", "1"));
        }
        let mut pipeline = ShadowVariants::compute("lighting", shaders, "lighting/lighting.comp", &defines)?;
        // Made now: a pipeline the device refuses fails the graph's build, not its first frame.
        pipeline.pick(ctx, ShadowMaps::default(), &mut Vec::new())?;
        let extras_pipeline = if emissive_occlusion {
            defines.push(("EMISSIVE_OCCLUSION", "1"));
            Some(ShadowVariants::compute("lighting", shaders, "lighting/lighting.comp", &defines)?)
        } else {
            None
        };
        let settings = LightingSettings { exposure: 0.8, debug_view: 0, light_tiles: 1 };
        Ok(Self { pipeline, extras_pipeline, sampler: Sampler::nearest_clamp(ctx)?, settings })
    }

    /// The pass configured by a graph node's settings, for the sample count of its bound depth.
    pub fn for_plan(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let samples = bound_image(plan, pass, "depth").map_or(vk::SampleCountFlags::TYPE_1, |(_, s)| s);
        let normal = bound_image(plan, pass, "normal").map_or(crate::passes::slots::GBUFFER_NORMAL_PACKED, |(f, _)| f);
        let emissive_occlusion = bound_image(plan, pass, "emissive_occlusion").is_some();
        let hdr = !lighting_output_defines(plan, pass).is_empty();
        Ok(Self {
            settings: LightingSettings::from_plan(pass)?,
            ..Self::new(ctx, shaders, samples, normal, emissive_occlusion, hdr)?
        })
    }

    /// Records one dispatch over the output.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        cmd: vk::CommandBuffer,
        io: &LightingInputs<'_>,
        settings: &LightingSettings,
    ) -> crate::Result<()> {
        let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let s = self.sampler.handle();
        let mut binds = vec![
            Bind::Sampled(0, io.depth.sampled_view(), s, read),
            Bind::Sampled(1, io.albedo.sampled_view(), s, read),
            Bind::Sampled(2, io.normal.sampled_view(), s, read),
            Bind::Buffer(3, io.frame.handle()),
            Bind::Buffer(4, io.lights.handle()),
            Bind::StorageImage(5, io.output.view()),
        ];
        let pipeline = match (io.emissive_occlusion, &mut self.extras_pipeline) {
            (Some(image), Some(extras)) => {
                binds.push(Bind::Sampled(6, image.sampled_view(), s, read));
                extras.pick(ctx, io.shadow_maps, &mut binds)?
            }
            _ => self.pipeline.pick(ctx, io.shadow_maps, &mut binds)?,
        };
        pipeline.dispatch_over(cmd, &binds, bytemuck::bytes_of(settings), io.output.extent());
        Ok(())
    }
}

impl PassNode for LightingPass {
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
        let io = LightingInputs {
            depth: slots.required_image("depth")?,
            albedo: slots.required_image("albedo")?,
            normal: slots.required_image("normal")?,
            emissive_occlusion: slots.image("emissive_occlusion").filter(|_| inputs.scene.emission_or_occlusion),
            frame: inputs.constants(),
            lights: inputs.lights(),
            shadow_maps: inputs.shadow_maps(),
            output: slots.required_image("output")?,
        };
        let settings = self.settings;
        LightingPass::record(self, rec.ctx, rec.cmd, &io, &settings)
    }
}

/// The `lighting` pass kind.
pub struct LightingKind;

impl PassKind for LightingKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "lighting",
            doc: "deferred lighting in compute: sun, point lights and sky ambient, written as linear HDR colour (tonemap maps it)",
            reads: vec![
                ms(slot(
                    "depth",
                    Usage::Sampled(Stages::Compute),
                    true,
                    FormatRule::Depth,
                    "reversed-Z depth (multisampled: every sample is lit)",
                )),
                ms(slot(
                    "albedo",
                    Usage::Sampled(Stages::Compute),
                    true,
                    FormatRule::Exact(GBUFFER_ALBEDO_FORMAT),
                    "albedo, metallic",
                )),
                ms(slot(
                    "normal",
                    Usage::Sampled(Stages::Compute),
                    true,
                    FormatRule::OneOf(GBUFFER_NORMAL_FORMATS),
                    NORMAL_SLOT_DOC,
                )),
                ms(slot(
                    "emissive_occlusion",
                    Usage::Sampled(Stages::Compute),
                    false,
                    FormatRule::Exact(GBUFFER_EMISSIVE_OCCLUSION_FORMAT),
                    EMISSIVE_OCCLUSION_SLOT_DOC,
                )),
            ],
            writes: vec![slot(
                "output",
                Usage::StorageImageWrite(Stages::Compute),
                true,
                FormatRule::OneOf(LIGHTING_OUTPUT_FORMATS),
                LIGHTING_OUTPUT_DOC,
            )],
            settings: lighting_settings(),
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(LightingPass::for_plan(s.ctx, s.shaders, s.pass, s.plan)?))
    }
}
