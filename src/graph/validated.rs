//! A graph that passed validation: names resolved to indices, usages derived, expressions parsed,
//! every piece carrying the position it came from (so that compile-time errors, such as a size
//! that evaluates negative for one scene, are still reported as `file:line:col`).
//!
//! Everything here is independent of the output size and the scene; [`super::compile()`] resolves
//! it for one frame configuration.

use super::error::Pos;
use super::expr::{Expr, Num};
use super::kinds::{KindRegistry, PassKindInfo, SettingDefault};
use super::plan::{ResourceId, SettingValue, Version};
use super::usage::Usage;
use ash::vk;
use std::path::PathBuf;

/// An expression (or a literal number) with where it is written.
#[derive(Clone, Debug, PartialEq)]
pub struct LocatedExpr {
    /// The parsed expression.
    pub expr: Expr,
    /// Position of the string (or number) in the file.
    pub pos: Pos,
    /// Whether character offsets in the expression map to columns after `pos` (a plain
    /// one-line string without escapes).
    pub plain: bool,
}

impl LocatedExpr {
    /// A literal number at `pos`.
    pub fn constant(n: Num, pos: Pos) -> Self {
        Self { expr: Expr::constant(n), pos, plain: false }
    }

    /// The position of character `offset` of the expression.
    pub fn pos_at(&self, offset: usize) -> Pos {
        if self.plain {
            self.pos.right(1 + offset)
        } else {
            self.pos
        }
    }
}

/// The value of a param.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// `true`/`false`.
    Bool(bool),
    /// Whole number.
    Int(i64),
    /// Real number.
    Float(f64),
    /// String.
    Str(String),
}

impl ParamValue {
    /// `bool`, `int`, `float` or `string`.
    pub fn type_name(&self) -> &'static str {
        match self {
            ParamValue::Bool(_) => "bool",
            ParamValue::Int(_) => "int",
            ParamValue::Float(_) => "float",
            ParamValue::Str(_) => "string",
        }
    }

    /// Parses `text` as a value of the same type as `self` (for `--param` overrides).
    pub fn parse_like(&self, text: &str) -> Result<ParamValue, String> {
        let t = text.trim();
        match self {
            ParamValue::Bool(_) => match t {
                "true" => Ok(ParamValue::Bool(true)),
                "false" => Ok(ParamValue::Bool(false)),
                _ => Err(format!("'{text}' is not true or false")),
            },
            ParamValue::Int(_) => t.parse().map(ParamValue::Int).map_err(|_| format!("'{text}' is not a whole number")),
            ParamValue::Float(_) => match t.parse::<f64>() {
                Ok(f) if f.is_finite() => Ok(ParamValue::Float(f)),
                _ => Err(format!("'{text}' is not a finite number")),
            },
            ParamValue::Str(_) => Ok(ParamValue::Str(text.to_string())),
        }
    }

    /// As a number for expressions (`None` for bools and strings).
    pub fn as_num(&self) -> Option<Num> {
        match self {
            ParamValue::Int(i) => Some(Num::Int(*i)),
            ParamValue::Float(f) => Some(Num::Float(*f)),
            _ => None,
        }
    }
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Bool(b) => write!(f, "{b}"),
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Float(x) => write!(f, "{x:?}"),
            ParamValue::Str(s) => write!(f, "{s:?}"),
        }
    }
}

/// A declared param with its value (defaults with load-time overrides applied).
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Name.
    pub name: String,
    /// Value.
    pub value: ParamValue,
    /// Position of its name in the `params` map.
    pub pos: Pos,
}

/// How an image's mip-0 size follows from the output size.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSize {
    /// The output size.
    Output,
    /// Output size times a factor, rounded up, at least 1.
    Scaled(LocatedExpr),
    /// Width and height.
    Fixed(LocatedExpr, LocatedExpr),
    /// The size of another resource's first mip, divided and rounded down, at least 1 (a
    /// resource a kind creates relative to one bound to another of its slots).
    Like {
        /// The resource whose size it follows.
        resource: ResourceId,
        /// Divides each dimension.
        divisor: u32,
    },
}

/// Mip levels of an image.
#[derive(Clone, Debug, PartialEq)]
pub enum Mips {
    /// Down to 1x1.
    All,
    /// This many.
    Count(LocatedExpr),
}

/// What a resource is.
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)] // a graph has tens of resources; boxing buys nothing
pub enum ResourceDesc {
    /// A 2D image.
    Image {
        /// Texel format.
        format: vk::Format,
        /// Where the format is written.
        format_pos: Pos,
        /// Size of mip 0.
        size: ImageSize,
        /// Mip levels.
        mips: Mips,
        /// Sample count (params only).
        samples: LocatedExpr,
    },
    /// A buffer.
    Buffer {
        /// Bytes.
        size: LocatedExpr,
    },
}

/// A declared resource.
#[derive(Clone, Debug, PartialEq)]
pub struct Resource {
    /// Name.
    pub name: String,
    /// Position of its name in the `resources` map.
    pub pos: Pos,
    /// Image or buffer.
    pub desc: ResourceDesc,
    /// `history: true`: last frame's contents readable as `name.prev`.
    pub history: bool,
    /// Provided by the host every frame.
    pub imported: bool,
    /// The pass whose kind created it for one of its slots (`None`: declared in the file).
    pub owner: Option<Owner>,
    /// `when`: it exists only for frames where this is not 0 (`None`: always).
    pub when: Option<LocatedExpr>,
}

/// The pass whose kind created a resource, and for which slot.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Owner {
    /// The pass's index in [`ValidatedGraph::passes`].
    pub pass: usize,
    /// The pass's name.
    pub pass_name: String,
    /// The slot.
    pub slot: String,
}

impl Resource {
    /// Whether it is an image.
    pub fn is_image(&self) -> bool {
        matches!(self.desc, ResourceDesc::Image { .. })
    }

    /// How messages name it: `'name'`, and for a resource a kind created, which pass and slot
    /// it is for.
    pub fn describe(&self) -> String {
        match &self.owner {
            None => format!("'{}'", self.name),
            Some(o) => format!("'{}' (created by pass '{}' for its slot \"{}\")", self.name, o.pass_name, o.slot),
        }
    }
}

/// A resource bound to a slot of a pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassBinding {
    /// Slot name (compute passes: the binding number as text).
    pub slot: String,
    /// The slot as written in the file (a GLSL variable name or number for compute passes).
    pub written_slot: String,
    /// The resource.
    pub resource: ResourceId,
    /// Which contents.
    pub version: Version,
    /// How the pass uses it.
    pub usage: Usage,
    /// Whether the slot accepts multisampled images.
    pub multisample_ok: bool,
    /// Whether it was bound in `writes` (else `reads`).
    pub in_writes: bool,
    /// Position of the resource name.
    pub pos: Pos,
}

/// Where a pass setting's value comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SettingSource {
    /// A literal of the right type.
    Value(SettingValue),
    /// The value of this param.
    Param(String),
    /// A numeric expression.
    Expr(LocatedExpr),
}

/// A setting given in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct PassSetting {
    /// Setting name.
    pub name: String,
    /// Its type and default.
    pub ty: SettingDefault,
    /// Its value.
    pub source: SettingSource,
    /// Position of the value.
    pub pos: Pos,
}

/// Workgroup count of a compute pass.
#[derive(Clone, Debug, PartialEq)]
pub enum DispatchSpec {
    /// One thread per texel of mip 0 of this image.
    PerPixel(ResourceId),
    /// Threads in x, y, z.
    Threads([LocatedExpr; 3]),
    /// Workgroups in x, y, z.
    Groups([LocatedExpr; 3]),
}

/// A validated pass.
#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    /// Name.
    pub name: String,
    /// Position of its name.
    pub pos: Pos,
    /// Kind name.
    pub kind: String,
    /// Bound resources: `reads` in file order, then `writes`.
    pub bindings: Vec<PassBinding>,
    /// Settings given in the file (the compiler fills defaults for the rest).
    pub settings: Vec<PassSetting>,
    /// Compute shader: the file next to the graph if it exists, else the path in the shader library.
    pub shader: Option<PathBuf>,
    /// Compute dispatch.
    pub dispatch: Option<DispatchSpec>,
    /// Position of the dispatch.
    pub dispatch_pos: Pos,
    /// The shader's workgroup size (compute passes; `[1, 1, 1]` otherwise).
    pub local_size: [u32; 3],
}

/// A graph that passed validation.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidatedGraph {
    /// Graph name.
    pub name: String,
    /// The file name given to the loader (used in messages).
    pub file: String,
    /// Every file it was composed from, in [`Pos::file`] order (the first is `file`).
    pub files: Vec<String>,
    /// Params in file order.
    pub params: Vec<Param>,
    /// Resources in file order.
    pub resources: Vec<Resource>,
    /// Passes in file order.
    pub passes: Vec<Pass>,
    /// Output resources.
    pub outputs: Vec<ResourceId>,
    /// Where each output is listed.
    pub output_pos: Vec<Pos>,
    /// The pass kinds it was validated against.
    pub kinds: KindRegistry,
    /// The limits of the device it was validated for (none without a device): compiling checks
    /// sizes against them.
    pub limits: Option<super::compile::device_limits::DeviceLimits>,
}

impl ValidatedGraph {
    /// The resource called `name`.
    pub fn resource_id(&self, name: &str) -> Option<ResourceId> {
        self.resources.iter().position(|r| r.name == name)
    }

    /// The pass called `name`.
    pub fn pass_index(&self, name: &str) -> Option<usize> {
        self.passes.iter().position(|p| p.name == name)
    }

    /// The kind of pass `pass`.
    pub fn kind(&self, pass: usize) -> Option<&PassKindInfo> {
        self.kinds.info(&self.passes[pass].kind)
    }
}
