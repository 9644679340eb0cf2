//! Named quantities of the scene a graph is compiled for (`instances`, `meshes`, ...): the
//! variables, besides the output size, of the size expressions of graphs and kinds.
//!
//! The graph knows none of them. Whoever registers a pass kind that needs one registers the
//! quantity beside it ([`crate::graph::KindRegistry::register_quantity`]), with the function
//! that counts it in the host's scene description, so a new quantity touches no file of the
//! graph layer. The host hands that description to [`crate::graph::KindRegistry::count`] (as
//! `&dyn Any`; each quantity downcasts it to the type it was written for) and compiles with what
//! comes back.

use std::any::Any;
use std::collections::BTreeMap;

/// The variables every expression may use besides the host's quantities.
pub const OUTPUT_VARIABLES: [&str; 2] = ["width", "height"];

/// How a quantity follows a scene that changes after the graph was compiled for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Growth {
    /// The host compiles for more than there is now, and again only when the scene outgrows
    /// that (instances, draw groups, lights).
    Grows,
    /// The host compiles again whenever it changes.
    Exact,
}

/// A named quantity and how to count it.
#[derive(Clone, Copy, Debug)]
pub struct Quantity {
    /// Its name in expressions.
    pub name: &'static str,
    /// What it counts.
    pub doc: &'static str,
    /// Counts it in the host's scene description; `None` when that is not the type it counts.
    pub count: fn(&dyn Any) -> Option<u64>,
    /// How it follows a changing scene.
    pub growth: Growth,
}

/// The values of the quantities one graph is compiled for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Quantities(BTreeMap<String, u64>);

impl Quantities {
    /// None.
    pub fn new() -> Self {
        Self::default()
    }

    /// The value of `name`.
    pub fn get(&self, name: &str) -> Option<u64> {
        self.0.get(name).copied()
    }

    /// Sets `name` to `value`.
    pub fn set(&mut self, name: &str, value: u64) {
        self.0.insert(name.to_string(), value);
    }

    /// `self` with `name` set to `value`.
    pub fn with(mut self, name: &str, value: u64) -> Self {
        self.set(name, value);
        self
    }

    /// Every quantity with its value, by name.
    pub fn iter(&self) -> impl Iterator<Item = (&str, u64)> {
        self.0.iter().map(|(k, v)| (k.as_str(), *v))
    }
}

impl FromIterator<(String, u64)> for Quantities {
    fn from_iter<I: IntoIterator<Item = (String, u64)>>(iter: I) -> Self {
        Self(iter.into_iter().collect())
    }
}
