//! Pass kinds as plugins: a [`PassKind`] declares its RON name, slots and settings
//! ([`PassKindInfo`]), the resources it creates for its slots, its own checks, decodes its
//! counters and creates the executor node of each pass of its kind. A [`KindRegistry`] holds the
//! kinds a graph is loaded with and the quantities their sizes use.
//!
//! The graph knows no kind of its own: cullgraph's built-in kinds register through this same
//! interface (`cullgraph::passes::builtin_kinds`), and so do an engine's. The declarations are
//! data shared by validation (names, usages, formats), the compiler (accesses and barriers) and
//! the executor.

mod counters;
mod setting;
mod slot;

pub use counters::{Adaptation, CounterEntry, DrawCounts, DrawList, DrawOrder, SettingOverride};
pub use setting::{Choice, SettingDecl, SettingDefault};
pub use slot::{Bytes, Counters, Created, Creates, Extent, FormatRule, MipChain, SlotDecl, Unbound};

use super::compile::device_limits::DeviceLimits;
use super::compile::resolve::Resolved;
use super::compose::LibraryGraph;
use super::error::Pos;
use super::executor::PassNode;
use super::expr::Expr;
use super::plan::{CompiledGraph, PlannedPass, SettingValue};
use super::quantity::{Quantities, Quantity, OUTPUT_VARIABLES};
use super::validated::{Pass, PassBinding, ValidatedGraph};
use crate::gpu::{GpuContext, ShaderCompiler};
use ash::vk;
use std::any::Any;
use std::path::Path;
use std::sync::Arc;

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

    /// Quantities the kind's sizes use that the host may not count yet, with how to count them
    /// ([`Quantity`]): registering the kind registers those whose names are new. `[]` (the
    /// default): it uses only quantities registered before it.
    fn quantities(&self) -> Vec<Quantity> {
        Vec::new()
    }

    /// Checks of one pass of this kind beyond its slots and settings, when the graph is loaded
    /// (for example which slots must be bound together): `(position, message)` each, reported
    /// at that position of the file. `check.resolved` is empty here.
    fn validate(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let _ = check;
        Vec::new()
    }

    /// Checks of one compilation (output size, scene, params, device): what the kind derives
    /// from the sizes, such as a pyramid's size from its depth's, and rules on settings that may
    /// come from params. `check.resolved` holds every resource as compiled and `check.planned`
    /// the pass with its settings resolved. Every rule the kind's node would enforce when it is
    /// created belongs here, so that `graph check --size` promises a frame.
    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let _ = check;
        Vec::new()
    }

    /// Creates the node that records a pass of this kind (pipelines made, ready to record).
    fn create_node(&self, setup: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>>;

    /// What the counters a pass of this kind wrote to its slot `slot` (declared with
    /// [`SlotDecl::counters`]) say, as an entry of the frame's stats; `pass` is the name they
    /// are reported under. `None` (the default): the kind reports nothing.
    fn decode_counters(&self, pass: &str, slot: &str, bytes: &[u8]) -> Option<CounterEntry> {
        let _ = (pass, slot, bytes);
        None
    }

    /// The draw list a pass of this kind draws, when it draws one (what a checking tool reads
    /// to know what each pass drew, [`crate::graph::GraphRuntime::capture_draw_lists`]);
    /// `None` (the default): it draws none.
    fn draw_list(&self) -> Option<DrawList> {
        None
    }

    /// Whether a pass of this kind reads the GPU times of the newest completed frame
    /// ([`crate::graph::PassContext::timings`]); the executor reads them back only then.
    fn reads_timings(&self) -> bool {
        false
    }

    /// The kind's policy for changing settings of the graph from what a pass's counters say
    /// (for example a pool that grows when it overflows), one per pass; `None` (the default):
    /// none.
    fn adaptation(&self) -> Option<Box<dyn Adaptation>> {
        None
    }
}

/// What a kind's own checks see of one pass.
pub struct KindCheck<'a> {
    /// The whole graph.
    pub graph: &'a ValidatedGraph,
    /// The pass being checked.
    pub pass: &'a Pass,
    /// Sample count of every resource (1 for buffers and for counts not known yet).
    pub samples: &'a [u32],
    /// Every resource as compiled ([`PassKind::check_compiled`]); empty at load time.
    pub resolved: &'a [Resolved],
    /// The pass as compiled, its settings resolved ([`PassKind::check_compiled`]); `None` at
    /// load time.
    pub planned: Option<&'a PlannedPass>,
    /// The device's limits and features, when there is a device.
    pub limits: Option<&'a DeviceLimits>,
    /// The scene's quantities of the compilation ([`PassKind::check_compiled`]); `None` at load
    /// time.
    pub quantities: Option<&'a Quantities>,
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

/// The pass kinds a graph may use, by name, and the quantities their sizes and the graphs'
/// expressions use. Cloning shares the kinds.
#[derive(Clone, Default)]
pub struct KindRegistry {
    kinds: Vec<RegisteredKind>,
    quantities: Vec<Quantity>,
    graphs: Vec<LibraryGraph>,
}

impl KindRegistry {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `kind`, and the quantities it declares that are not registered yet. A name already
    /// registered is refused, naming it: two kinds never share a name, and a kind is never
    /// replaced behind the graphs that use it.
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
        let mut with_quantities = self.clone();
        for quantity in kind.quantities() {
            if with_quantities.quantity(quantity.name).is_none() {
                with_quantities.register_quantity(quantity)?;
            }
        }
        if let Some(why) = with_quantities.declaration_error(&info) {
            return Err(crate::Error::Invalid(format!("pass kind '{}': {why}", info.name)));
        }
        *self = with_quantities;
        self.kinds.push(RegisteredKind { info, kind: Arc::new(kind) });
        Ok(())
    }

    /// Adds `quantity`, a variable of every expression of the graphs loaded with this registry.
    /// A name already registered, or one that is not an identifier, is refused.
    pub fn register_quantity(&mut self, quantity: Quantity) -> crate::Result<()> {
        let name = quantity.name;
        let identifier = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !identifier {
            return Err(crate::Error::Invalid(format!("quantity name '{name}' must be an identifier")));
        }
        if self.quantity(name).is_some() || OUTPUT_VARIABLES.contains(&name) {
            return Err(crate::Error::Invalid(format!("a quantity named '{name}' is already registered")));
        }
        self.quantities.push(quantity);
        Ok(())
    }

    /// Adds `graph` to the library of graphs that others extend by name (`extends:
    /// "two_phase"`). A name already registered is refused.
    pub fn register_graph(&mut self, graph: LibraryGraph) -> crate::Result<()> {
        if self.graph(graph.name).is_some() {
            return Err(crate::Error::Invalid(format!("a graph named '{}' is already registered", graph.name)));
        }
        self.graphs.push(graph);
        Ok(())
    }

    /// The library's graph called `name`.
    pub fn graph(&self, name: &str) -> Option<&LibraryGraph> {
        self.graphs.iter().find(|g| g.name == name)
    }

    /// The library's graphs, in registration order.
    pub fn graphs(&self) -> impl Iterator<Item = &LibraryGraph> {
        self.graphs.iter()
    }

    /// The quantity called `name`.
    pub fn quantity(&self, name: &str) -> Option<&Quantity> {
        self.quantities.iter().find(|q| q.name == name)
    }

    /// Every registered quantity, in registration order.
    pub fn quantities(&self) -> impl Iterator<Item = &Quantity> {
        self.quantities.iter()
    }

    /// The names every expression may use besides params: the output size and the quantities.
    pub fn variables(&self) -> Vec<&'static str> {
        OUTPUT_VARIABLES.iter().copied().chain(self.quantities.iter().map(|q| q.name)).collect()
    }

    /// Counts every registered quantity in the host's scene description `scene`; an error names
    /// a quantity that cannot count it.
    pub fn count(&self, scene: &dyn Any) -> crate::Result<Quantities> {
        self.quantities
            .iter()
            .map(|q| {
                let value = (q.count)(scene).ok_or_else(|| {
                    crate::Error::Invalid(format!("quantity '{}' cannot be counted in this host's scene", q.name))
                })?;
                Ok((q.name.to_string(), value))
            })
            .collect()
    }

    /// What is wrong with a kind's declaration: a size expression that does not parse or uses
    /// a name that is neither the output size, a registered quantity nor a numeric setting of
    /// the kind; a counters slot without an exact size; a created image sized by a slot the
    /// kind does not have.
    fn declaration_error(&self, info: &PassKindInfo) -> Option<String> {
        for slot in info.reads.iter().chain(&info.writes) {
            let created = match slot.creates {
                Some(Creates { resource: Created::BufferOf(e), .. }) => Some(e),
                _ => None,
            };
            for text in slot.bytes.expr().into_iter().chain(created) {
                let expr = match Expr::parse(text) {
                    Ok(e) => e,
                    Err(e) => return Some(format!("slot '{}': size \"{text}\": {}", slot.name, e.message)),
                };
                for (name, _) in expr.variables() {
                    let setting = info.settings.iter().any(|s| s.name == name && s.default.is_numeric());
                    if !setting && !OUTPUT_VARIABLES.contains(&name) && self.quantity(name).is_none() {
                        return Some(format!(
                            "slot '{}': size \"{text}\" uses '{name}', which is no quantity registered before \
                             the kind and no numeric setting of it",
                            slot.name
                        ));
                    }
                }
            }
            if slot.counters.is_some() && !matches!(slot.bytes, Bytes::Exactly(_)) {
                return Some(format!("counters slot '{}' must declare its exact size", slot.name));
            }
            if let Some(Creates { resource: Created::Image { extent: Extent::Of { slot: of, divisor }, .. }, .. }) =
                slot.creates
            {
                if info.slot(of).is_none() || divisor == 0 {
                    return Some(format!("slot '{}' creates an image sized by '{of}' / {divisor}", slot.name));
                }
            }
            if slot.creates.is_some() && !info.writes.iter().any(|w| w.name == slot.name) {
                return Some(format!("slot '{}' creates a resource but is not written", slot.name));
            }
        }
        None
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
            && self.quantities.iter().map(|q| q.name).eq(other.quantities.iter().map(|q| q.name))
            && self.graphs == other.graphs
    }
}
