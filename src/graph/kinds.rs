//! Pass kinds: what each built-in pass reads and writes (its slots) and which settings it takes.
//!
//! This is data only, shared by validation (names, usages, formats), the compiler (accesses and
//! barriers) and the executor (which instantiates a pass for each kind).

use super::usage::{Stages, Usage};
use ash::vk;

/// Which formats a slot accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatRule {
    /// Any format the usage supports on the device.
    Any,
    /// Any depth format.
    Depth,
    /// Any color (non-depth) format.
    Color,
    /// Exactly this format (the pass's shaders are written for it).
    Exact(vk::Format),
    /// One of these formats (the pass compiles its shaders for the one bound).
    OneOf(&'static [vk::Format]),
}

/// One named input or output of a pass kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotDecl {
    /// Slot name used in the RON `reads`/`writes` maps.
    pub name: &'static str,
    /// How the pass uses what is bound there.
    pub usage: Usage,
    /// Whether the graph must bind it.
    pub required: bool,
    /// Accepted formats (images only).
    pub format: FormatRule,
    /// Whether a multisampled image is accepted (attachments must match the pass's other attachments).
    pub multisample_ok: bool,
    /// What the slot is for, for `graph/README.md`-style listings and errors.
    pub doc: &'static str,
    /// The least a buffer bound here must hold; checked when the graph is compiled for a scene.
    pub min_bytes: MinBytes,
}

/// The least a buffer slot takes, in terms of the scene a graph is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MinBytes {
    /// No minimum (or an image slot).
    Any,
    /// This many bytes.
    Fixed(u64),
    /// This many bytes per instance (`instances * n`).
    PerInstance(u64),
    /// This many bytes per draw group (`meshes * n`).
    PerMesh(u64),
    /// A bit per instance, in 32-bit words (`ceil(instances / 32) * 4`).
    InstanceBits,
}

impl MinBytes {
    /// The bytes it asks for with `instances` instances and `meshes` draw groups.
    pub fn bytes(self, instances: u64, meshes: u64) -> u64 {
        match self {
            MinBytes::Any => 0,
            MinBytes::Fixed(n) => n,
            MinBytes::PerInstance(n) => instances * n,
            MinBytes::PerMesh(n) => meshes * n,
            MinBytes::InstanceBits => instances.div_ceil(32) * 4,
        }
    }

    /// The rule as a size expression of the graph files.
    pub fn rule(self) -> String {
        match self {
            MinBytes::Any => "any size".into(),
            MinBytes::Fixed(n) => n.to_string(),
            MinBytes::PerInstance(n) => format!("instances * {n}"),
            MinBytes::PerMesh(n) => format!("meshes * {n}"),
            MinBytes::InstanceBits => "ceil_div(instances, 32) * 4".into(),
        }
    }
}

/// The type and default of a pass setting.
#[derive(Clone, Debug, PartialEq)]
pub enum SettingDefault {
    /// A boolean.
    Bool(bool),
    /// A whole number.
    Int(i64),
    /// A real number.
    Float(f64),
    /// One of a fixed set of words; the first is the default.
    Choice(&'static [&'static str]),
}

/// One setting a pass kind takes (`settings: {"exposure": 0.8}` in RON).
#[derive(Clone, Debug, PartialEq)]
pub struct SettingDecl {
    /// Name in RON.
    pub name: &'static str,
    /// Type and default.
    pub default: SettingDefault,
    /// What it does.
    pub doc: &'static str,
}

/// Everything the graph needs to know about a pass kind.
#[derive(Clone, Debug, PartialEq)]
pub struct PassKindInfo {
    /// Name used as `kind: "..."` in RON.
    pub name: &'static str,
    /// One-line description.
    pub doc: &'static str,
    /// Slots whose bound resources the pass reads (and does not write).
    pub reads: Vec<SlotDecl>,
    /// Slots whose bound resources the pass writes (possibly also reading them, see the usage).
    pub writes: Vec<SlotDecl>,
    /// Settings.
    pub settings: Vec<SettingDecl>,
    /// Whether the kind's slots come from its shader (`compute`) instead of the lists above.
    pub slots_from_shader: bool,
}

impl PassKindInfo {
    /// The slot named `name` among reads and writes.
    pub fn slot(&self, name: &str) -> Option<&SlotDecl> {
        self.reads.iter().chain(&self.writes).find(|s| s.name == name)
    }
}

/// Name of the generic compute kind, whose slots are the bindings of its shader.
pub const COMPUTE_KIND: &str = "compute";

/// The G-buffer geometry pass's albedo/metallic format.
pub const GBUFFER_ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
/// The G-buffer's packed normal/roughness format: octahedral normal in 12 + 12 bits, roughness
/// in 8 (`shaders/common/gbuffer_normal.glsl`). The built-in graphs use it where they have no
/// multisampling.
pub const GBUFFER_NORMAL_PACKED: vk::Format = vk::Format::R32_UINT;
/// The G-buffer normal/roughness formats the geometry and lighting passes accept: the packed
/// word, or normal xyz + roughness as four halves (the thesis's per-sample MSAA baseline layout).
pub const GBUFFER_NORMAL_FORMATS: &[vk::Format] = &[GBUFFER_NORMAL_PACKED, vk::Format::R16G16B16A16_SFLOAT];
/// What the G-buffer's `normal` slots hold, in either format.
const NORMAL_SLOT_DOC: &str = "normal and roughness (packed R32_UINT, or R16G16B16A16_SFLOAT)";
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
/// FXAA's search schedules (`FXAA_QUALITY__PRESET`), the `fxaa` kind's `preset` words; the first
/// is the default (39, "extreme quality": twelve taps per direction, the first five one pixel
/// apart).
pub const FXAA_PRESETS: &[&str] = &["39", "29", "23", "15", "12", "10"];

const fn slot(name: &'static str, usage: Usage, required: bool, format: FormatRule, doc: &'static str) -> SlotDecl {
    SlotDecl { name, usage, required, format, multisample_ok: false, doc, min_bytes: MinBytes::Any }
}

/// `s`, taking buffers of at least `min` bytes.
const fn sized(s: SlotDecl, min: MinBytes) -> SlotDecl {
    SlotDecl { min_bytes: min, ..s }
}

/// A draw command per draw group (`VkDrawIndexedIndirectCommand`).
const COMMANDS_BYTES: MinBytes =
    MinBytes::PerMesh(std::mem::size_of::<crate::render::gpu_types::DrawIndexedIndirect>() as u64);
/// A draw count per face-cull region: back, front, none (graphs before face culling declared 4).
const COUNT_BYTES: MinBytes = MinBytes::Fixed(crate::render::face_cull::DRAW_COUNT_BYTES);
/// An instance id per instance.
const IDS_BYTES: MinBytes = MinBytes::PerInstance(4);
/// A cull pass's counters (`CullCounters`), and the compressed G-buffer's.
const STATS_BYTES: MinBytes = MinBytes::Fixed(crate::graph::executor::STATS_BYTES as u64);

const fn ms(s: SlotDecl) -> SlotDecl {
    SlotDecl { multisample_ok: true, ..s }
}

/// The three slots of one draw list: `names` and `docs` for its commands, count and instance
/// ids (`required`: the graph must bind them).
fn list_slots(names: [&'static str; 3], docs: [&'static str; 3], required: bool) -> [SlotDecl; 3] {
    [
        sized(slot(names[0], Usage::Indirect, required, FormatRule::Any, docs[0]), COMMANDS_BYTES),
        sized(slot(names[1], Usage::Indirect, required, FormatRule::Any, docs[1]), COUNT_BYTES),
        sized(slot(names[2], Usage::StorageBufferRead(Stages::Vertex), required, FormatRule::Any, docs[2]), IDS_BYTES),
    ]
}

/// The draw list a geometry pass draws (`required`: the graph must bind it; otherwise an
/// unbound list means every instance).
fn draw_list_slots(required: bool) -> Vec<SlotDecl> {
    list_slots(
        ["draw_commands", "draw_count", "draw_instance_ids"],
        ["VkDrawIndexedIndirectCommand per draw group", "number of commands", "instance ids, one slice per draw group"],
        required,
    )
    .to_vec()
}

/// The lists a redraw pass draws: the first (default: every instance) and an optional `late_` one.
fn redraw_list_slots() -> Vec<SlotDecl> {
    let mut slots = draw_list_slots(false);
    slots.extend(list_slots(
        ["late_draw_commands", "late_draw_count", "late_draw_instance_ids"],
        ["a second list's commands (two-phase culling's late draw)", "its count", "its instance ids"],
        false,
    ));
    slots
}

fn lighting_settings() -> Vec<SettingDecl> {
    vec![
        SettingDecl { name: "exposure", default: SettingDefault::Float(0.8), doc: "scale applied before tone mapping" },
        SettingDecl {
            name: "debug_view",
            default: SettingDefault::Choice(&["none", "normals", "albedo", "depth", "samples"]),
            doc: "show a G-buffer channel instead of the lit image (samples: distinct surfaces per pixel as a heatmap)",
        },
        SettingDecl {
            name: "light_tiles",
            default: SettingDefault::Bool(true),
            doc: "cull point lights per 16x16 tile (false: every light for every pixel, the thesis's loop)",
        },
    ]
}

fn clear_colors_setting() -> SettingDecl {
    SettingDecl {
        name: "clear_colors",
        default: SettingDefault::Bool(false),
        doc: "clear the color targets first; off, texels no fragment wrote keep whatever they held (every built-in reader masks them by depth = 0), which saves a full-screen write",
    }
}

/// The built-in pass kinds.
pub fn builtin_kinds() -> Vec<PassKindInfo> {
    vec![
        PassKindInfo {
            name: "gbuffer",
            doc: "draws a draw list with vkCmdDrawIndexedIndirectCount into albedo, normal and reversed-Z depth (any sample count), or into depth alone when no color target is bound (an MSAA Z-prepass)",
            reads: draw_list_slots(false),
            writes: vec![
                ms(slot("albedo", Usage::ColorAttachment, false, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a (omit albedo and normal for a depth-only pass)")),
                ms(slot("normal", Usage::ColorAttachment, false, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
                ms(slot("ids", Usage::ColorAttachment, false, FormatRule::OneOf(VISIBILITY_FORMATS), "visibility buffer: instance id and triangle id, packed in R32_UINT or as R32G32_UINT (instead of albedo and normal)")),
                ms(slot("depth", Usage::DepthAttachment, true, FormatRule::Depth, "reversed-Z depth (cleared to 0, stencil to 0)")),
            ],
            settings: vec![clear_colors_setting()],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "gbuffer_equal",
            doc: "the MSAA Z-prepass baseline: redraws the lists with depth EQUAL against finished depth, one stencil bit per sample (each sample written once), into albedo and normal",
            reads: redraw_list_slots(),
            writes: vec![
                ms(slot("albedo", Usage::ColorAttachment, true, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a")),
                ms(slot("normal", Usage::ColorAttachment, true, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
                ms(slot("depth", Usage::DepthAttachmentLoad, true, FormatRule::Depth, "the finished depth, with stencil (its stencil is written)")),
            ],
            settings: vec![clear_colors_setting()],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "gbuffer_compressed",
            doc: "the compressed G-buffer geometry pass: redraws the lists with depth EQUAL, stencil first-fragment-wins (or, without stencil, atomic sample claims) and post-depth coverage, writing one 14-byte block per pixel plus pooled blocks for the other distinct surfaces of edge pixels, in per-pixel linked lists",
            reads: {
                let mut reads = redraw_list_slots();
                reads.push(slot("aa_mask", Usage::Sampled(Stages::Fragment), false, FormatRule::Exact(AA_MASK_FORMAT), "selective AA: only pixels whose mask is not 0 keep more than one block (an aa_edges pass makes it)"));
                reads
            },
            writes: vec![
                ms(slot("depth", Usage::DepthAttachmentLoad, true, FormatRule::Depth, "the finished MSAA depth: with stencil (its stencil is written), or without stencil and a sample_claim buffer")),
                slot("gbuffer", Usage::StorageBufferWrite(Stages::ComputeFragment), true, FormatRule::Any, "header, width x height head blocks, then the pool (size: compressed_gbuffer_bytes(pool_blocks))"),
                slot("sample_claim", Usage::StorageBufferWrite(Stages::ComputeFragment), false, FormatRule::Any, "with a depth format without stencil: the samples already claimed, one byte per pixel (size: ceil_div(width * height, 4) * 4; at most 8 samples)"),
            ],
            settings: vec![
                SettingDecl { name: "aa_region", default: SettingDefault::Choice(&["all", "ellipse", "rectangle"]), doc: "selective AA: only pixels inside this screen region (centered, aa_region_size of the screen) keep more than one block" },
                SettingDecl { name: "aa_region_size", default: SettingDefault::Float(0.6), doc: "size of the AA region as a fraction of the screen's width and height" },
                SettingDecl { name: "aa_max_depth_distance", default: SettingDefault::Float(0.0), doc: "selective AA: pixels farther than this distance keep one block (0: no limit)" },
                SettingDecl { name: "aa_object_flags", default: SettingDefault::Bool(false), doc: "selective AA: instances flagged no-AA keep one block" },
                SettingDecl { name: "claim_order", default: SettingDefault::Choice(&["auto", "draw", "arrival"]), doc: "with sample_claim: who wins an exactly coplanar tie. draw: the first fragment in draw order, as the stencil decides, through an ordered sample interlock (needs VK_EXT_fragment_shader_interlock); arrival: the first to claim, which may change from run to run and so flicker; auto: draw where the device has the interlock, else arrival. Refused on a pass whose depth has stencil (the stencil decides, in draw order)" },
            ],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "lighting_visibility",
            doc: "shades from a visibility buffer in compute (seed 003): each distinct (instance, triangle) id of a pixel's samples is rebuilt from the shared pools (barycentrics of the pixel-center ray) and shaded once, weighted by its samples",
            reads: vec![
                ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "the depth the ids were drawn with")),
                ms(slot("ids", Usage::Sampled(Stages::Compute), true, FormatRule::OneOf(VISIBILITY_FORMATS), "instance id and triangle id per sample (packed R32_UINT or R32G32_UINT)")),
            ],
            writes: vec![slot("output", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(LIT_OUTPUT_FORMAT), "lit image")],
            settings: lighting_settings(),
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "aa_edges",
            doc: "selective AA by depth-edge detection: marks the pixels whose depth samples mix background and surface or differ by more than a relative threshold",
            reads: vec![ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "the finished MSAA depth"))],
            writes: vec![slot("mask", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(AA_MASK_FORMAT), "1 on depth edges, 0 elsewhere")],
            settings: vec![SettingDecl { name: "threshold", default: SettingDefault::Float(0.01), doc: "relative view-depth difference between a pixel's samples that makes it an edge" }],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "lighting_compressed",
            doc: "lights the compressed G-buffer in compute: every block shaded once with tile-culled point lights, tone-mapped, weighted by the samples it covers, averaged",
            reads: vec![
                ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "the MSAA depth (positions are rebuilt from each block's sample)")),
                slot("gbuffer", Usage::StorageBufferRead(Stages::Compute), true, FormatRule::Any, "the compressed G-buffer"),
                slot("sample_claim", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "the samples gbuffer_compressed's fragments claimed (with a depth without stencil): the covered samples in one word instead of a read of every depth sample"),
            ],
            writes: vec![
                slot("output", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(LIT_OUTPUT_FORMAT), "lit image"),
                sized(slot("stats", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "pool counters and a blocks-per-pixel histogram (size: 64)"), STATS_BYTES),
            ],
            settings: {
                let mut settings = lighting_settings();
                settings.push(SettingDecl {
                    name: "shared_blocks",
                    default: SettingDefault::Int(512),
                    doc: "pool blocks a 16x16 tile gathers and shades with all its invocations per round, in up to four rounds (0..=1024; 0: each pixel loops over its own list, the thesis's resolve)",
                });
                settings.push(SettingDecl {
                    name: "shared_min_blocks",
                    default: SettingDefault::Int(0),
                    doc: "a tile with at most this many pool blocks leaves them to their pixels' own loops (0: every tile shares its blocks, the fastest on the H100)",
                });
                settings
            },
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "lighting",
            doc: "deferred lighting in compute: sun, point lights and sky ambient, tone-mapped, sRGB-encoded",
            reads: vec![
                ms(slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "reversed-Z depth (multisampled: every sample is lit)")),
                ms(slot("albedo", Usage::Sampled(Stages::Compute), true, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo, metallic")),
                ms(slot("normal", Usage::Sampled(Stages::Compute), true, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
            ],
            writes: vec![slot(
                "output",
                Usage::StorageImageWrite(Stages::Compute),
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "lit image",
            )],
            settings: lighting_settings(),
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "fxaa",
            doc: "FXAA 3.11 (PC quality) in compute over the lit image: luma from the sRGB-encoded value, edge search along the local edge, subpixel blend (the post-process AA baseline)",
            reads: vec![slot("input", Usage::Sampled(Stages::Compute), true, FormatRule::Exact(LIT_OUTPUT_FORMAT), "the lit image (sRGB-encoded), sampled bilinearly")],
            writes: vec![slot("output", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(LIT_OUTPUT_FORMAT), "the anti-aliased image (same size as the input)")],
            settings: vec![
                SettingDecl { name: "preset", default: SettingDefault::Choice(FXAA_PRESETS), doc: "FXAA_QUALITY__PRESET: the edge search schedule (39: extreme quality, 12: FXAA's default)" },
                SettingDecl { name: "subpix", default: SettingDefault::Float(0.75), doc: "amount of subpixel aliasing removal (0: off, 1: softest)" },
                SettingDecl { name: "edge_threshold", default: SettingDefault::Float(0.166), doc: "minimum local contrast, relative to the local maximum luma, to process a pixel" },
                SettingDecl { name: "edge_threshold_min", default: SettingDefault::Float(0.0833), doc: "minimum absolute local contrast (skips dark areas)" },
            ],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "gbuffer_append",
            doc: "like gbuffer, but draws on top of the existing targets (the late phase of two-phase culling)",
            reads: draw_list_slots(true),
            writes: vec![
                ms(slot("albedo", Usage::ColorAttachmentLoad, false, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a (omit albedo and normal for a depth-only pass)")),
                ms(slot("normal", Usage::ColorAttachmentLoad, false, FormatRule::OneOf(GBUFFER_NORMAL_FORMATS), NORMAL_SLOT_DOC)),
                ms(slot("ids", Usage::ColorAttachmentLoad, false, FormatRule::OneOf(VISIBILITY_FORMATS), "visibility buffer: instance id and triangle id (packed R32_UINT or R32G32_UINT)")),
                ms(slot("depth", Usage::DepthAttachmentLoad, true, FormatRule::Depth, "reversed-Z depth")),
            ],
            settings: vec![],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "hiz_build",
            doc: "builds the reversed-Z Hi-Z pyramid (minimum = farthest depth per footprint, conservative for every size) from (MSAA) depth",
            reads: vec![SlotDecl { multisample_ok: true, ..slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "depth, reduced across samples first") }],
            writes: vec![slot("hiz", Usage::StorageImageWrite(Stages::Compute), true, FormatRule::Exact(HIZ_FORMAT), "the pyramid from chain level 1: mip 0 at half the depth's size (max(1, width / 2) x max(1, height / 2)), at most the levels down to 1x1, every mip written")],
            settings: vec![SettingDecl {
                name: "method",
                default: SettingDefault::Choice(&["single", "per_mip"]),
                doc: "one dispatch for the whole pyramid, or one dispatch per mip (baseline)",
            }],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "instance_cull",
            doc: "tests every instance's world bound (frustum, optionally Hi-Z occlusion) and compacts the survivors per draw group in slot order (the unculled draw order) into draw commands for vkCmdDrawIndexedIndirectCount",
            reads: vec![
                sized(slot("visibility_prev", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "last frame's visibility bits (early and late phases)"), MinBytes::InstanceBits),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid to test against (none: frustum only)"),
            ],
            writes: vec![
                sized(slot("draw_commands", Usage::StorageBufferWrite(Stages::Compute), true, FormatRule::Any, "one command per draw group (size: meshes * 20)"), COMMANDS_BYTES),
                sized(slot("draw_count", Usage::StorageBufferWrite(Stages::Compute), true, FormatRule::Any, "number of commands of each face-cull region (12 bytes)"), COUNT_BYTES),
                sized(slot("draw_instance_ids", Usage::StorageBufferWrite(Stages::Compute), true, FormatRule::Any, "survivors, one slice per draw group (size: instances * 4)"), IDS_BYTES),
                sized(slot("visibility", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "this frame's visibility bits (late phase)"), MinBytes::InstanceBits),
                sized(slot("visible_ids", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visibility`: instance ids of this frame's visible slots, one slice per draw group: the next frame's early draw list, which that frame draws as it is with no cull pass (size: instances * 4, history; the draw binds `.prev`)"), IDS_BYTES),
                sized(slot("list_commands", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visible_ids`: the commands of that list (size: meshes * 20, history)"), COMMANDS_BYTES),
                sized(slot("list_count", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visible_ids`: their number per face-cull region (size: 12, history)"), COUNT_BYTES),
                sized(slot("list_stats", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "late phase, with `visible_ids`: that list's counters, reported as the next frame's early draw (size: 64, history)"), STATS_BYTES),
                sized(slot("stats", Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, "counters of this pass (size: 64)"), STATS_BYTES),
            ],
            settings: vec![
                SettingDecl { name: "phase", default: SettingDefault::Choice(&["all", "early", "late", "occluders", "rest"]), doc: "which instances the pass draws: all survivors; last frame's visible ones (early); newly visible ones (late); chosen occluders; all but the occluders" },
                SettingDecl { name: "frustum", default: SettingDefault::Bool(true), doc: "test against the view frustum (false: keep everything, the no-cull baseline)" },
                SettingDecl { name: "bound", default: SettingDefault::Choice(&["box", "sphere"]), doc: "world bound tested: axis-aligned box or sphere" },
                SettingDecl { name: "hiz_test", default: SettingDefault::Choice(&["coarse", "finer"]), doc: "occlusion footprint: at most 2x2 texels, or up to 3x3 one level finer (culls more)" },
                SettingDecl { name: "hiz_view", default: SettingDefault::Choice(&["current", "previous"]), doc: "project with this frame's camera, or last frame's (a test against last frame's pyramid)" },
                SettingDecl { name: "compaction", default: SettingDefault::Choice(&["ordered", "atomic"]), doc: "prefix-sum compaction in slot order (the unculled draw order), or the thesis's atomic append (order varies, measured only)" },
                SettingDecl { name: "occluder_distance", default: SettingDefault::Float(200.0), doc: "occluders phase: farthest distance of an occluder's bound" },
                SettingDecl { name: "occluder_size", default: SettingDefault::Float(0.02), doc: "occluders phase: smallest projected radius, as a fraction of the view height" },
                SettingDecl { name: "occluder_triangles", default: SettingDefault::Int(1024), doc: "occluders phase: instances of meshes with at most this many triangles are candidates too, besides those flagged as occluders (0: flagged ones only)" },
            ],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "overlay",
            doc: "draws this frame's culling counters (formatted on the GPU), with `gbuffer_stats` the compressed G-buffer's, per-pass GPU milliseconds and optional debug views (a Hi-Z mip, occlusion-culled instances) over the lit image",
            reads: vec![
                sized(slot("stats0", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a cull pass (its `stats` buffer, 64 bytes)"), STATS_BYTES),
                sized(slot("stats1", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a second cull pass"), STATS_BYTES),
                sized(slot("stats2", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a third cull pass"), STATS_BYTES),
                sized(slot("stats3", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a fourth cull pass"), STATS_BYTES),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid (view \"hiz\")"),
                sized(slot("visibility", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "this frame's visibility bits from the late cull pass (view \"culled\")"), MinBytes::InstanceBits),
                sized(slot("gbuffer_stats", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "a compressed G-buffer's counters (a lighting_compressed pass's `stats`): pool blocks in use, overflowed samples, pixels with several surfaces"), STATS_BYTES),
            ],
            writes: vec![slot(
                "output",
                Usage::StorageImageReadWrite(Stages::Compute),
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "the lit image, drawn on in place",
            )],
            settings: vec![
                SettingDecl {
                    name: "view",
                    default: SettingDefault::Choice(&["stats", "hiz", "culled"]),
                    doc: "the counter panel only; plus a Hi-Z mip in grey over the whole image; plus occlusion-culled instances tinted red",
                },
                SettingDecl { name: "hiz_level", default: SettingDefault::Int(0), doc: "mip of the Hi-Z pyramid shown by view \"hiz\" (clamped to the last)" },
                SettingDecl { name: "scale", default: SettingDefault::Int(0), doc: "text size in pixels per font pixel (0: max(1, height / 720))" },
                SettingDecl { name: "timings", default: SettingDefault::Bool(true), doc: "show GPU milliseconds per pass (of the newest completed frame)" },
            ],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: COMPUTE_KIND,
            doc: "a user compute shader; its slots are the shader's bindings (by binding number or variable name)",
            reads: vec![],
            writes: vec![],
            settings: vec![],
            slots_from_shader: true,
        },
    ]
}
