//! Geometry passes that draw the culled draw lists with `vkCmdDrawIndexedIndirectCount`:
//!
//! - `gbuffer`: clears depth and draws albedo/metallic, normal/roughness (and, where bound,
//!   emissive/occlusion) and reversed-Z depth, or
//!   depth alone when no color target is bound (the MSAA Z-prepass of the compressed G-buffer);
//! - `gbuffer_append`: the same on top of what an earlier pass drew (two-phase culling's late draw);
//! - `gbuffer_equal`: the MSAA Z-prepass baseline: depth EQUAL against a finished depth buffer,
//!   one stencil bit per sample so each sample is written once.
//!
//! `gbuffer` and `gbuffer_append` also write per-pixel motion vectors where the graph binds
//! `motion` ([`MOTION_FORMAT`], `shaders/gbuffer/motion.glsl`): each vertex is projected with
//! this frame's unjittered matrix and, at its instance's previous transform
//! ([`GpuScene::previous_instances`]), with last frame's unjittered matrix relative to last
//! frame's eye; the fragment takes the difference of the two projections, in pixels. `gbuffer`
//! always clears `motion` to 0, the value the background keeps.
//!
//! The color targets are cleared only with the `clear_colors` setting. Readers tell background
//! from geometry by depth (0 = nothing drawn), so a clear would only write texels nobody reads,
//! a full-screen write that is a large share of a culled frame (`docs/history.md`).
//!
//! Formats and the sample count come from the bound images, so one pass serves no AA and every
//! MSAA rate.

use super::slots::{
    clear_colors_setting, draw_list_slots, ms, redraw_list_slots, slot, EMISSIVE_OCCLUSION_SLOT_DOC,
    GBUFFER_ALBEDO_FORMAT, GBUFFER_EMISSIVE_OCCLUSION_FORMAT, GBUFFER_NORMAL_FORMATS, MOTION_FORMAT, MOTION_SLOT_DOC,
    NORMAL_SLOT_DOC, VISIBILITY_FORMATS,
};
use crate::gpu::barrier::layout_for_format;
use crate::gpu::cmd_set_full_viewport;
use crate::gpu::Spirv;
use crate::gpu::{Bind, Buffer, GpuContext, GraphicsDesc, Image, Pipeline, ShaderCompiler, StencilRule};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass, ResolvedKind};
use crate::graph::validated::ResourceDesc;
use crate::graph::{
    DrawList, DrawOrder, FormatRule, Growth, KindCheck, NodeSetup, PassKind, PassKindInfo, PassNode, Pos, Quantity,
    Usage,
};
use crate::passes::shared::face_cull::{FaceCull, DRAW_COUNT_BYTES};
use crate::passes::shared::lazy_pipeline::LazyPipeline;
use crate::passes::shared::scene_buffers::GpuScene;
use crate::passes::shared::vertex_streams::{VertexFetch, VERTEX_STRIDES};
use crate::passes::shared::SceneInputs;
use ash::vk;

/// Slots of a geometry pass's draw list.
pub const LIST_SLOTS: [&str; 3] = ["draw_commands", "draw_count", "draw_instance_ids"];
/// Slots of a redraw pass's second (late) list.
pub const LATE_LIST_SLOTS: [&str; 3] = ["late_draw_commands", "late_draw_count", "late_draw_instance_ids"];

/// Where the draws come from: the scene's unculled list, or a culling pass's output.
pub struct DrawSource<'a> {
    /// `VkDrawIndexedIndirectCommand`s.
    pub commands: &'a Buffer,
    /// Their number in each face-cull region (read by the GPU).
    pub count: &'a Buffer,
    /// Instance ids, one slice per command.
    pub instance_ids: &'a Buffer,
    /// A `cluster_cull` pass's cluster list (commands, counts), drawn after the list with the
    /// same instance ids.
    pub clusters: Option<(&'a Buffer, &'a Buffer)>,
    /// Its list of the alpha-masked instances' clusters, drawn with the alpha-tested pipelines.
    pub masked_clusters: Option<(&'a Buffer, &'a Buffer)>,
}

impl<'a> DrawSource<'a> {
    /// Every instance of the scene.
    pub fn unculled(scene: &'a GpuScene) -> Self {
        Self {
            commands: &scene.draw_commands,
            count: &scene.draw_count,
            instance_ids: &scene.draw_instance_ids,
            clusters: None,
            masked_clusters: None,
        }
    }

    /// The list bound to the slots `names` (commands, count, instance ids), if all three are
    /// bound; an error if its count buffer cannot hold a count per face-cull region.
    pub fn bound(slots: &crate::graph::executor::SlotBindings<'a>, names: [&str; 3]) -> crate::Result<Option<Self>> {
        let (Some(commands), Some(count), Some(instance_ids)) =
            (slots.buffer(names[0]), slots.buffer(names[1]), slots.buffer(names[2]))
        else {
            return Ok(None);
        };
        if count.size() < DRAW_COUNT_BYTES {
            return Err(crate::Error::Invalid(format!(
                "pass '{}': {} holds {} bytes; a draw count holds one count per face cull ({DRAW_COUNT_BYTES} bytes)",
                slots.pass_name(),
                names[1],
                count.size()
            )));
        }
        Ok(Some(Self { commands, count, instance_ids, clusters: None, masked_clusters: None }))
    }

    /// The lists a redraw pass draws: the first list (or every instance when none is bound),
    /// then the `late_` list when bound (two-phase culling draws in two lists).
    pub fn redraw_lists(
        slots: &crate::graph::executor::SlotBindings<'a>,
        scene: &'a GpuScene,
    ) -> crate::Result<Vec<Self>> {
        let mut lists = vec![Self::bound(slots, LIST_SLOTS)?.unwrap_or_else(|| Self::unculled(scene))];
        lists.extend(Self::bound(slots, LATE_LIST_SLOTS)?);
        Ok(lists)
    }
}

/// Format and samples of the image bound to `slot` of `pass`.
pub fn bound_image(plan: &CompiledGraph, pass: &PlannedPass, slot: &str) -> Option<(vk::Format, vk::SampleCountFlags)> {
    let binding = pass.bindings.iter().find(|b| b.slot == slot)?;
    match &plan.resources.get(binding.resource)?.kind {
        ResolvedKind::Image { format, samples, .. } => Some((*format, *samples)),
        ResolvedKind::Buffer { .. } => None,
    }
}

/// The defines of the shaders that write or read a visibility-id image of `format`:
/// `PACKED_IDS` for one word per sample (`visibility_ids`).
pub fn visibility_defines(format: Option<vk::Format>) -> &'static [(&'static str, &'static str)] {
    if format == Some(crate::passes::slots::VISIBILITY_PACKED) {
        &[("PACKED_IDS", "1")]
    } else {
        &[]
    }
}

/// The scene's triangle bits for packed visibility ids (`visibility_ids`), or the error that
/// names `pass`.
pub fn packed_id_bits(pass: &str, scene: &GpuScene) -> crate::Result<u32> {
    super::visibility_ids::triangle_bits(scene.instance_count, scene.max_mesh_triangles)
        .map_err(|m| crate::Error::Invalid(format!("pass '{pass}': {m}")))
}

/// The defines of the shaders that write or read a G-buffer normal image of `format`
/// (`shaders/common/gbuffer_normal.glsl`): `NORMAL_PACKED` for the packed word.
pub fn normal_defines(format: Option<vk::Format>) -> &'static [(&'static str, &'static str)] {
    if format == Some(crate::passes::slots::GBUFFER_NORMAL_PACKED) {
        &[("NORMAL_PACKED", "1")]
    } else {
        &[]
    }
}

/// Samples per texel of the image bound to `slot` of `pass` (1 when none is bound): the
/// `SAMPLES` define of the compute shaders that read multisampled images.
pub fn bound_samples(plan: &CompiledGraph, pass: &PlannedPass, slot: &str) -> u32 {
    bound_image(plan, pass, slot).map_or(1, |(_, s)| s.as_raw().max(1))
}

/// A geometry pipeline's compiled shaders and fixed state: `gbuffer.vert` (whose invariant
/// position every geometry pass shares, so depth EQUAL against another pass's depth holds
/// exactly) and a fragment shader, its color formats and depth. `equal`: depth EQUAL without
/// writes and, where the format has stencil, stencil first-fragment-wins.
pub struct GeometryShaders {
    vertex: Spirv,
    fetch: VertexFetch,
    fragment: Option<Spirv>,
    color_formats: Vec<vk::Format>,
    depth: (vk::Format, vk::SampleCountFlags),
    equal: bool,
}

impl GeometryShaders {
    /// Compiles `gbuffer.vert` with its defines (`MOTION`: the clip positions motion vectors
    /// are made from; its `gl_Position` is the same either way), fetching only the vertex
    /// streams of `fetch`, and the fragment shader `fragment` with its defines, if any.
    pub fn compile(
        shaders: &ShaderCompiler,
        vertex_defines: &[(&str, &str)],
        fetch: VertexFetch,
        fragment: Option<(&str, &[(&str, &str)])>,
        color_formats: &[vk::Format],
        depth: (vk::Format, vk::SampleCountFlags),
        equal: bool,
    ) -> crate::Result<Self> {
        let mut all_vertex_defines = vertex_defines.to_vec();
        all_vertex_defines.extend(fetch.defines());
        let vertex = shaders.compile("gbuffer/gbuffer.vert", &all_vertex_defines)?;
        // Masked materials keep a share of the samples (shaders/common/material_surface.glsl).
        let samples = depth.1.as_raw().max(1).to_string();
        let fragment = fragment
            .map(|(path, defines)| {
                let mut all = defines.to_vec();
                all.push(("MSAA_SAMPLES", samples.as_str()));
                shaders.compile(path, &all)
            })
            .transpose()?;
        Ok(Self { vertex, fetch, fragment, color_formats: color_formats.to_vec(), depth, equal })
    }

    /// Creates the pipeline.
    pub fn create(&self, ctx: &GpuContext, name: &str) -> crate::Result<Pipeline> {
        let (depth, equal) = (self.depth, self.equal);
        Ok(Pipeline::graphics(
            ctx,
            name,
            &GraphicsDesc {
                vertex: &self.vertex,
                fragment: self.fragment.as_ref(),
                vertex_strides: &VERTEX_STRIDES,
                vertex_attributes: &self.fetch.attributes(),
                color_formats: &self.color_formats,
                depth_format: depth.0,
                depth_compare: if equal { vk::CompareOp::EQUAL } else { vk::CompareOp::GREATER },
                depth_write: !equal,
                samples: depth.1,
                // EQUAL redraws without stencil decide each sample otherwise (gbuffer_compressed's
                // sample_claim); the passes refuse that combination where they have no other way.
                stencil: if equal && crate::gpu::image::aspect_of(depth.0).contains(vk::ImageAspectFlags::STENCIL) {
                    StencilRule::FirstFragmentWins
                } else {
                    StencilRule::Off
                },
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                blend: false,
            },
        )?)
    }
}

/// Which regions of each list a pipeline draws ([`FaceCull`]).
pub type RegionDraw<'a> = (&'a Pipeline, &'a [FaceCull]);

/// Records `lists` inside dynamic rendering over `colors` and `depth`: for each of `draws` in
/// turn, its regions of every list with its pipeline (a list's cluster draws go with the
/// opaque regions). `extra` bindings (binding 4 and up) are pushed after the shared ones;
/// `push` is the pipelines' push-constant block (empty for none).
#[allow(clippy::too_many_arguments)]
pub fn record_geometry(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    draws: &[RegionDraw<'_>],
    scene: &GpuScene,
    lists: &[DrawSource<'_>],
    frame: &Buffer,
    colors: &[vk::RenderingAttachmentInfo<'_>],
    depth: &Image,
    depth_load: vk::AttachmentLoadOp,
    extra: &[Bind],
    push: &[u8],
) {
    let device = ctx.device();
    let extent = depth.extent();
    let depth_layout = layout_for_format(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, depth.format());
    let depth_info = vk::RenderingAttachmentInfo::default()
        .image_view(depth.view())
        .image_layout(depth_layout)
        .load_op(depth_load)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 0.0, stencil: 0 } });
    let has_stencil = depth.aspect().contains(vk::ImageAspectFlags::STENCIL);
    let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
    let mut rendering = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(colors)
        .depth_attachment(&depth_info);
    if has_stencil {
        rendering = rendering.stencil_attachment(&depth_info);
    }
    // SAFETY: cmd is recording; every handle is alive for the command buffer's execution.
    unsafe {
        device.cmd_begin_rendering(cmd, &rendering);
        cmd_set_full_viewport(device, cmd, extent);
        scene.vertices.bind(device, cmd);
        device.cmd_bind_index_buffer(cmd, scene.indices.handle(), 0, vk::IndexType::UINT32);
        for &(pipeline, regions) in draws {
            pipeline.bind(cmd);
            pipeline.push_constant_bytes(cmd, push);
            for list in lists {
                let mut binds = vec![
                    Bind::Buffer(1, list.instance_ids.handle()),
                    Bind::Buffer(2, frame.handle()),
                    Bind::Buffer(3, scene.materials.handle()),
                ];
                binds.extend(scene.instance_binds(0));
                binds.extend_from_slice(scene.textures.bindings());
                binds.extend_from_slice(extra);
                pipeline.push_bindings(cmd, &binds);
                scene.regions.record(device, cmd, list.commands, list.count, regions);
                // Each cluster list with the pipeline of its materials.
                for (clusters, kind) in [(list.clusters, FaceCull::OPAQUE), (list.masked_clusters, FaceCull::MASKED)] {
                    if let Some((commands, count)) = clusters.filter(|_| regions.contains(&kind[0])) {
                        crate::passes::cluster_cull::record_cluster_draws(ctx, cmd, commands, count, kind);
                    }
                }
            }
        }
        device.cmd_end_rendering(cmd);
    }
}

/// The G-buffer's color targets in attachment order (`gbuffer.frag`'s outputs).
const GBUFFER_COLOR_SLOTS: [&str; 3] = ["albedo", "normal", "emissive_occlusion"];

/// How a geometry pass treats what is already in its targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryMode {
    /// Clear everything, depth test GREATER with writes (`gbuffer`).
    Clear,
    /// Keep what earlier passes drew (`gbuffer_append`).
    Append,
    /// Test EQUAL against the finished depth, stencil first-fragment-wins (`gbuffer_equal`).
    Equal,
}

/// The pipelines of one geometry pass, by what the scene has: a third target for emission and
/// occlusion (`extras`), alpha-masked materials (`masked`), and textures (`textured`: only
/// then are texture coordinates and tangents fetched, see [`VertexFetch`]).
///
/// Without an alpha test the fragment shaders have no `discard`, so the depth test runs
/// before shading: on the H100 this takes a sixth off the textured single-sample G-buffer
/// draw. So opaque materials always draw with those, and masked materials, from regions of
/// their own ([`FaceCull::MASKED`]), with the alpha-tested pipelines. Without emission or
/// occlusion the `emissive_occlusion` target is left out: a third color export costs a fifth
/// of the frame on GPUs that export pixels slowly, for nothing.
struct GeometryPipelines {
    /// `[extras][masked][textured]`, created when first picked; the `extras` row only where
    /// the target is bound.
    variants: [[[Option<LazyPipeline>; 2]; 2]; 2],
}

impl GeometryPipelines {
    /// The pipelines for a scene with (or without) emission or occlusion and textures: the one
    /// for opaque materials, and the alpha-tested one for masked materials if `masked`.
    fn pick(
        &mut self,
        ctx: &GpuContext,
        extras: bool,
        masked: bool,
        textured: bool,
    ) -> crate::Result<(&Pipeline, Option<&Pipeline>)> {
        let row = if self.writes_extras(extras) { 1 } else { 0 };
        let [opaque, alpha_tested] = &mut self.variants[row];
        let made = "every variant of a row is made";
        let opaque = opaque[textured as usize].as_mut().expect(made).get(ctx)?;
        let alpha_tested = match masked {
            true => Some(alpha_tested[textured as usize].as_mut().expect(made).get(ctx)?),
            false => None,
        };
        Ok((opaque, alpha_tested))
    }

    /// Whether the pass draws the emissive/occlusion target for such a scene.
    fn writes_extras(&self, extras: bool) -> bool {
        extras && self.variants[1][0][0].is_some()
    }
}

/// The `gbuffer`, `gbuffer_append` and `gbuffer_equal` passes.
pub struct GbufferPass {
    /// The pass's name in the graph, for messages.
    name: String,
    pipelines: GeometryPipelines,
    mode: GeometryMode,
    /// The `clear_colors` setting (`gbuffer_append` has none: it loads what is there).
    clear_colors: bool,
    /// Visibility ids packed in one word (`visibility_ids`): the triangle bits are pushed.
    packed_ids: bool,
    /// Whether `motion` is bound: the pipelines write motion vectors after the other targets.
    motion: bool,
    /// Whether `object_id` is bound: the pipelines write each pixel's instance id last.
    object_id: bool,
}

impl GbufferPass {
    /// The pass for `pass`, with formats and samples from the images bound to it in `plan`.
    pub fn for_plan(
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
        mode: GeometryMode,
    ) -> crate::Result<Self> {
        let invalid = |m: String| crate::Error::Invalid(format!("pass '{}': {m}", pass.name));
        let depth = bound_image(plan, pass, "depth").ok_or_else(|| invalid("no depth image bound".into()))?;
        let colors: Vec<vk::Format> =
            GBUFFER_COLOR_SLOTS.iter().filter_map(|s| bound_image(plan, pass, s).map(|(f, _)| f)).collect();
        let ids = bound_image(plan, pass, "ids");
        let surface = ["albedo", "normal"].iter().filter(|s| bound_image(plan, pass, s).is_some()).count();
        if surface == 1 || (ids.is_some() && !colors.is_empty()) || (surface == 0 && !colors.is_empty()) {
            return Err(invalid(
                "bind both albedo and normal (and emissive_occlusion if wanted), or ids alone (a visibility buffer), or none (a depth-only pass)".into(),
            ));
        }
        let emissive_occlusion = bound_image(plan, pass, "emissive_occlusion").is_some();
        let motion = bound_image(plan, pass, "motion");
        if motion.is_some() && surface != 2 {
            return Err(invalid(MOTION_TARGETS.into()));
        }
        let object_id = bound_image(plan, pass, "object_id");
        if object_id.is_some() && surface != 2 {
            return Err(invalid(OBJECT_ID_TARGETS.into()));
        }
        if mode == GeometryMode::Equal && !crate::gpu::image::aspect_of(depth.0).contains(vk::ImageAspectFlags::STENCIL)
        {
            return Err(invalid(format!(
                "gbuffer_equal needs a depth format with stencil (one stencil bit per sample), not {:?}",
                depth.0
            )));
        }
        let normal = bound_image(plan, pass, "normal").map(|(f, _)| f);
        let packed_ids = ids.is_some_and(|(format, _)| format == crate::passes::slots::VISIBILITY_PACKED);
        let equal = mode == GeometryMode::Equal;
        let surface_colors: Vec<vk::Format> =
            ["albedo", "normal"].iter().filter_map(|s| bound_image(plan, pass, s).map(|(f, _)| f)).collect();
        let make = |extras: bool, masked: bool, textured: bool| -> crate::Result<LazyPipeline> {
            let no_masks: &[(&str, &str)] = if masked { &[] } else { &[("NO_ALPHA_MASK", "1")] };
            let (path, mut defines, formats): (&str, Vec<(&str, &str)>, &[vk::Format]) = match ids {
                Some((format, _)) => ("gbuffer/visibility.frag", visibility_defines(Some(format)).to_vec(), &[]),
                // Even without masks a depth-only pass keeps its (then empty) fragment shader: on
                // the H100 the multisampled depth-only draws ran 5 % slower without one.
                None if colors.is_empty() => ("gbuffer/depth_alpha.frag", Vec::new(), &[]),
                None if extras => ("gbuffer/gbuffer.frag", normal_defines(normal).to_vec(), &colors),
                None => ("gbuffer/gbuffer.frag", normal_defines(normal).to_vec(), &surface_colors),
            };
            let id_format = ids.map(|(f, _)| [f]);
            let mut formats = id_format.as_ref().map_or(formats, |f| f.as_slice()).to_vec();
            if extras {
                defines.push(("EMISSIVE_OCCLUSION", "1"));
            }
            defines.extend_from_slice(no_masks);
            if !textured {
                defines.push(("NO_TEXTURES", "1"));
            }
            // Motion vectors come after the targets this variant writes.
            let motion_location = formats.len().to_string();
            let mut vertex_defines: Vec<(&str, &str)> = Vec::new();
            if let Some((format, _)) = motion {
                formats.push(format);
                defines.extend([("MOTION", "1"), ("MOTION_LOCATION", motion_location.as_str())]);
                vertex_defines.push(("MOTION", "1"));
            }
            let object_id_location = formats.len().to_string();
            if let Some((format, _)) = object_id {
                formats.push(format);
                defines.extend([("OBJECT_ID", "1"), ("OBJECT_ID_LOCATION", object_id_location.as_str())]);
            }
            let fragment = Some((path, defines.as_slice()));
            // Shading reads normals; only a texture reads the surface stream, and without color
            // targets only a masked material's alpha texture does.
            let fetch = match colors.is_empty() {
                false => VertexFetch { normals: true, surface: textured },
                true => VertexFetch { normals: false, surface: textured && masked },
            };
            let compiled = GeometryShaders::compile(shaders, &vertex_defines, fetch, fragment, &formats, depth, equal)?;
            Ok(LazyPipeline::geometry(&pass.name, compiled))
        };
        let row = |extras: bool| -> crate::Result<[[Option<LazyPipeline>; 2]; 2]> {
            let masked = |masked: bool| -> crate::Result<[Option<LazyPipeline>; 2]> {
                Ok([Some(make(extras, masked, false)?), Some(make(extras, masked, true)?)])
            };
            Ok([masked(false)?, masked(true)?])
        };
        let none = || [[None, None], [None, None]];
        let pipelines =
            GeometryPipelines { variants: [row(false)?, if emissive_occlusion { row(true)? } else { none() }] };
        Ok(Self {
            name: pass.name.clone(),
            pipelines,
            mode,
            // gbuffer_append loads its targets and declares no clear_colors.
            clear_colors: mode != GeometryMode::Append && pass.flag("clear_colors")?,
            packed_ids,
            motion: motion.is_some(),
            object_id: object_id.is_some(),
        })
    }
}

/// The format of object ids (`Renderer::pick`).
pub const OBJECT_ID_FORMAT: vk::Format = vk::Format::R32_UINT;

/// What the `object_id` slot holds.
const OBJECT_ID_SLOT_DOC: &str =
    "each pixel's instance id plus one, 0 for the background (R32_UINT, one sample; cleared by gbuffer, kept by gbuffer_append), read by Renderer::pick";

/// Why a geometry pass refuses its `object_id` binding.
const OBJECT_ID_TARGETS: &str =
    "object ids are written beside albedo and normal: bind both with object_id (not ids, nor a depth-only pass)";

/// Why a geometry pass refuses its `motion` binding: motion vectors are written beside a
/// G-buffer's surface.
const MOTION_TARGETS: &str =
    "motion vectors are written beside albedo and normal: bind both with motion (not ids, nor a depth-only pass)";

impl PassNode for GbufferPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn reads_previous_instances(&self) -> bool {
        self.motion
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let slots = &rec.slots;
        let depth = slots.required_image("depth")?;
        let color_load = match (self.mode, self.clear_colors) {
            (GeometryMode::Append, _) => vk::AttachmentLoadOp::LOAD,
            (_, true) => vk::AttachmentLoadOp::CLEAR,
            (_, false) => vk::AttachmentLoadOp::DONT_CARE,
        };
        let depth_load =
            if self.mode == GeometryMode::Clear { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD };
        let inputs = SceneInputs::of(rec)?;
        let scene = &inputs.scene;
        let extras = self.pipelines.writes_extras(scene.emission_or_occlusion);
        // Masked materials draw from regions of their own, after the opaque ones, with the
        // pipeline that alpha-tests: the opaque draws keep the depth test ahead of the shader.
        let masked = scene.alpha_masks && scene.regions.any(&FaceCull::MASKED);
        let (opaque, alpha_tested) =
            self.pipelines.pick(rec.ctx, scene.emission_or_occlusion, masked, scene.textured)?;
        let mut draws: Vec<RegionDraw> = vec![(opaque, &FaceCull::OPAQUE)];
        draws.extend(alpha_tested.map(|p| (p, &FaceCull::MASKED[..])));
        // Motion vectors and object ids are cleared to 0 by the first pass whatever
        // `clear_colors` says: the background has no fragment to write its 0.
        let motion_load = match self.mode {
            GeometryMode::Append => vk::AttachmentLoadOp::LOAD,
            _ => vk::AttachmentLoadOp::CLEAR,
        };
        let colors: Vec<vk::RenderingAttachmentInfo> = GBUFFER_COLOR_SLOTS
            .iter()
            .chain(&["ids", "motion", "object_id"])
            .filter(|&&s| extras || s != "emissive_occlusion")
            .filter(|&&s| self.motion || s != "motion")
            .filter(|&&s| self.object_id || s != "object_id")
            .filter_map(|s| slots.image(s).map(|image| (*s, image)))
            .map(|(s, image)| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(image.view())
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(if s == "motion" || s == "object_id" { motion_load } else { color_load })
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } })
            })
            .collect();
        let triangle_bits = if self.packed_ids { Some(packed_id_bits(&self.name, scene)?.to_ne_bytes()) } else { None };
        let push: &[u8] = triangle_bits.as_ref().map_or(&[], |b| b.as_slice());
        let lists = match self.mode {
            GeometryMode::Equal => DrawSource::redraw_lists(slots, scene)?,
            _ => {
                let mut list = DrawSource::bound(slots, LIST_SLOTS)?.unwrap_or_else(|| DrawSource::unculled(scene));
                if let (Some(commands), Some(count)) = (slots.buffer("cluster_commands"), slots.buffer("cluster_count"))
                {
                    list.clusters = Some((commands, count));
                }
                let [commands, count] = crate::passes::cluster_cull::MASKED_LIST_SLOTS.map(|s| slots.buffer(s));
                list.masked_clusters = commands.zip(count);
                vec![list]
            }
        };
        let mut previous = scene.previous_instance_binds(8).to_vec();
        previous.push(Bind::Buffer(9, scene.prev_positions.handle()));
        let extra: &[Bind] = if self.motion { &previous } else { &[] };
        record_geometry(
            rec.ctx,
            rec.cmd,
            &draws,
            scene,
            &lists,
            inputs.constants(),
            &colors,
            depth,
            depth_load,
            extra,
            push,
        );
        Ok(())
    }
}

/// The `gbuffer`, `gbuffer_append` and `gbuffer_equal` pass kinds: one geometry pass drawing in
/// each [`GeometryMode`].
pub struct GbufferKind(pub GeometryMode);

impl PassKind for GbufferKind {
    fn info(&self) -> PassKindInfo {
        match self.0 {
            GeometryMode::Clear => PassKindInfo {
                name: "gbuffer",
                doc: "draws a draw list with vkCmdDrawIndexedIndirectCount into albedo, normal and reversed-Z depth (any sample count), or into depth alone when no color target is bound (an MSAA Z-prepass)",
                reads: [draw_list_slots(false), crate::passes::cluster_cull::cluster_list_slots().to_vec()].concat(),
                writes: vec![
                    ms(slot("albedo", Usage::ColorAttachment, false, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a (omit albedo and normal for a depth-only pass)")),
                    ms(slot("normal", Usage::ColorAttachment, false, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
                    ms(slot("emissive_occlusion", Usage::ColorAttachment, false, FormatRule::Exact(GBUFFER_EMISSIVE_OCCLUSION_FORMAT), EMISSIVE_OCCLUSION_SLOT_DOC)),
                    ms(slot("ids", Usage::ColorAttachment, false, FormatRule::OneOf(VISIBILITY_FORMATS), "visibility buffer: instance id and triangle id, packed in R32_UINT or as R32G32_UINT (instead of albedo and normal)")),
                    ms(slot("depth", Usage::DepthAttachment, true, FormatRule::Depth, "reversed-Z depth (cleared to 0, stencil to 0)")),
                    ms(slot("motion", Usage::ColorAttachment, false, FormatRule::Exact(MOTION_FORMAT), MOTION_SLOT_DOC)),
                    slot("object_id", Usage::ColorAttachment, false, FormatRule::Exact(OBJECT_ID_FORMAT), OBJECT_ID_SLOT_DOC),
                ],
                settings: vec![clear_colors_setting()],
                slots_from_shader: false,
            },
            GeometryMode::Append => PassKindInfo {
                name: "gbuffer_append",
                doc: "like gbuffer, but draws on top of the existing targets (the late phase of two-phase culling)",
                reads: [draw_list_slots(true), crate::passes::cluster_cull::cluster_list_slots().to_vec()].concat(),
                writes: vec![
                    ms(slot("albedo", Usage::ColorAttachmentLoad, false, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a (omit albedo and normal for a depth-only pass)")),
                    ms(slot("normal", Usage::ColorAttachmentLoad, false, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
                    ms(slot("emissive_occlusion", Usage::ColorAttachmentLoad, false, FormatRule::Exact(GBUFFER_EMISSIVE_OCCLUSION_FORMAT), EMISSIVE_OCCLUSION_SLOT_DOC)),
                    ms(slot("ids", Usage::ColorAttachmentLoad, false, FormatRule::OneOf(VISIBILITY_FORMATS), "visibility buffer: instance id and triangle id (packed R32_UINT or R32G32_UINT)")),
                    ms(slot("depth", Usage::DepthAttachmentLoad, true, FormatRule::Depth, "reversed-Z depth")),
                    ms(slot("motion", Usage::ColorAttachmentLoad, false, FormatRule::Exact(MOTION_FORMAT), MOTION_SLOT_DOC)),
                    slot("object_id", Usage::ColorAttachmentLoad, false, FormatRule::Exact(OBJECT_ID_FORMAT), OBJECT_ID_SLOT_DOC),
                ],
                settings: vec![],
                slots_from_shader: false,
            },
            GeometryMode::Equal => PassKindInfo {
                name: "gbuffer_equal",
                doc: "the MSAA Z-prepass baseline: redraws the lists with depth EQUAL against finished depth, one stencil bit per sample (each sample written once), into albedo and normal",
                reads: redraw_list_slots(),
                writes: vec![
                    ms(slot("albedo", Usage::ColorAttachment, true, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a")),
                    ms(slot("normal", Usage::ColorAttachment, true, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
                    ms(slot("emissive_occlusion", Usage::ColorAttachment, false, FormatRule::Exact(GBUFFER_EMISSIVE_OCCLUSION_FORMAT), EMISSIVE_OCCLUSION_SLOT_DOC)),
                    ms(slot("depth", Usage::DepthAttachmentLoad, true, FormatRule::DepthStencil, "the finished depth, with stencil (its stencil is written)")),
                ],
                settings: vec![clear_colors_setting()],
                slots_from_shader: false,
            },
        }
    }

    fn draw_list(&self) -> Option<DrawList> {
        Some(DrawList {
            slots: LIST_SLOTS,
            order: DrawOrder::Regions,
            cluster_slots: &[["cluster_commands", "cluster_count"], crate::passes::cluster_cull::MASKED_LIST_SLOTS],
        })
    }

    fn validate(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let masked = crate::passes::cluster_cull::masked_pair_error(check, check.pass.name.as_str());
        targets_error(check).into_iter().chain(masked).collect()
    }

    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        packed_ids_error(check).into_iter().collect()
    }

    fn quantities(&self) -> Vec<Quantity> {
        vec![MESH_TRIANGLES]
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(GbufferPass::for_plan(s.shaders, s.pass, s.plan, self.0)?))
    }
}

/// The quantity `mesh_triangles`: the triangles of the scene's largest mesh, which decide how
/// many bits packed visibility ids give the triangle.
pub const MESH_TRIANGLES: Quantity = Quantity {
    name: "mesh_triangles",
    doc: "triangles of the scene's largest mesh",
    count: |s| {
        let c = crate::passes::shared::SceneCounts::downcast(s)?;
        Some(c.scene.meshes.iter().map(|m| m.index_count as u64 / 3).max().unwrap_or(0))
    },
    growth: Growth::Exact,
};

/// Which targets a geometry pass binds must make one of its three forms: albedo and normal
/// (emissive_occlusion optional), ids alone (a visibility buffer), or none (depth only).
fn targets_error(check: &KindCheck<'_>) -> Option<(Pos, String)> {
    let bound = |slot: &str| check.binding(slot);
    let surface = ["albedo", "normal"].iter().filter(|s| bound(s).is_some()).count();
    let colors = GBUFFER_COLOR_SLOTS.iter().filter(|s| bound(s).is_some()).count();
    let ids = bound("ids");
    if surface == 1 || (ids.is_some() && colors > 0) || (surface == 0 && colors > 0) {
        let at = GBUFFER_COLOR_SLOTS.iter().chain(&["ids"]).find_map(|s| bound(s)).map_or(check.pass.pos, |b| b.pos);
        let message = format!(
            "pass '{}': bind both albedo and normal (and emissive_occlusion if wanted), or ids alone (a \
             visibility buffer), or none (a depth-only pass)",
            check.pass.name
        );
        return Some((at, message));
    }
    if let Some(motion) = bound("motion").filter(|_| surface != 2) {
        return Some((motion.pos, format!("pass '{}': {MOTION_TARGETS}", check.pass.name)));
    }
    if let Some(object_id) = bound("object_id").filter(|_| surface != 2) {
        return Some((object_id.pos, format!("pass '{}': {OBJECT_ID_TARGETS}", check.pass.name)));
    }
    None
}

/// Packed visibility ids (R32_UINT) must hold the scene's instance and triangle ids.
fn packed_ids_error(check: &KindCheck<'_>) -> Option<(Pos, String)> {
    let ids = check.binding("ids")?;
    let ResourceDesc::Image { format, .. } = check.graph.resources[ids.resource].desc else { return None };
    let quantities = check.quantities?;
    if format != crate::passes::slots::VISIBILITY_PACKED {
        return None;
    }
    let instances = quantities.get("instances")?.min(u32::MAX as u64) as u32;
    let triangles = quantities.get(MESH_TRIANGLES.name)?.min(u32::MAX as u64) as u32;
    let why = super::visibility_ids::triangle_bits(instances, triangles).err()?;
    Some((ids.pos, format!("pass '{}': {why}", check.pass.name)))
}
