//! The RON file format, as serde types (see `graph/README.md` for the format with examples).
//!
//! These types accept what ron can check by itself (structure, field and variant names; every
//! struct denies unknown fields) and keep everything else as written, so that validation can
//! report *all* semantic problems at once with positions (serde stops at the first error):
//! maps keep their entries in file order *with duplicates* ([`Entries`]), formats stay names,
//! numbers stay numbers or expression strings.

use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use std::fmt;
use std::marker::PhantomData;

/// A whole graph file: `Graph(name: .., extends: .., params: {..}, resources: {..}, passes: [..],
/// edits: [..], outputs: [..])`.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename = "Graph", deny_unknown_fields)]
pub struct GraphFile {
    /// Graph name (for messages, labels and the plan).
    pub name: String,
    /// The graph this one builds on: a name of the registry's library or a `.ron` path relative
    /// to this file.
    #[serde(default)]
    pub extends: Option<String>,
    /// Parameters with their defaults; `--param k=v` overrides them. With `extends`: added, or
    /// new defaults of the base's.
    #[serde(default)]
    pub params: Entries<Literal>,
    /// Resources by name. With `extends`: added, or replacing the base's of the same name.
    #[serde(default)]
    pub resources: Entries<ResourceDecl>,
    /// Passes in declaration order. With `extends`: after the base's.
    #[serde(default)]
    pub passes: Vec<PassDecl>,
    /// Changes to the passes so far (the base's and the ones above), in order.
    #[serde(default)]
    pub edits: Vec<EditDecl>,
    /// Resources the frame produces for the host (required; the first is the image shown).
    /// With `extends`: the base's unless given.
    #[serde(default)]
    pub outputs: Option<Vec<String>>,
}

/// A change to the passes of a graph, by pass name.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename = "Edit", deny_unknown_fields)]
pub enum EditDecl {
    /// Inserts passes before or after a pass (exactly one of `before` and `after`).
    Insert {
        /// The pass they go before.
        #[serde(default)]
        before: Option<String>,
        /// The pass they go after.
        #[serde(default)]
        after: Option<String>,
        /// The passes, in order.
        passes: Vec<PassDecl>,
    },
    /// Replaces a pass (the new one may have another name and kind).
    Replace {
        /// The pass replaced.
        pass: String,
        /// What replaces it.
        with: PassDecl,
    },
    /// Removes a pass.
    Remove {
        /// The pass removed.
        pass: String,
    },
    /// Changes bindings and settings of a pass: entries given replace the pass's of the same
    /// slot or setting, or are added; `unbind` removes bindings.
    Set {
        /// The pass changed.
        pass: String,
        /// Read bindings to add or replace.
        #[serde(default)]
        reads: Entries<String>,
        /// Write bindings to add or replace.
        #[serde(default)]
        writes: Entries<String>,
        /// Settings to add or replace.
        #[serde(default)]
        settings: Entries<Literal>,
        /// Slots whose bindings are removed (before the others are added).
        #[serde(default)]
        unbind: Vec<String>,
    },
}

/// The entries of a RON map in file order, duplicates kept (ron itself keeps only the last).
#[derive(Clone, Debug, PartialEq)]
pub struct Entries<V>(pub Vec<(String, V)>);

impl<V> Default for Entries<V> {
    fn default() -> Self {
        Entries(Vec::new())
    }
}

impl<'de, V: Deserialize<'de>> Deserialize<'de> for Entries<V> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V2<V>(PhantomData<V>);
        impl<'de, V: Deserialize<'de>> Visitor<'de> for V2<V> {
            type Value = Entries<V>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map with string keys")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = map.next_entry::<String, V>()? {
                    out.push((k, v));
                }
                Ok(Entries(out))
            }
        }
        d.deserialize_map(V2(PhantomData))
    }
}

/// A literal value: param defaults and pass settings.
#[derive(Clone, Debug, PartialEq)]
pub enum Literal {
    /// `true` / `false`.
    Bool(bool),
    /// A whole number.
    Int(i64),
    /// A real number (written with a `.` or exponent).
    Float(f64),
    /// A string (for settings: a literal word, a param name or an expression).
    Str(String),
}

impl<'de> Deserialize<'de> for Literal {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Literal;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a bool, a number or a string")
            }
            fn visit_bool<E>(self, v: bool) -> Result<Literal, E> {
                Ok(Literal::Bool(v))
            }
            fn visit_i64<E>(self, v: i64) -> Result<Literal, E> {
                Ok(Literal::Int(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Literal, E> {
                i64::try_from(v).map(Literal::Int).map_err(|_| E::custom(format!("{v} is too large")))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Literal, E> {
                Ok(Literal::Float(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<Literal, E> {
                Ok(Literal::Str(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A number or an expression string (`4`, `0.5`, `"meshes * 20 + 16"`).
#[derive(Clone, Debug, PartialEq)]
pub enum NumLit {
    /// A whole number.
    Int(i64),
    /// A real number.
    Float(f64),
    /// An expression over params and frame quantities.
    Expr(String),
}

impl<'de> Deserialize<'de> for NumLit {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NumLit;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an expression string")
            }
            fn visit_i64<E>(self, v: i64) -> Result<NumLit, E> {
                Ok(NumLit::Int(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<NumLit, E> {
                i64::try_from(v).map(NumLit::Int).map_err(|_| E::custom(format!("{v} is too large")))
            }
            fn visit_f64<E>(self, v: f64) -> Result<NumLit, E> {
                Ok(NumLit::Float(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<NumLit, E> {
                Ok(NumLit::Expr(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A format name written as a bare identifier (`D32_SFLOAT`); checked against the table by
/// validation, so that an unknown one is reported with suggestions and with the other errors.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FormatName(pub String);

impl<'de> Deserialize<'de> for FormatName {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = FormatName;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a format name such as R8G8B8A8_UNORM")
            }
            fn visit_str<E>(self, v: &str) -> Result<FormatName, E> {
                Ok(FormatName(v.to_string()))
            }
        }
        d.deserialize_identifier(V)
    }
}

/// `mips: All` or a count (number or expression). ron hands a bare identifier over without its
/// text, so `Named` is checked against the file text by validation (it must say `All`).
#[derive(Clone, Debug, PartialEq)]
pub enum MipsDecl {
    /// An identifier; must be `All` (a full chain down to 1x1).
    Named,
    /// A number of levels.
    Count(NumLit),
}

impl<'de> Deserialize<'de> for MipsDecl {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = MipsDecl;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("`All`, a number or an expression string")
            }
            fn visit_unit<E>(self) -> Result<MipsDecl, E> {
                Ok(MipsDecl::Named)
            }
            fn visit_i64<E>(self, v: i64) -> Result<MipsDecl, E> {
                Ok(MipsDecl::Count(NumLit::Int(v)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<MipsDecl, E> {
                i64::try_from(v).map(|v| MipsDecl::Count(NumLit::Int(v))).map_err(|_| E::custom("too many mips"))
            }
            fn visit_f64<E>(self, v: f64) -> Result<MipsDecl, E> {
                Ok(MipsDecl::Count(NumLit::Float(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<MipsDecl, E> {
                Ok(MipsDecl::Count(NumLit::Expr(v.to_string())))
            }
        }
        d.deserialize_any(V)
    }
}

/// Size of an image's first mip.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(rename = "Size", deny_unknown_fields)]
pub enum SizeDecl {
    /// The output size (`width` x `height`).
    #[default]
    Output,
    /// The output size times a factor, rounded up, at least 1.
    Scaled(NumLit),
    /// Fixed width and height (numbers or expressions).
    Fixed(NumLit, NumLit),
}

/// A resource declaration.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename = "Resource", deny_unknown_fields)]
pub enum ResourceDecl {
    /// A 2D image.
    Image {
        /// Texel format.
        format: FormatName,
        /// Size of mip 0 (default: the output size).
        #[serde(default)]
        size: SizeDecl,
        /// Mip levels (default 1).
        #[serde(default)]
        mips: Option<MipsDecl>,
        /// Samples per texel: 1, 2, 4 or 8 (default 1).
        #[serde(default)]
        samples: Option<NumLit>,
        /// Keep last frame's contents readable as `name.prev`.
        #[serde(default)]
        history: bool,
        /// An expression: the image exists only where it is not 0 (a scene quantity, say), and
        /// the passes' optional slots bound to it are left unbound otherwise.
        #[serde(default)]
        when: Option<NumLit>,
    },
    /// A buffer.
    Buffer {
        /// Bytes (number or expression).
        size: NumLit,
        /// Keep last frame's contents readable as `name.prev`.
        #[serde(default)]
        history: bool,
        /// As an image's `when`.
        #[serde(default)]
        when: Option<NumLit>,
    },
    /// A resource the host provides every frame.
    Imported(ImportedDecl),
}

/// What an imported resource is.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename = "Imported", deny_unknown_fields)]
pub enum ImportedDecl {
    /// A 2D image.
    Image {
        /// Texel format.
        format: FormatName,
        /// Size of mip 0 (default: the output size).
        #[serde(default)]
        size: SizeDecl,
        /// Mip levels (default 1).
        #[serde(default)]
        mips: Option<MipsDecl>,
        /// Samples per texel (default 1).
        #[serde(default)]
        samples: Option<NumLit>,
    },
    /// A buffer.
    Buffer {
        /// Bytes.
        size: NumLit,
    },
}

/// How many workgroups a compute pass dispatches.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename = "Dispatch", deny_unknown_fields)]
pub enum DispatchDecl {
    /// One thread per texel of mip 0 of this image (divided by the workgroup size, rounded up).
    PerPixel(String),
    /// A number of threads in x, y, z (divided by the workgroup size, rounded up).
    Threads(NumLit, NumLit, NumLit),
    /// A number of workgroups in x, y, z.
    Groups(NumLit, NumLit, NumLit),
}

/// A pass declaration.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename = "Pass", deny_unknown_fields)]
pub struct PassDecl {
    /// Unique name.
    pub name: String,
    /// Pass kind (`gbuffer`, `lighting`, `compute`, ...).
    pub kind: String,
    /// Slot -> resource (`"name"` or `"name.prev"`) the pass reads.
    #[serde(default)]
    pub reads: Entries<String>,
    /// Slot -> resource the pass writes.
    #[serde(default)]
    pub writes: Entries<String>,
    /// Setting -> literal, param name or expression.
    #[serde(default)]
    pub settings: Entries<Literal>,
    /// Compute shader path (compute passes only): relative to the graph file, then `shaders/`.
    #[serde(default)]
    pub shader: Option<String>,
    /// Workgroup count (compute passes only).
    #[serde(default)]
    pub dispatch: Option<DispatchDecl>,
}

/// ron options used for graph files: `Some(..)` may be left out (`shader: "x.comp"`).
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// Parses a graph file; the error is ron's, with its span.
pub fn parse(text: &str) -> Result<GraphFile, ron::error::SpannedError> {
    ron_options().from_str(text)
}
