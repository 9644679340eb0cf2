//! The settings a pass kind takes, each declared once with its type and default: booleans,
//! numbers with their range, and choices whose words come from a Rust enum ([`Choice`]), so that
//! the kind reads a setting back as the type it declared.

use crate::graph::plan::SettingValue;

/// A setting that is one of a fixed set of words, read back as a Rust enum. Declare it with
/// [`crate::choice!`], which writes each word once, next to its variant.
pub trait Choice: Copy + Sized + 'static {
    /// The words in RON, in variant order; the first is the default.
    const WORDS: &'static [&'static str];

    /// The variant of `WORDS[index]`.
    fn from_index(index: usize) -> Option<Self>;

    /// The word of this variant.
    fn word(self) -> &'static str;
}

/// Declares an enum whose variants are the words of a choice setting ([`Choice`]); the first
/// variant is the default.
///
/// ```
/// cullgraph::choice! {
///     /// How the pyramid is built.
///     pub enum Method {
///         /// One dispatch.
///         Single = "single",
///         /// One dispatch per level.
///         PerMip = "per_mip",
///     }
/// }
/// use cullgraph::graph::Choice;
/// assert_eq!(Method::WORDS, ["single", "per_mip"]);
/// assert_eq!(Method::from_index(1), Some(Method::PerMip));
/// ```
#[macro_export]
macro_rules! choice {
    ($(#[$meta:meta])* $vis:vis enum $name:ident { $($(#[$vmeta:meta])* $variant:ident = $word:literal),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        $vis enum $name {
            $($(#[$vmeta])* $variant),+
        }

        impl $crate::graph::Choice for $name {
            const WORDS: &'static [&'static str] = &[$($word),+];

            fn from_index(index: usize) -> Option<Self> {
                const VARIANTS: &[$name] = &[$($name::$variant),+];
                VARIANTS.get(index).copied()
            }

            fn word(self) -> &'static str {
                match self {
                    $($name::$variant => $word),+
                }
            }
        }
    };
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

    /// Whether values of this type are numbers (variables of a kind's size expressions).
    pub fn is_numeric(&self) -> bool {
        matches!(self, SettingDefault::Int(_) | SettingDefault::Float(_))
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
    /// value outside is an error at the setting's position.
    pub range: Option<(f64, f64)>,
    /// What it does.
    pub doc: &'static str,
}

impl SettingDecl {
    /// A boolean setting.
    pub fn flag(name: &'static str, default: bool, doc: &'static str) -> Self {
        Self { name, default: SettingDefault::Bool(default), range: None, doc }
    }

    /// A whole-number setting within `min..=max`.
    pub fn int(name: &'static str, default: i64, (min, max): (i64, i64), doc: &'static str) -> Self {
        Self { name, default: SettingDefault::Int(default), range: Some((min as f64, max as f64)), doc }
    }

    /// A real setting within `min..=max`.
    pub fn real(name: &'static str, default: f64, range: (f64, f64), doc: &'static str) -> Self {
        Self { name, default: SettingDefault::Float(default), range: Some(range), doc }
    }

    /// A choice among the words of `C`; the first is the default.
    pub fn choice<C: Choice>(name: &'static str, doc: &'static str) -> Self {
        Self { name, default: SettingDefault::Choice(C::WORDS), range: None, doc }
    }

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
