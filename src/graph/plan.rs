//! The compiled graph: what the compiler hands the executor (and `cullgraph graph plan` prints).
//!
//! Positions in [`CompiledGraph::passes`] are the execution order. Resource sizes are resolved
//! for one output size and scene; a change of either recompiles.

use super::usage::Usage;
use crate::gpu::Access;
use ash::vk;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Index into [`CompiledGraph::resources`].
pub type ResourceId = usize;

/// Which contents of a resource a binding sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Version {
    /// This frame's contents.
    Current,
    /// Last frame's final contents (history resources only; `name.prev` in RON).
    Previous,
}

/// How a resource lives across passes and frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResourceClass {
    /// Lives within one frame between its first and last use; may share memory with others.
    Transient,
    /// Two copies swapped every frame so that last frame's contents can be read (never aliased).
    History,
    /// Provided by the host each frame (never allocated or aliased by the graph).
    Imported,
    /// Read by the host after the frame (never aliased).
    Output,
}

/// A resource with its size resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum ResolvedKind {
    /// A 2D image.
    Image {
        /// Texel format.
        format: vk::Format,
        /// Size of mip 0.
        extent: vk::Extent2D,
        /// Mip levels.
        mip_levels: u32,
        /// Samples per texel.
        samples: vk::SampleCountFlags,
        /// Union of the usages of every pass that touches it (plus transfer source for outputs).
        usage: vk::ImageUsageFlags,
    },
    /// A buffer.
    Buffer {
        /// Bytes.
        size: u64,
        /// Union of the usages of every pass that touches it.
        usage: vk::BufferUsageFlags,
    },
}

/// One resource of the compiled graph.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedResource {
    /// Name in the RON file.
    pub name: String,
    /// Resolved description.
    pub kind: ResolvedKind,
    /// Lifetime class.
    pub class: ResourceClass,
    /// First and last position (in execution order) of a pass that uses the current version;
    /// `None` when no kept pass uses it.
    pub lifetime: Option<(usize, usize)>,
    /// Where it is declared in the graph file (errors of creating or importing it name it); for
    /// a resource a kind created, where the pass binds it or is named.
    pub pos: super::error::Pos,
    /// The pass whose kind created it (`None`: declared in the graph).
    pub owner: Option<String>,
}

/// A resource bound to a slot of a pass.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Binding {
    /// Slot name (for compute passes: the binding number as text).
    pub slot: String,
    /// The resource.
    pub resource: ResourceId,
    /// Which contents.
    pub version: Version,
    /// How the pass uses it.
    pub usage: Usage,
}

/// A resolved pass setting.
#[derive(Clone, Debug, PartialEq)]
pub enum SettingValue {
    /// Boolean.
    Bool(bool),
    /// Whole number.
    Int(i64),
    /// Real number.
    Float(f64),
    /// One word of a fixed set.
    Choice(String),
}

/// Typed reads of a planned pass's settings. The compiler fills every setting the kind declares
/// (with its one declared default where the graph gives none), so a read fails only for a setting
/// the kind does not declare as that type: a mistake of the kind's code, named in the error.
impl PlannedPass {
    fn undeclared(&self, name: &str, ty: &str) -> crate::Error {
        crate::Error::Invalid(format!(
            "pass '{}' ({}): no {ty} setting '{name}' (its kind does not declare one)",
            self.name, self.kind
        ))
    }

    /// The real-valued setting `name` (a whole number counts).
    pub fn real(&self, name: &str) -> crate::Result<f64> {
        match self.settings.get(name) {
            Some(SettingValue::Float(f)) => Ok(*f),
            Some(SettingValue::Int(i)) => Ok(*i as f64),
            _ => Err(self.undeclared(name, "real")),
        }
    }

    /// The whole-number setting `name`.
    pub fn int(&self, name: &str) -> crate::Result<i64> {
        match self.settings.get(name) {
            Some(SettingValue::Int(i)) => Ok(*i),
            _ => Err(self.undeclared(name, "whole-number")),
        }
    }

    /// The choice setting `name`, as the enum its kind declared it with
    /// ([`crate::graph::SettingDecl::choice`]).
    pub fn choice<C: crate::graph::Choice>(&self, name: &str) -> crate::Result<C> {
        match self.settings.get(name) {
            Some(SettingValue::Choice(word)) => C::WORDS
                .iter()
                .position(|w| w == word)
                .and_then(C::from_index)
                .ok_or_else(|| self.undeclared(name, &format!("choice of {}", C::WORDS.join(", ")))),
            _ => Err(self.undeclared(name, "choice")),
        }
    }

    /// The boolean setting `name`.
    pub fn flag(&self, name: &str) -> crate::Result<bool> {
        match self.settings.get(name) {
            Some(SettingValue::Bool(b)) => Ok(*b),
            _ => Err(self.undeclared(name, "boolean")),
        }
    }
}

/// A barrier recorded before a pass (all of a pass's barriers go into one `vkCmdPipelineBarrier2`).
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedBarrier {
    /// The resource.
    pub resource: ResourceId,
    /// Which copy (history resources).
    pub version: Version,
    /// The access that must complete first. `None` for the first use of the resource in the
    /// frame: the executor fills it from what last touched that memory (previous frame, or an
    /// aliased resource), which only it knows at run time.
    pub src: Option<Access>,
    /// The access that waits.
    pub dst: Access,
    /// Previous contents are not needed (images transition from `UNDEFINED`).
    pub discard: bool,
}

/// A pass in execution order.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedPass {
    /// Name in the RON file.
    pub name: String,
    /// Kind name (`gbuffer`, `lighting`, `compute`, ...).
    pub kind: String,
    /// Resources bound to its slots.
    pub bindings: Vec<Binding>,
    /// Settings with defaults filled in.
    pub settings: BTreeMap<String, SettingValue>,
    /// The shader of a `compute` pass (resolved path).
    pub shader: Option<PathBuf>,
    /// Workgroup counts of a `compute` pass.
    pub dispatch: Option<[u32; 3]>,
    /// Barriers before the pass.
    pub barriers: Vec<PlannedBarrier>,
    /// Where the pass is declared (in whichever file of a composed graph).
    pub pos: super::error::Pos,
}

/// A pass the compiler removed, with the reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PrunedPass {
    /// Name in the RON file.
    pub name: String,
    /// Kind name.
    pub kind: String,
    /// Why, per resource it writes (e.g. "'debug' is never read; 'tmp' is overwritten by 'b'
    /// before anything reads it").
    pub reason: String,
    /// What it would have bound (for reports and graphviz).
    pub bindings: Vec<Binding>,
}

/// Where a transient lives in memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Placement {
    /// Index of the heap.
    pub heap: usize,
    /// Byte offset in it.
    pub offset: u64,
}

/// Transient memory: placements of resources that share heaps when their lifetimes do not overlap.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemoryPlan {
    /// Per resource (same indices as [`CompiledGraph::resources`]); `None` for non-transients.
    pub placements: Vec<Option<Placement>>,
    /// Size of each heap in bytes.
    pub heaps: Vec<u64>,
    /// Bytes of all transients if each had its own memory.
    pub bytes_without_aliasing: u64,
    /// Bytes of the heaps.
    pub bytes_with_aliasing: u64,
}

/// A graph ready to execute.
#[derive(Clone, Debug, PartialEq)]
pub struct CompiledGraph {
    /// Graph name.
    pub name: String,
    /// The file it was loaded from, as given to the loader.
    pub file: String,
    /// Every file it was composed from, in [`super::error::Pos::file`] order.
    pub files: Vec<String>,
    /// Passes in execution order.
    pub passes: Vec<PlannedPass>,
    /// Removed passes.
    pub pruned: Vec<PrunedPass>,
    /// Every declared resource.
    pub resources: Vec<PlannedResource>,
    /// Resources the frame produces for the host (the first is the image `cullgraph render` saves).
    pub outputs: Vec<ResourceId>,
    /// Where each output is listed in the graph's files.
    pub output_pos: Vec<super::error::Pos>,
    /// Transient memory, estimated from formats and sizes (the executor re-plans with the
    /// device's real memory requirements through the same algorithm).
    pub memory: MemoryPlan,
    /// The pass kinds the graph was loaded with (the executor creates each pass's node through
    /// its kind).
    pub kinds: super::kinds::KindRegistry,
}

impl CompiledGraph {
    /// The name of the file of `pos`, among those the graph was composed from.
    pub fn file_at(&self, pos: super::error::Pos) -> &str {
        super::error::file_of(&self.files, pos)
    }

    /// `file:line:col: resource 'name'`: where resource `id` is declared, for errors of what
    /// is done with it after compiling (creating its memory, importing it).
    pub fn declaration(&self, id: ResourceId) -> String {
        let r = &self.resources[id];
        format!("{}:{}: resource '{}'", super::error::file_of(&self.files, r.pos), r.pos, r.name)
    }

    /// `error` of resource `id`, prefixed with where it is declared.
    pub fn error_at(&self, id: ResourceId, error: impl Into<crate::Error>) -> crate::Error {
        crate::Error::Declared { at: self.declaration(id), source: Box::new(error.into()) }
    }
}
