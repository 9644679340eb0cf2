//! Slot and setting declarations that several built-in pass kinds share: the G-buffer's formats,
//! draw lists, counters and the lighting settings.

use crate::graph::{FormatRule, SettingDecl, SlotDecl, Stages, Usage};
use ash::vk;

/// The G-buffer geometry pass's albedo/metallic format.
pub const GBUFFER_ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The G-buffer's packed normal/roughness format: octahedral normal in 12 + 12 bits, roughness
/// in 8 (`shaders/common/gbuffer_normal.glsl`). The built-in graphs use it where they have no
/// multisampling.
pub const GBUFFER_NORMAL_PACKED: vk::Format = vk::Format::R32_UINT;
/// The G-buffer normal/roughness formats the geometry and lighting passes accept: the packed
/// word, or normal xyz + roughness as four halves (the thesis's per-sample MSAA baseline layout).
pub const GBUFFER_NORMAL_FORMATS: &[vk::Format] = &[GBUFFER_NORMAL_PACKED, vk::Format::R16G16B16A16_SFLOAT];
/// The G-buffer's emissive/occlusion format: emissive rgb (sRGB-encoded by the format), ambient
/// occlusion a (`shaders/common/emissive_occlusion.glsl`).
pub const GBUFFER_EMISSIVE_OCCLUSION_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;
/// What the G-buffer's `emissive_occlusion` slots hold.
pub(crate) const EMISSIVE_OCCLUSION_SLOT_DOC: &str =
    "emissive rgb and ambient occlusion a (optional: without it, surfaces emit nothing and are not occluded)";
/// What the G-buffer's `normal` slots hold, in either format.
pub(crate) const NORMAL_SLOT_DOC: &str = "normal and roughness (packed R32_UINT, or R16G16B16A16_SFLOAT)";
/// The geometry passes' motion-vector format: per pixel, in pixels, from this frame's position to
/// last frame's, x right, y down (`shaders/gbuffer/motion.glsl`); 0 where no geometry was drawn.
pub const MOTION_FORMAT: vk::Format = vk::Format::R16G16_SFLOAT;
/// What the geometry passes' `motion` slots hold.
pub(crate) const MOTION_SLOT_DOC: &str = "motion vectors (R16G16_SFLOAT, optional): pixels from this frame's position to last frame's, x right, y down, unjittered; 0 where nothing is drawn (with albedo and normal)";
/// The visibility buffer's packed format: instance id and triangle id in one 32-bit word, the
/// triangle in the low bits (as many as the scene's largest mesh needs; `passes::visibility_ids`).
pub const VISIBILITY_PACKED: vk::Format = vk::Format::R32_UINT;
/// The visibility buffer's formats: the packed word, or instance id and triangle id as two words
/// (any scene).
pub const VISIBILITY_FORMATS: &[vk::Format] = &[VISIBILITY_PACKED, vk::Format::R32G32_UINT];
/// Format of the selective-AA mask (`aa_edges`): 1 where a pixel may keep several surfaces.
pub const AA_MASK_FORMAT: vk::Format = vk::Format::R8_UINT;
/// Format of the Hi-Z pyramid (reversed-Z depth, minimum reduction).
pub const HIZ_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
/// The lighting passes' output format: linear HDR colour, scene radiance before exposure and
/// tone mapping (the `tonemap` pass maps it to [`LIT_OUTPUT_FORMAT`]).
pub const HDR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// The `depth_resolve` pass's output format: one reversed-Z depth per pixel.
pub const RESOLVED_DEPTH_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
/// The tone-mapped image's format (sRGB-encoded values in a UNORM image, so it can be storage):
/// the `tonemap` pass's output, which the transparent, FXAA and overlay passes read or write.
pub const LIT_OUTPUT_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// What a lighting pass writes: linear HDR colour for a tonemap pass, or the tone-mapped image
/// itself (the pass then applies the curve in place, as graphs without a tonemap pass expect).
pub(crate) const LIGHTING_OUTPUT_FORMATS: &[vk::Format] = &[HDR_FORMAT, LIT_OUTPUT_FORMAT];
/// What a lighting pass's `output` slot holds, in either format.
pub(crate) const LIGHTING_OUTPUT_DOC: &str =
    "linear HDR colour (R16G16B16A16_SFLOAT: scene radiance before exposure, for a tonemap pass), or the tone-mapped, sRGB-encoded image (R8G8B8A8_UNORM)";

/// The lighting shaders' defines for the format bound to their `output` (`HDR_OUTPUT` for
/// [`HDR_FORMAT`]).
pub(crate) fn lighting_output_defines(
    plan: &crate::graph::plan::CompiledGraph,
    pass: &crate::graph::plan::PlannedPass,
) -> &'static [(&'static str, &'static str)] {
    match crate::passes::gbuffer::bound_image(plan, pass, "output") {
        Some((HDR_FORMAT, _)) => &[("HDR_OUTPUT", "1")],
        _ => &[],
    }
}

pub(crate) const fn slot(
    name: &'static str,
    usage: Usage,
    required: bool,
    format: FormatRule,
    doc: &'static str,
) -> SlotDecl {
    let s = SlotDecl::new(name, usage, doc).format(format);
    if required {
        s.required()
    } else {
        s
    }
}

/// What a draw list's buffers hold ([`SlotDecl::content`]): only a kind that writes them so may
/// feed a draw.
pub(crate) const DRAW_COMMANDS: &str = "draw commands";
/// A draw list's counts.
pub(crate) const DRAW_COUNTS: &str = "draw counts";
/// A draw list's instance ids.
pub(crate) const INSTANCE_IDS: &str = "instance ids";

/// A draw command per draw group (`VkDrawIndexedIndirectCommand`, 20 bytes).
pub(crate) const COMMANDS_BYTES: &str = "meshes * 20";
/// A draw count per region: back, front and none for opaque and for masked materials, then
/// transparent ([`crate::passes::shared::face_cull::FaceCull`]).
pub(crate) const COUNT_BYTES: &str = "28";
/// An instance id per instance.
pub(crate) const IDS_BYTES: &str = "instances * 4";
/// A bit per instance, in 32-bit words.
pub(crate) const INSTANCE_BITS: &str = "ceil_div(instances, 32) * 4";
/// A pass's counters (a cull pass's, the compressed G-buffer's): a fixed record the host reads
/// whole.
pub(crate) const COUNTERS_BYTES: &str = "64";

const _: () = {
    assert!(std::mem::size_of::<crate::passes::shared::gpu_types::DrawIndexedIndirect>() == 20);
    assert!(crate::passes::shared::face_cull::DRAW_COUNT_BYTES == 28);
};

pub(crate) const fn ms(s: SlotDecl) -> SlotDecl {
    s.multisample()
}

/// The three slots of one draw list: `names` and `docs` for its commands, count and instance
/// ids (`required`: the graph must bind them).
pub(crate) fn list_slots(names: [&'static str; 3], docs: [&'static str; 3], required: bool) -> [SlotDecl; 3] {
    [
        slot(names[0], Usage::Indirect, required, FormatRule::Any, docs[0])
            .at_least(COMMANDS_BYTES)
            .content(DRAW_COMMANDS),
        slot(names[1], Usage::Indirect, required, FormatRule::Any, docs[1]).at_least(COUNT_BYTES).content(DRAW_COUNTS),
        slot(names[2], Usage::StorageBufferRead(Stages::Vertex), required, FormatRule::Any, docs[2])
            .at_least(IDS_BYTES)
            .content(INSTANCE_IDS),
    ]
}

/// The draw list a geometry pass draws (`required`: the graph must bind it; otherwise an
/// unbound list means every instance).
pub(crate) fn draw_list_slots(required: bool) -> Vec<SlotDecl> {
    list_slots(
        ["draw_commands", "draw_count", "draw_instance_ids"],
        ["VkDrawIndexedIndirectCommand per draw group", "number of commands", "instance ids, one slice per draw group"],
        required,
    )
    .to_vec()
}

/// The lists a redraw pass draws: the first (default: every instance) and an optional `late_` one.
pub(crate) fn redraw_list_slots() -> Vec<SlotDecl> {
    let mut slots = draw_list_slots(false);
    slots.extend(list_slots(
        ["late_draw_commands", "late_draw_count", "late_draw_instance_ids"],
        ["a second list's commands (two-phase culling's late draw)", "its count", "its instance ids"],
        false,
    ));
    slots
}

pub(crate) fn lighting_settings() -> Vec<SettingDecl> {
    vec![
        SettingDecl::real("exposure", 0.8, (0.0, 1.0e6), "the exposure the tonemap pass applies: edge pixels of multisampled G-buffers are resolved in tone-mapped space with it"),
        SettingDecl::choice::<DebugView>(
            "debug_view",
            "show a G-buffer channel instead of the lit image (samples: distinct surfaces per pixel as a heatmap)",
        ),
        SettingDecl::flag(
            "light_tiles",
            true,
            "cull point lights per 16x16 tile (false: every light for every pixel, the thesis's loop)",
        ),
    ]
}

crate::choice! {
    /// What the lighting passes show (setting `debug_view`).
    pub enum DebugView {
        /// The lit image.
        None = "none",
        /// Normals.
        Normals = "normals",
        /// Albedo.
        Albedo = "albedo",
        /// Depth.
        Depth = "depth",
        /// Distinct surfaces per pixel, as a heatmap.
        Samples = "samples",
        /// The lit image tinted by the sun shadow cascade that shades each pixel (red, green,
        /// blue, yellow from the nearest; untinted beyond the last).
        Cascades = "cascades",
    }
}

pub(crate) fn clear_colors_setting() -> SettingDecl {
    SettingDecl::flag(
        "clear_colors",
        false,
        "clear the color targets first; off, texels no fragment wrote keep whatever they held (every built-in reader masks them by depth = 0), which saves a full-screen write",
    )
}
