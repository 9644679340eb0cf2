//! The render graph: a RON file declares parameters, resources and passes; loading validates it
//! with `file:line:col` positions; compiling prunes, orders, computes lifetimes, aliases
//! transient memory and plans synchronization2 barriers; the executor records the plan.
//!
//! Semantics (see `graph/README.md` for the file format):
//! - Passes are listed in a RON sequence. A pass that reads a resource sees the latest write
//!   declared *before* it; if none is declared before it, the first write declared after it
//!   (so independent passes may be listed in any order). Reading something nothing writes is an
//!   error, except imported resources (the host fills them) and `name.prev` of history resources
//!   (last frame's contents).
//! - Writes to one resource happen in declaration order; reads stay between the writes they
//!   see. Any other reordering is allowed: execution order is a topological order that prefers
//!   declaration order. A dependency cycle is an error naming the passes on it.
//! - Reading `name.prev` creates no edge: the graph of one frame stays acyclic even when a pass
//!   uses last frame's Hi-Z.
//! - Passes whose results reach no output and no later frame are pruned (and listed).
//!
//! The graph knows no pass kind: every kind, built-in or an engine's, is a [`PassKind`] in the
//! [`KindRegistry`] a graph is loaded with; this module imports nothing from the layers above it
//! (`tests/layers.rs` checks it).
//!
//! Pipeline: [`load`] (parse the RON, then report all errors at once, each at its position) ->
//! [`ValidatedGraph`] -> [`compile()`] for one output size and scene -> [`CompiledGraph`]
//! (printable through `Display`, [`to_dot`]) -> [`GraphRuntime`], which records it.

pub(crate) mod compile;
pub(crate) mod compose;
pub(crate) mod env;
pub(crate) mod error;
pub(crate) mod executor;
pub(crate) mod expr;
pub mod formats;
pub(crate) mod kinds;
pub(crate) mod locate;
pub mod plan;
pub(crate) mod quantity;
pub(crate) mod report;
pub(crate) mod schema;
pub(crate) mod usage;
pub(crate) mod validate;
pub mod validated;

pub use compile::device_limits::{ComputeLimits, DeviceLimits};
pub use compile::resolve::Resolved;
pub use compile::{compile, FrameInputs};
pub use compose::LibraryGraph;
pub use env::{DeviceEnv, Environment, NoDevice};
pub use error::{GraphError, GraphErrors, Pos, COMMAND_LINE};
pub(crate) use executor::Captured;
pub use executor::{
    CompletedTimings, FrameData, FrameRecording, GraphRuntime, Import, Imports, PassContext, PassNode, ResourceBytes,
    SlotBindings, StepTimer, FRAMES_IN_FLIGHT,
};
pub use kinds::{
    Adaptation, Bytes, Choice, CounterEntry, Counters, Created, Creates, DrawCounts, DrawList, DrawOrder, Extent,
    FormatRule, KindCheck, KindRegistry, MipChain, NodeSetup, PassKind, PassKindInfo, RegisteredKind, SettingDecl,
    SettingDefault, SettingOverride, SlotDecl, Unbound, COMPUTE_KIND,
};
pub use plan::{
    Binding, CompiledGraph, PlannedBarrier, PlannedPass, PlannedResource, ResolvedKind, ResourceClass, ResourceId,
    SettingValue, Version,
};
pub use quantity::{Growth, Quantities, Quantity};
pub use report::to_dot;
pub use usage::{Stages, Usage};
pub use validate::{load, load_file, load_in, parse_param_override, ParamOverride};
pub use validated::{Pass, PassBinding, ValidatedGraph};
