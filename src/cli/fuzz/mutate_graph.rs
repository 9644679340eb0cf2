//! Structure-aware mutations of RON graphs: the seed is parsed into a [`Node`] tree and edited
//! there, so that most inputs get past the RON parser and reach validation, compiling and
//! rendering.
//!
//! The edits know nothing of the graph schema. Every node has a *context*: the field, map or
//! list it sits in (`kind`, `reads.key`, `reads.value`, `passes[]`, `Fixed()`). What the seeds
//! hold at each context is pooled, and an edit replaces a node, adds a field, inserts a map
//! entry or a list element with something found at the same context in some seed: a resource
//! name where one was, a pass from another graph, a `size:` of another resource, a setting of
//! another pass. Scalars are also set to edge values (numbers at the limits, expressions
//! rewritten token by token, odd strings and formats), and containers lose, duplicate, reorder
//! and gain items. A field added to the format needs no change here: its values are pooled
//! like any other.

use super::ron_tree::{self, Document, Node};
use rand::rngs::SmallRng;
use rand::Rng;
use std::collections::BTreeMap;

/// Numbers at an edge: zero, negative, not whole, at and beyond 16 and 32 bits, huge, tiny,
/// not finite.
const EDGE_NUMBERS: &[&str] = &[
    "0",
    "1",
    "-1",
    "2",
    "3",
    "0.5",
    "-0.0",
    "1e-40",
    "1e30",
    "1e308",
    "255",
    "256",
    "16384",
    "16385",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "inf",
    "-inf",
    "NaN",
];

/// Strings that no seed has but a user might write.
const ODD_STRINGS: &[&str] = &[
    "",
    " ",
    ".prev",
    "x.prev.prev",
    "a.b",
    "\u{0}",
    "/dev/zero",
    "/proc/self/mem",
    "../../../../etc/passwd",
    ".",
    "missing.comp",
    "builtin:none",
    "width * height * 4096",
    "instances * 1e12",
    "ceil_div(width, 0)",
    "max(1, ",
    "((((((((((((((((1))))))))))))))))",
    "-1",
    "1e400",
    "width / 0",
    "\u{e9}\u{1F600}",
];

/// Identifiers that stretch the format names and variants.
const ODD_IDENTS: &[&str] = &[
    "R8_UNORM",
    "R8G8B8_UNORM",
    "R8G8B8A8_SRGB",
    "R16G16_SFLOAT",
    "R32_UINT",
    "R32_SFLOAT",
    "R32G32B32A32_SFLOAT",
    "B10G11R11_UFLOAT_PACK32",
    "D16_UNORM",
    "D24_UNORM_S8_UINT",
    "D32_SFLOAT",
    "D32_SFLOAT_S8_UINT",
    "BC1_RGB_UNORM_BLOCK",
    "UNDEFINED",
    "All",
    "None",
    "true",
    "false",
    "Output",
    "inf",
    "NaN",
];

/// Quantities an expression may name.
const QUANTITIES: &[&str] = &[
    "width",
    "height",
    "instances",
    "meshes",
    "lights",
    "blended",
    "materials",
    "triangles",
    "samples",
    "views",
    "max",
    "min",
    "ceil_div",
    "undefined_name",
];

/// One step from a node to one inside it.
#[derive(Clone, Copy, Debug)]
enum Step {
    Field(usize),
    Item(usize),
    Key(usize),
    Value(usize),
}

/// What the seeds hold, by context, to draw replacements from.
#[derive(Default)]
pub struct Pools {
    /// Every node seen at a context.
    nodes: BTreeMap<String, Vec<Node>>,
    /// Every entry of the maps at a context.
    entries: BTreeMap<String, Vec<(Node, Node)>>,
    /// Every field of the structs of a name (`""` for unnamed ones).
    fields: BTreeMap<String, Vec<(String, Node)>>,
    /// Every string, for the rare edit that crosses contexts.
    strings: Vec<String>,
    /// Identifiers met in expressions and the params' names.
    expression_words: Vec<String>,
}

impl Pools {
    /// Pools everything in `docs`.
    pub fn of<'a>(docs: impl IntoIterator<Item = &'a Document>) -> Pools {
        let mut pools = Pools::default();
        for doc in docs {
            pools.add(&doc.root, "");
        }
        pools.expression_words.extend(QUANTITIES.iter().map(|q| q.to_string()));
        pools.expression_words.sort();
        pools.expression_words.dedup();
        pools.strings.sort();
        pools.strings.dedup();
        pools
    }

    fn add(&mut self, node: &Node, ctx: &str) {
        self.nodes.entry(ctx.to_string()).or_default().push(node.clone());
        if plain(ctx) != ctx {
            self.nodes.entry(plain(ctx).to_string()).or_default().push(node.clone());
        }
        match node {
            Node::Struct { name, fields } => {
                let pool = self.fields.entry(name.clone().unwrap_or_default()).or_default();
                pool.extend(fields.iter().cloned());
                let scope = scope_of(fields, ctx);
                for (k, v) in fields {
                    self.add(v, &format!("{scope}{k}"));
                }
            }
            Node::Tuple { name, items } => {
                let ctx = format!("{}()", name.as_deref().unwrap_or(ctx));
                items.iter().for_each(|v| self.add(v, &ctx));
            }
            Node::List(items) => {
                let ctx = format!("{ctx}[]");
                items.iter().for_each(|v| self.add(v, &ctx));
            }
            Node::Map(entries) => {
                self.entries.entry(ctx.to_string()).or_default().extend(entries.iter().cloned());
                if plain(ctx) != ctx {
                    self.entries.entry(plain(ctx).to_string()).or_default().extend(entries.iter().cloned());
                }
                let (keys, values) = (format!("{ctx}.key"), format!("{ctx}.value"));
                for (k, v) in entries {
                    self.add(k, &keys);
                    self.add(v, &values);
                    if let (Node::Str(name), "params") = (k, plain(ctx)) {
                        self.expression_words.push(name.clone());
                    }
                }
            }
            Node::Str(s) => {
                self.strings.push(s.clone());
                self.expression_words.extend(words(s).filter(|w| !w.starts_with(|c: char| c.is_ascii_digit())));
            }
            Node::Num(_) | Node::Ident(_) | Node::Char(_) => {}
        }
    }
}

/// Where replacements come from: the seed being mutated (its own resource names, say) and all
/// seeds; at a context in a struct with a `kind` (a pass), mostly what structs of that kind
/// have there (a gbuffer pass's slots).
pub struct Donors<'a> {
    global: &'a Pools,
    local: Pools,
}

impl Donors<'_> {
    fn pools(&self, rng: &mut SmallRng) -> &Pools {
        if rng.random_bool(0.4) {
            &self.local
        } else {
            self.global
        }
    }

    /// A node seen at `ctx` (or, a quarter of the time, at the same context in any scope).
    fn donor(&self, rng: &mut SmallRng, ctx: &str) -> Option<Node> {
        let pools = self.pools(rng);
        let scoped = if rng.random_bool(0.75) { ctx } else { plain(ctx) };
        pick(rng, pools.nodes.get(scoped).or_else(|| pools.nodes.get(plain(ctx)))?).cloned()
    }

    /// An entry of the maps seen at `ctx`.
    fn entry(&self, rng: &mut SmallRng, ctx: &str) -> Option<(Node, Node)> {
        let pools = self.pools(rng);
        let scoped = if rng.random_bool(0.75) { ctx } else { plain(ctx) };
        pick(rng, pools.entries.get(scoped).or_else(|| pools.entries.get(plain(ctx)))?).cloned()
    }
}

/// Separates a context from the scope it is in (`gbuffer:reads.key`).
const SCOPE: char = ':';

/// `ctx` without its scope.
fn plain(ctx: &str) -> &str {
    ctx.rsplit_once(SCOPE).map_or(ctx, |(_, c)| c)
}

/// The scope of a struct's fields: its `kind` when it has one (the one thing these edits know
/// of the format: a pass's kind decides its slots and settings), else the scope it is in.
fn scope_of(fields: &[(String, Node)], ctx: &str) -> String {
    match fields.iter().find(|(k, _)| k == "kind") {
        Some((_, Node::Str(kind))) => format!("{kind}{SCOPE}"),
        _ => ctx.rsplit_once(SCOPE).map_or(String::new(), |(scope, _)| format!("{scope}{SCOPE}")),
    }
}

/// The identifiers in an expression.
fn words(s: &str) -> impl Iterator<Item = String> + '_ {
    s.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).filter(|w| !w.is_empty()).map(str::to_string)
}

fn pick<'a, T>(rng: &mut SmallRng, items: &'a [T]) -> Option<&'a T> {
    (!items.is_empty()).then(|| &items[rng.random_range(0..items.len())])
}

/// Every node of `node` with its path and context.
fn places(node: &Node, ctx: &str, path: &mut Vec<Step>, out: &mut Vec<(Vec<Step>, String)>) {
    out.push((path.clone(), ctx.to_string()));
    let mut inner = |step: Step, child: &Node, ctx: &str, out: &mut Vec<(Vec<Step>, String)>| {
        path.push(step);
        places(child, ctx, path, out);
        path.pop();
    };
    match node {
        Node::Struct { fields, .. } => {
            let scope = scope_of(fields, ctx);
            for (i, (k, v)) in fields.iter().enumerate() {
                inner(Step::Field(i), v, &format!("{scope}{k}"), out);
            }
        }
        Node::Tuple { name, items } => {
            let ctx = format!("{}()", name.as_deref().unwrap_or(ctx));
            for (i, v) in items.iter().enumerate() {
                inner(Step::Item(i), v, &ctx, out);
            }
        }
        Node::List(items) => {
            let ctx = format!("{ctx}[]");
            for (i, v) in items.iter().enumerate() {
                inner(Step::Item(i), v, &ctx, out);
            }
        }
        Node::Map(entries) => {
            let (keys, values) = (format!("{ctx}.key"), format!("{ctx}.value"));
            for (i, (k, v)) in entries.iter().enumerate() {
                inner(Step::Key(i), k, &keys, out);
                inner(Step::Value(i), v, &values, out);
            }
        }
        _ => {}
    }
}

fn node_at<'a>(node: &'a mut Node, path: &[Step]) -> Option<&'a mut Node> {
    let Some((first, rest)) = path.split_first() else { return Some(node) };
    let child = match (node, *first) {
        (Node::Struct { fields, .. }, Step::Field(i)) => &mut fields.get_mut(i)?.1,
        (Node::Tuple { items, .. } | Node::List(items), Step::Item(i)) => items.get_mut(i)?,
        (Node::Map(entries), Step::Key(i)) => &mut entries.get_mut(i)?.0,
        (Node::Map(entries), Step::Value(i)) => &mut entries.get_mut(i)?.1,
        _ => return None,
    };
    node_at(child, rest)
}

/// A mutated copy of `seed`: one to four edits of its tree, printed as RON.
pub fn graph(rng: &mut SmallRng, seed: &Document, pools: &Pools) -> String {
    let donors = Donors { global: pools, local: Pools::of([seed]) };
    let mut doc = seed.clone();
    // Mostly one edit, so that an input's outcome says what the edit did; sometimes a few,
    // for what only a combination reaches.
    let edits = 1 + (0..3).take_while(|_| rng.random_bool(0.4)).count();
    for _ in 0..edits {
        let mut all = Vec::new();
        places(&doc.root, "", &mut Vec::new(), &mut all);
        let (path, ctx) = all.swap_remove(rng.random_range(0..all.len()));
        if let Some(node) = node_at(&mut doc.root, &path) {
            edit(rng, node, &ctx, &donors);
        }
    }
    ron_tree::print(&doc)
}

/// One edit of `node`, which sits at `ctx`.
fn edit(rng: &mut SmallRng, node: &mut Node, ctx: &str, pools: &Donors) {
    // Edits any node may take: what another seed has here, or (rarely: the schema refuses it
    // at once) something of another context, or wrapped.
    match rng.random_range(0..40) {
        0..=7 => {
            if let Some(donor) = pools.donor(rng, ctx) {
                *node = donor;
                return;
            }
        }
        8 => {
            let contexts: Vec<&String> = pools.global.nodes.keys().collect();
            if let Some(other) = pick(rng, &contexts).and_then(|c| pools.donor(rng, c.as_str())) {
                *node = other;
                return;
            }
        }
        9 => {
            *node = match rng.random_range(0..3) {
                0 => Node::Tuple { name: Some("Some".into()), items: vec![node.clone()] },
                1 => Node::List(vec![node.clone()]),
                _ => Node::Tuple { name: None, items: vec![] },
            };
            return;
        }
        _ => {}
    }
    match node {
        Node::Num(n) => *n = number(rng, n),
        Node::Str(s) => *s = string(rng, s, ctx, pools),
        Node::Ident(i) => {
            *i = match rng.random_range(0..3) {
                0 => ODD_IDENTS[rng.random_range(0..ODD_IDENTS.len())].to_string(),
                _ => match pools.donor(rng, ctx) {
                    Some(Node::Ident(other)) => other,
                    _ => ODD_IDENTS[rng.random_range(0..ODD_IDENTS.len())].to_string(),
                },
            }
        }
        Node::Char(_) => *node = Node::Str(String::new()),
        Node::Struct { name, fields } => {
            let pool = pools.global.fields.get(name.as_deref().unwrap_or("")).map(Vec::as_slice).unwrap_or(&[]);
            match rng.random_range(0..12) {
                0 | 1 if !fields.is_empty() => {
                    fields.remove(rng.random_range(0..fields.len()));
                }
                2 if !fields.is_empty() => {
                    let copy = fields[rng.random_range(0..fields.len())].clone();
                    fields.insert(rng.random_range(0..=fields.len()), copy);
                }
                3 | 4 => rename(rng, name, ctx, pools),
                5 if fields.len() > 1 => {
                    let (a, b) = (rng.random_range(0..fields.len()), rng.random_range(0..fields.len()));
                    fields.swap(a, b);
                }
                _ => {
                    // A field this kind of struct has somewhere: replaces the one of that name
                    // (a setting, a size, a shader of another pass) or is added.
                    if let Some((key, value)) = pick(rng, pool).cloned() {
                        match fields.iter_mut().find(|(k, _)| *k == key) {
                            Some(slot) if rng.random_bool(0.9) => slot.1 = value,
                            _ => fields.insert(rng.random_range(0..=fields.len()), (key, value)),
                        }
                    }
                }
            }
        }
        Node::Tuple { name, items } => match rng.random_range(0..4) {
            0 => rename(rng, name, ctx, pools),
            1 if !items.is_empty() => {
                items.remove(rng.random_range(0..items.len()));
            }
            2 if !items.is_empty() => {
                let copy = items[rng.random_range(0..items.len())].clone();
                items.push(copy);
            }
            _ => {
                if let Some(n) = pick(rng, EDGE_NUMBERS) {
                    items.push(Node::Num(n.to_string()));
                }
            }
        },
        Node::List(items) => sequence(rng, items, &format!("{ctx}[]"), pools),
        Node::Map(entries) => map(rng, entries, ctx, pools),
    }
}

/// A new name for a struct or tuple: one seen at the same context (`Image` for `Buffer`,
/// `Scaled` for `Fixed`), any seen, or none.
fn rename(rng: &mut SmallRng, name: &mut Option<String>, ctx: &str, pools: &Donors) {
    let named = |n: &Node| match n {
        Node::Struct { name, .. } | Node::Tuple { name, .. } => name.clone(),
        _ => None,
    };
    *name = match rng.random_range(0..4) {
        0 => None,
        1 => {
            let all: Vec<&String> = pools.global.fields.keys().filter(|k| !k.is_empty()).collect();
            pick(rng, &all).map(|s| s.to_string())
        }
        _ => pools.donor(rng, ctx).and_then(|n| named(&n)).or(name.clone()),
    };
}

/// Removes, duplicates, moves or inserts (from what the seeds have at `item_ctx`) elements.
fn sequence(rng: &mut SmallRng, items: &mut Vec<Node>, item_ctx: &str, pools: &Donors) {
    let n = items.len();
    match rng.random_range(0..7) {
        0 if n > 0 => {
            items.remove(rng.random_range(0..n));
        }
        1 if n > 0 => {
            let copy = items[rng.random_range(0..n)].clone();
            items.insert(rng.random_range(0..=n), copy);
        }
        2 if n > 1 => {
            let from = items.remove(rng.random_range(0..n));
            items.insert(rng.random_range(0..n), from);
        }
        3 if n > 1 => {
            let (a, b) = (rng.random_range(0..n), rng.random_range(0..n));
            items.swap(a, b);
        }
        4 => {
            if rng.random_bool(0.5) {
                items.reverse();
            } else {
                items.truncate(rng.random_range(0..=n));
            }
        }
        _ => {
            if let Some(donor) = pools.donor(rng, item_ctx) {
                items.insert(rng.random_range(0..=n), donor);
            }
        }
    }
}

/// Removes, duplicates, renames or inserts (from the seeds' maps at `ctx`) entries.
fn map(rng: &mut SmallRng, entries: &mut Vec<(Node, Node)>, ctx: &str, pools: &Donors) {
    let n = entries.len();
    match rng.random_range(0..14) {
        0 | 1 if n > 0 => {
            entries.remove(rng.random_range(0..n));
        }
        2 if n > 0 => {
            let copy = entries[rng.random_range(0..n)].clone();
            entries.insert(rng.random_range(0..=n), copy);
        }
        3 | 4 if n > 0 => {
            // The same value under another key the seeds use here (another slot, resource).
            if let Some(key) = pools.donor(rng, &format!("{ctx}.key")) {
                let i = rng.random_range(0..n);
                entries[i].0 = key;
            }
        }
        5 | 6 if n > 1 => {
            let (a, b) = (rng.random_range(0..n), rng.random_range(0..n));
            let value = entries[b].1.clone();
            entries[b].1 = std::mem::replace(&mut entries[a].1, value);
        }
        7 if n > 0 => entries.truncate(rng.random_range(0..n)),
        _ => {
            if let Some(entry) = pools.entry(rng, ctx) {
                // Replaces the entry of that key, if any, as often as it is added.
                match entries.iter_mut().find(|(k, _)| *k == entry.0) {
                    Some(slot) if rng.random_bool(0.8) => *slot = entry,
                    _ => entries.insert(rng.random_range(0..=n), entry),
                }
            }
        }
    }
}

/// A number at an edge, or a near one.
fn number(rng: &mut SmallRng, n: &str) -> String {
    let value: f64 = n.parse().unwrap_or(1.0);
    match rng.random_range(0..6) {
        0 => format!("{}", value as i64 + 1),
        1 => format!("{}", value as i64 - 1),
        2 => format!("{}", (value * 2.0) as i64),
        3 => format!("{value:.1}"),
        _ => EDGE_NUMBERS[rng.random_range(0..EDGE_NUMBERS.len())].to_string(),
    }
}

/// Another string: one of the seeds' at the same context (a resource, slot, kind or shader
/// name where one was), an expression rewritten, a renamed or `.prev` variant, or an odd one.
fn string(rng: &mut SmallRng, s: &str, ctx: &str, pools: &Donors) -> String {
    // Names are rarely worth rewriting as expressions; sizes and settings are.
    let expression_like = s.contains(|c: char| "()+-*/%, ".contains(c) || c.is_ascii_digit());
    match rng.random_range(0..10) {
        0..=3 => match pools.donor(rng, ctx) {
            Some(Node::Str(other)) => other,
            _ => pick(rng, &pools.global.strings).cloned().unwrap_or_default(),
        },
        4..=6 if expression_like || rng.random_bool(0.15) => expression(rng, s, pools),
        4..=6 => match pools.donor(rng, ctx) {
            Some(Node::Str(other)) => other,
            _ => s.to_string(),
        },
        7 => match s.strip_suffix(".prev") {
            Some(base) => base.to_string(),
            None if rng.random_bool(0.5) => format!("{s}.prev"),
            None => format!("{s}_2"),
        },
        8 => pick(rng, &pools.global.strings).cloned().unwrap_or_default(),
        _ => ODD_STRINGS[rng.random_range(0..ODD_STRINGS.len())].to_string(),
    }
}

/// `s` read as an expression and rewritten: a word or number replaced, an operator changed, a
/// token dropped, or the whole wrapped.
fn expression(rng: &mut SmallRng, s: &str, pools: &Donors) -> String {
    let mut tokens: Vec<String> = Vec::new();
    let mut chars = s.chars().peekable();
    while let Some(&c) = chars.peek() {
        let mut token = String::new();
        if c.is_ascii_alphanumeric() || c == '_' || c == '.' {
            while let Some(&c) = chars.peek().filter(|c| c.is_ascii_alphanumeric() || **c == '_' || **c == '.') {
                token.push(c);
                chars.next();
            }
        } else {
            token.push(c);
            chars.next();
        }
        tokens.push(token);
    }
    let word =
        |rng: &mut SmallRng| pick(rng, &pools.global.expression_words).cloned().unwrap_or_else(|| "width".into());
    let is_word = |t: &str| t.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_');
    let is_number = |t: &str| t.starts_with(|c: char| c.is_ascii_digit());
    let at = |rng: &mut SmallRng, f: &dyn Fn(&str) -> bool| {
        let found: Vec<usize> = (0..tokens.len()).filter(|&i| f(&tokens[i])).collect();
        pick(rng, &found).copied()
    };
    match rng.random_range(0..8) {
        0 => match at(rng, &is_word) {
            Some(i) => tokens[i] = word(rng),
            None => tokens.push(format!(" * {}", word(rng))),
        },
        1 => match at(rng, &is_number) {
            Some(i) => tokens[i] = EDGE_NUMBERS[rng.random_range(0..EDGE_NUMBERS.len())].to_string(),
            None => tokens.push(format!(" + {}", EDGE_NUMBERS[rng.random_range(0..EDGE_NUMBERS.len())])),
        },
        2 => match at(rng, &|t: &str| "+-*/%".contains(t) && t.len() == 1) {
            Some(i) => tokens[i] = ["+", "-", "*", "/", "%", "^", ","][rng.random_range(0..7)].to_string(),
            None => tokens.push(" / 0".into()),
        },
        3 if !tokens.is_empty() => {
            tokens.remove(rng.random_range(0..tokens.len()));
        }
        4 => return format!("max(1, {s})"),
        5 => return format!("ceil_div({s}, {})", ["0", "1", "-1", "4294967296"][rng.random_range(0..4)]),
        6 => return format!("({s}) * {}", ["1000000", "4096", "-1", "0.5", "1e30"][rng.random_range(0..5)]),
        _ => return format!("{s} {} {}", ["+", "-", "*", "/"][rng.random_range(0..4)], word(rng)),
    }
    tokens.concat()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn most_mutants_of_the_shipped_graphs_still_parse_and_differ() {
        let docs: Vec<Document> =
            cullgraph::passes::SHIPPED_GRAPHS.iter().map(|g| ron_tree::parse(g.text).unwrap()).collect();
        let pools = Pools::of(&docs);
        // New fields reach the pools like any other.
        assert!(pools.nodes.contains_key("kind") && pools.nodes.contains_key("reads.value"));
        let mut rng = SmallRng::seed_from_u64(7);
        let (mut parsed, mut changed) = (0, 0);
        for i in 0..500 {
            let seed = &docs[i % docs.len()];
            let text = graph(&mut rng, seed, &pools);
            parsed += usize::from(ron_tree::parse(&text).is_some());
            changed += usize::from(text != ron_tree::print(seed));
        }
        assert_eq!(parsed, 500, "a printed tree is RON");
        // A few seeds are small (a one-pass shadow graph), where a mutation more often prints
        // the seed back.
        assert!(changed > 375, "{changed} of 500 changed");
    }

    #[test]
    fn expressions_are_rewritten_token_by_token() {
        let pools = Pools::of(std::iter::empty());
        let pools = Donors { global: &pools, local: Pools::default() };
        let mut rng = SmallRng::seed_from_u64(1);
        let outs: Vec<String> = (0..50).map(|_| expression(&mut rng, "ceil_div(instances, 32) * 4", &pools)).collect();
        assert!(outs.iter().any(|o| o.contains("ceil_div(") && !o.contains("instances")), "{outs:?}");
        assert!(outs.iter().any(|o| o.starts_with("max(1, ")), "{outs:?}");
    }
}
