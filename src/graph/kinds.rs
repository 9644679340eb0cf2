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
/// The G-buffer geometry pass's normal/roughness format.
pub const GBUFFER_NORMAL_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// The lighting pass's output format (sRGB-encoded values in a UNORM image, so it can be storage).
pub const LIT_OUTPUT_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

const fn slot(name: &'static str, usage: Usage, required: bool, format: FormatRule, doc: &'static str) -> SlotDecl {
    SlotDecl { name, usage, required, format, multisample_ok: false, doc }
}

/// The built-in pass kinds.
pub fn builtin_kinds() -> Vec<PassKindInfo> {
    vec![
        PassKindInfo {
            name: "gbuffer",
            doc: "draws the scene's draw groups with vkCmdDrawIndexedIndirectCount into albedo, normal and reversed-Z depth",
            reads: vec![
                slot("draw_commands", Usage::Indirect, false, FormatRule::Any, "VkDrawIndexedIndirectCommand per draw group (default: every instance)"),
                slot("draw_count", Usage::Indirect, false, FormatRule::Any, "number of commands (default: every non-empty group)"),
                slot(
                    "draw_instance_ids",
                    Usage::StorageBufferRead(Stages::Vertex),
                    false,
                    FormatRule::Any,
                    "instance ids, one slice per draw group",
                ),
            ],
            writes: vec![
                slot("albedo", Usage::ColorAttachment, true, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo rgb, metallic a"),
                slot("normal", Usage::ColorAttachment, true, FormatRule::Exact(GBUFFER_NORMAL_FORMAT), "normal xyz, roughness a"),
                slot("depth", Usage::DepthAttachment, true, FormatRule::Exact(vk::Format::D32_SFLOAT), "reversed-Z depth"),
            ],
            settings: vec![],
            slots_from_shader: false,
        },
        PassKindInfo {
            name: "lighting",
            doc: "deferred lighting in compute: sun, point lights and sky ambient, tone-mapped, sRGB-encoded",
            reads: vec![
                slot("depth", Usage::Sampled(Stages::Compute), true, FormatRule::Depth, "reversed-Z depth"),
                slot("albedo", Usage::Sampled(Stages::Compute), true, FormatRule::Exact(GBUFFER_ALBEDO_FORMAT), "albedo, metallic"),
                slot("normal", Usage::Sampled(Stages::Compute), true, FormatRule::Exact(GBUFFER_NORMAL_FORMAT), "normal, roughness"),
            ],
            writes: vec![slot(
                "output",
                Usage::StorageImageWrite(Stages::Compute),
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "lit image",
            )],
            settings: vec![
                SettingDecl { name: "exposure", default: SettingDefault::Float(0.8), doc: "scale applied before tone mapping" },
                SettingDecl {
                    name: "debug_view",
                    default: SettingDefault::Choice(&["none", "normals", "albedo", "depth"]),
                    doc: "show a G-buffer channel instead of the lit image",
                },
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
