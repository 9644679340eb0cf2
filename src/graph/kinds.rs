//! Pass kinds as plugins: a [`PassKind`] declares its RON name, slots and settings
//! ([`PassKindInfo`]), its own checks, and creates the executor node of each pass of its kind. A
//! [`KindRegistry`] holds the kinds a graph is loaded with.
//!
//! The graph knows no kind of its own: cullgraph's built-in kinds register through this same
//! interface (`cullgraph::passes::builtin_kinds`), and so do an engine's. The declarations are
//! data shared by validation (names, usages, formats), the compiler (accesses and barriers) and
//! the executor.

use super::compile::resolve::Resolved;
use super::error::Pos;
use super::executor::PassNode;
use super::plan::{CompiledGraph, PlannedPass, SettingValue};
use super::usage::Usage;
use super::validated::{Pass, PassBinding, ValidatedGraph};
use crate::gpu::{GpuContext, ShaderCompiler};
use ash::vk;
use std::path::Path;
use std::sync::Arc;

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
    /// The least a buffer bound here must hold (or exactly what, for [`MinBytes::Exact`]);
    /// checked when the graph is compiled for a scene.
    pub min_bytes: MinBytes,
}

/// The least a buffer slot takes, in terms of the scene a graph is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MinBytes {
    /// No minimum (or an image slot).
    Any,
    /// This many bytes.
    Fixed(u64),
    /// Exactly this many bytes: a fixed-size record that the pass writes and the host reads
    /// whole (counters). A larger buffer is refused too, since its tail would mean nothing.
    Exact(u64),
    /// This many bytes per instance (`instances * n`).
    PerInstance(u64),
    /// This many bytes per draw group (`meshes * n`).
    PerMesh(u64),
    /// A bit per instance, in 32-bit words (`ceil(instances / 32) * 4`).
    InstanceBits,
    /// This many bytes per transparent instance (`max(1, blended) * n`).
    PerBlended(u64),
}

impl MinBytes {
    /// The bytes it asks for with `instances` instances (`blended` of them transparent) and
    /// `meshes` draw groups.
    pub fn bytes(self, instances: u64, meshes: u64, blended: u64) -> u64 {
        match self {
            MinBytes::PerBlended(n) => blended.max(1) * n,
            MinBytes::Any => 0,
            MinBytes::Fixed(n) | MinBytes::Exact(n) => n,
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
            MinBytes::Exact(n) => format!("exactly {n}"),
            MinBytes::PerInstance(n) => format!("instances * {n}"),
            MinBytes::PerMesh(n) => format!("meshes * {n}"),
            MinBytes::InstanceBits => "ceil_div(instances, 32) * 4".into(),
            MinBytes::PerBlended(n) => format!("max(1, blended) * {n}"),
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

impl SettingDefault {
    /// The default as a setting's value (a choice's first word).
    pub fn value(&self) -> SettingValue {
        match self {
            SettingDefault::Bool(b) => SettingValue::Bool(*b),
            SettingDefault::Int(i) => SettingValue::Int(*i),
            SettingDefault::Float(f) => SettingValue::Float(*f),
            SettingDefault::Choice(c) => SettingValue::Choice(c.first().copied().unwrap_or("").to_string()),
        }
    }
}

/// One setting a pass kind takes (`settings: {"exposure": 0.8}` in RON).
#[derive(Clone, Debug, PartialEq)]
pub struct SettingDecl {
    /// Name in RON.
    pub name: &'static str,
    /// Type and default.
    pub default: SettingDefault,
    /// The values a whole or real setting may take, inclusive; `None`: any (finite) value. A
    /// value outside is an error at the setting's position when the graph is compiled.
    pub range: Option<(f64, f64)>,
    /// What it does.
    pub doc: &'static str,
}

impl SettingDecl {
    /// Why `value` is outside the declared range, if it is.
    pub fn range_error(&self, value: &SettingValue) -> Option<String> {
        let (min, max) = self.range?;
        let v = match value {
            SettingValue::Int(i) => *i as f64,
            SettingValue::Float(f) => *f,
            _ => return None,
        };
        (!(min..=max).contains(&v)).then(|| format!("is {v}, outside {min} to {max}"))
    }
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
    /// Every setting at its declared default (what a pass that sets none of them gets).
    pub fn default_settings(&self) -> std::collections::BTreeMap<String, SettingValue> {
        self.settings.iter().map(|decl| (decl.name.to_string(), decl.default.value())).collect()
    }

    /// The slot named `name` among reads and writes.
    pub fn slot(&self, name: &str) -> Option<&SlotDecl> {
        self.reads.iter().chain(&self.writes).find(|s| s.name == name)
    }
}

/// Name of the generic compute kind, whose slots are the bindings of its shader.
pub const COMPUTE_KIND: &str = "compute";

/// A pass kind: what the graph needs to validate, compile and execute the passes of one kind.
///
/// Implement it for a compute pass or a graphics pass (dynamic rendering into the attachments
/// bound to its slots), register it in a [`KindRegistry`], and RON graphs loaded with that
/// registry use it as `kind: "name"`, with the same validation, barriers, aliasing and
/// timestamps as the built-in kinds.
pub trait PassKind: Send + Sync {
    /// The kind's name, slots, settings and documentation.
    fn info(&self) -> PassKindInfo;

    /// Checks of one pass of this kind beyond its slots and settings, when the graph is loaded
    /// (for example which slots must be bound together): `(position, message)` each, reported
    /// at that position of the file. `check.resolved` is empty here.
    fn validate(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let _ = check;
        Vec::new()
    }

    /// Checks of what the kind derives from the sizes of one compilation (output size and
    /// scene), such as a pyramid's size from its depth's: `check.resolved` holds every resource
    /// as compiled.
    fn check_sizes(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let _ = check;
        Vec::new()
    }

    /// Creates the node that records a pass of this kind (pipelines made, ready to record).
    fn create_node(&self, setup: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>>;
}

/// What a kind's own checks see of one pass.
pub struct KindCheck<'a> {
    /// The whole graph.
    pub graph: &'a ValidatedGraph,
    /// The pass being checked.
    pub pass: &'a Pass,
    /// Sample count of every resource (1 for buffers and for counts not known yet).
    pub samples: &'a [u32],
    /// Every resource as compiled ([`PassKind::check_sizes`]); empty at load time.
    pub resolved: &'a [Resolved],
}

impl<'a> KindCheck<'a> {
    /// The binding of `slot`, if the pass binds it.
    pub fn binding(&self, slot: &str) -> Option<&'a PassBinding> {
        self.pass.bindings.iter().find(|b| b.slot == slot)
    }

    /// The name of the resource bound by `binding`.
    pub fn resource_name(&self, binding: &PassBinding) -> &'a str {
        &self.graph.resources[binding.resource].name
    }

    /// The extent of the image bound to `slot`, as compiled.
    pub fn image_extent(&self, slot: &str) -> Option<(&'a PassBinding, vk::Extent2D)> {
        let b = self.binding(slot)?;
        match self.resolved.get(b.resource)? {
            Resolved::Image { extent, .. } => Some((b, *extent)),
            Resolved::Buffer(_) => None,
        }
    }
}

/// What a kind gets to create the node of one planned pass.
pub struct NodeSetup<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// Compiles the kind's shaders.
    pub shaders: &'a ShaderCompiler,
    /// The pass: its name, resolved settings and bindings.
    pub pass: &'a PlannedPass,
    /// The whole compiled graph (formats and sizes of the bound resources).
    pub plan: &'a CompiledGraph,
    /// The folder of the graph file, where its own shader files are found.
    pub graph_dir: Option<&'a Path>,
}

/// One registered kind.
#[derive(Clone)]
pub struct RegisteredKind {
    /// Its declaration, taken once at registration.
    pub info: PassKindInfo,
    /// The kind itself.
    pub kind: Arc<dyn PassKind>,
}

/// The pass kinds a graph may use, by name. Cloning shares the kinds.
#[derive(Clone, Default)]
pub struct KindRegistry {
    kinds: Vec<RegisteredKind>,
}

impl KindRegistry {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `kind`. A name already registered is refused, naming it: two kinds never share a
    /// name, and a kind is never replaced behind the graphs that use it.
    pub fn register(&mut self, kind: impl PassKind + 'static) -> crate::Result<()> {
        let info = kind.info();
        if self.get(info.name).is_some() {
            return Err(crate::Error::Invalid(format!("a pass kind named '{}' is already registered", info.name)));
        }
        if info.name.is_empty() || !info.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(crate::Error::Invalid(format!(
                "pass kind name '{}' must be letters, digits and '_' (it is written as kind: \"...\" in RON)",
                info.name
            )));
        }
        self.kinds.push(RegisteredKind { info, kind: Arc::new(kind) });
        Ok(())
    }

    /// The kind called `name`.
    pub fn get(&self, name: &str) -> Option<&RegisteredKind> {
        self.kinds.iter().find(|k| k.info.name == name)
    }

    /// The declaration of the kind called `name`.
    pub fn info(&self, name: &str) -> Option<&PassKindInfo> {
        self.get(name).map(|k| &k.info)
    }

    /// Every declaration, in registration order.
    pub fn infos(&self) -> impl Iterator<Item = &PassKindInfo> {
        self.kinds.iter().map(|k| &k.info)
    }
}

impl std::fmt::Debug for KindRegistry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.infos().map(|k| k.name)).finish()
    }
}

impl Eq for KindRegistry {}

impl PartialEq for KindRegistry {
    fn eq(&self, other: &Self) -> bool {
        self.infos().eq(other.infos())
    }
}
