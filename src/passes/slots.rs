//! Slot and setting declarations that several built-in pass kinds share: the G-buffer's formats,
//! draw lists, counters and the lighting settings.

use crate::graph::{FormatRule, MinBytes, SettingDecl, SettingDefault, SlotDecl, Stages, Usage};
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
/// The lighting pass's output format (sRGB-encoded values in a UNORM image, so it can be storage).
pub const LIT_OUTPUT_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

pub(crate) const fn slot(
    name: &'static str,
    usage: Usage,
    required: bool,
    format: FormatRule,
    doc: &'static str,
) -> SlotDecl {
    SlotDecl { name, usage, required, format, multisample_ok: false, doc, min_bytes: MinBytes::Any }
}

/// `s`, taking buffers of at least `min` bytes.
pub(crate) const fn sized(s: SlotDecl, min: MinBytes) -> SlotDecl {
    SlotDecl { min_bytes: min, ..s }
}

/// A draw command per draw group (`VkDrawIndexedIndirectCommand`).
pub(crate) const COMMANDS_BYTES: MinBytes =
    MinBytes::PerMesh(std::mem::size_of::<crate::passes::shared::gpu_types::DrawIndexedIndirect>() as u64);
/// A draw count per face-cull region: back, front, none (graphs before face culling declared 4).
pub(crate) const COUNT_BYTES: MinBytes = MinBytes::Fixed(crate::passes::shared::face_cull::DRAW_COUNT_BYTES);
/// An instance id per instance.
pub(crate) const IDS_BYTES: MinBytes = MinBytes::PerInstance(4);
/// A cull pass's counters (`CullCounters`), and the compressed G-buffer's: a fixed record the
/// host reads whole.
pub(crate) const COUNTERS_BYTES: MinBytes = MinBytes::Exact(crate::graph::STATS_BYTES as u64);

pub(crate) const fn ms(s: SlotDecl) -> SlotDecl {
    SlotDecl { multisample_ok: true, ..s }
}

/// The three slots of one draw list: `names` and `docs` for its commands, count and instance
/// ids (`required`: the graph must bind them).
pub(crate) fn list_slots(names: [&'static str; 3], docs: [&'static str; 3], required: bool) -> [SlotDecl; 3] {
    [
        sized(slot(names[0], Usage::Indirect, required, FormatRule::Any, docs[0]), COMMANDS_BYTES),
        sized(slot(names[1], Usage::Indirect, required, FormatRule::Any, docs[1]), COUNT_BYTES),
        sized(slot(names[2], Usage::StorageBufferRead(Stages::Vertex), required, FormatRule::Any, docs[2]), IDS_BYTES),
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
        SettingDecl {
            name: "exposure",
            default: SettingDefault::Float(0.8),
            range: Some((0.0, 1.0e6)),
            doc: "scale applied before tone mapping",
        },
        SettingDecl {
            name: "debug_view",
            default: SettingDefault::Choice(&["none", "normals", "albedo", "depth", "samples"]),
            range: None,
            doc: "show a G-buffer channel instead of the lit image (samples: distinct surfaces per pixel as a heatmap)",
        },
        SettingDecl {
            name: "light_tiles",
            default: SettingDefault::Bool(true),
            range: None,
            doc: "cull point lights per 16x16 tile (false: every light for every pixel, the thesis's loop)",
        },
    ]
}

pub(crate) fn clear_colors_setting() -> SettingDecl {
    SettingDecl {
        name: "clear_colors",
        default: SettingDefault::Bool(false),
        range: None, doc: "clear the color targets first; off, texels no fragment wrote keep whatever they held (every built-in reader masks them by depth = 0), which saves a full-screen write",
    }
}
