//! A RON document as a generic tree that keeps what the graph format relies on and
//! `ron::Value` drops: struct and enum variant names (`Pass(..)`, `Fixed(..)`), bare
//! identifiers (`D32_SFLOAT`, `All`), the order of map entries and their duplicates, and numbers
//! as written. The structure-aware fuzzer parses its seeds into it, edits the tree, and prints
//! it back as RON, so that it needs to know nothing of the graph schema: a field added to the
//! format is one more node.

use std::fmt::Write;

/// One RON value.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// `Name(field: value, ..)` or `(field: value, ..)`.
    Struct { name: Option<String>, fields: Vec<(String, Node)> },
    /// `Name(value, ..)`, `(value, ..)` or `Name()`.
    Tuple { name: Option<String>, items: Vec<Node> },
    /// `[value, ..]`.
    List(Vec<Node>),
    /// `{key: value, ..}`, in file order, duplicates kept.
    Map(Vec<(Node, Node)>),
    /// A string, unescaped.
    Str(String),
    /// A number as written (`12`, `-0.5`, `1e30`, `0xff`).
    Num(String),
    /// A bare identifier: `true`, `None`, `All`, `R8G8B8A8_UNORM`, `inf`.
    Ident(String),
    /// A character literal.
    Char(char),
}

/// A parsed document: its leading attributes (`#![enable(..)]`) and its value.
#[derive(Clone, Debug, PartialEq)]
pub struct Document {
    /// Attributes before the value, as written.
    pub attributes: Vec<String>,
    /// The value.
    pub root: Node,
}

/// Deepest nesting parsed; a seed deeper than this is left to the byte-level mutations.
const MAX_DEPTH: usize = 64;

/// Parses `text`; None when it is not RON this tree can hold (the byte-level mutations still
/// use such seeds).
pub fn parse(text: &str) -> Option<Document> {
    let mut p = Parser { s: text.as_bytes(), i: 0, text };
    let mut attributes = Vec::new();
    p.skip();
    while p.s[p.i..].starts_with(b"#![") {
        let start = p.i;
        let end = text[start..].find(']').map(|e| start + e + 1)?;
        // `#![enable(a, b)]`: the closing bracket follows the closing parenthesis.
        let end = if text[start..end].contains('(') && !text[start..end].contains(')') {
            text[end..].find(']').map(|e| end + e + 1)?
        } else {
            end
        };
        attributes.push(text[start..end].to_string());
        p.i = end;
        p.skip();
    }
    let root = p.value(0)?;
    p.skip();
    (p.i == p.s.len()).then_some(Document { attributes, root })
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    text: &'a str,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    /// Skips white space and comments (`/* */` nest in RON).
    fn skip(&mut self) {
        loop {
            while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
                self.i += 1;
            }
            if self.s[self.i..].starts_with(b"//") {
                while self.peek().is_some_and(|c| c != b'\n') {
                    self.i += 1;
                }
            } else if self.s[self.i..].starts_with(b"/*") {
                let mut depth = 0usize;
                while self.i < self.s.len() {
                    if self.s[self.i..].starts_with(b"/*") {
                        depth += 1;
                        self.i += 2;
                    } else if self.s[self.i..].starts_with(b"*/") {
                        depth -= 1;
                        self.i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        self.i += 1;
                    }
                }
            } else {
                return;
            }
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip();
        if self.peek() == Some(c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    fn ident(&mut self) -> Option<String> {
        let start = self.i;
        if self.s[self.i..].starts_with(b"r#") {
            self.i += 2;
        }
        if !self.peek().is_some_and(|c| c.is_ascii_alphabetic() || c == b'_') {
            self.i = start;
            return None;
        }
        while self.peek().is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_') {
            self.i += 1;
        }
        Some(self.text[start..self.i].to_string())
    }

    fn value(&mut self, depth: usize) -> Option<Node> {
        if depth > MAX_DEPTH {
            return None;
        }
        self.skip();
        match self.peek()? {
            b'"' => self.string().map(Node::Str),
            b'r' if matches!(self.s.get(self.i + 1), Some(b'"' | b'#')) && self.raw_string_ahead() => {
                self.raw_string().map(Node::Str)
            }
            b'\'' => self.char().map(Node::Char),
            b'[' => {
                self.i += 1;
                let items = self.sequence(b']', depth)?;
                Some(Node::List(items))
            }
            b'{' => {
                self.i += 1;
                let mut entries = Vec::new();
                while !self.eat(b'}') {
                    let key = self.value(depth + 1)?;
                    if !self.eat(b':') {
                        return None;
                    }
                    let value = self.value(depth + 1)?;
                    entries.push((key, value));
                    if !self.eat(b',') {
                        if !self.eat(b'}') {
                            return None;
                        }
                        break;
                    }
                }
                Some(Node::Map(entries))
            }
            b'(' => self.parenthesised(None, depth),
            c if c == b'-' || c == b'+' || c == b'.' || c.is_ascii_digit() => self.number(),
            _ => {
                let name = self.ident()?;
                let after = self.i;
                self.skip();
                if self.peek() == Some(b'(') {
                    self.parenthesised(Some(name), depth)
                } else {
                    self.i = after;
                    Some(Node::Ident(name))
                }
            }
        }
    }

    /// Whether `r` starts a raw string (`r"..."`, `r#"..."#`) rather than an identifier.
    fn raw_string_ahead(&self) -> bool {
        let mut j = self.i + 1;
        while self.s.get(j) == Some(&b'#') {
            j += 1;
        }
        self.s.get(j) == Some(&b'"')
    }

    /// Items up to `close`, comma-separated, a trailing comma allowed.
    fn sequence(&mut self, close: u8, depth: usize) -> Option<Vec<Node>> {
        let mut items = Vec::new();
        while !self.eat(close) {
            items.push(self.value(depth + 1)?);
            if !self.eat(b',') {
                if !self.eat(close) {
                    return None;
                }
                break;
            }
        }
        Some(items)
    }

    /// After an optional name, at `(`: a struct when the first item is `ident:`, else a tuple.
    fn parenthesised(&mut self, name: Option<String>, depth: usize) -> Option<Node> {
        self.i += 1; // '('
        self.skip();
        let start = self.i;
        let is_struct = self.ident().is_some() && {
            self.skip();
            self.peek() == Some(b':') && self.s.get(self.i + 1) != Some(&b':')
        };
        self.i = start;
        if !is_struct {
            let items = self.sequence(b')', depth)?;
            return Some(Node::Tuple { name, items });
        }
        let mut fields = Vec::new();
        while !self.eat(b')') {
            self.skip();
            let field = self.ident()?;
            if !self.eat(b':') {
                return None;
            }
            fields.push((field, self.value(depth + 1)?));
            if !self.eat(b',') {
                if !self.eat(b')') {
                    return None;
                }
                break;
            }
        }
        Some(Node::Struct { name, fields })
    }

    fn number(&mut self) -> Option<Node> {
        let start = self.i;
        if matches!(self.peek(), Some(b'-' | b'+')) {
            self.i += 1;
        }
        // `-inf`, `+NaN`
        if self.peek().is_some_and(|c| c.is_ascii_alphabetic()) {
            self.ident()?;
            return Some(Node::Num(self.text[start..self.i].to_string()));
        }
        while let Some(c) = self.peek() {
            let exponent_sign = matches!(c, b'-' | b'+') && matches!(self.s.get(self.i - 1), Some(b'e' | b'E'));
            if c.is_ascii_alphanumeric() || c == b'.' || c == b'_' || exponent_sign {
                self.i += 1;
            } else {
                break;
            }
        }
        (self.i > start).then(|| Node::Num(self.text[start..self.i].to_string()))
    }

    fn string(&mut self) -> Option<String> {
        self.i += 1; // '"'
        let mut out = String::new();
        loop {
            let rest = &self.text[self.i..];
            let c = rest.chars().next()?;
            self.i += c.len_utf8();
            match c {
                '"' => return Some(out),
                '\\' => out.push(self.escape()?),
                c => out.push(c),
            }
        }
    }

    fn escape(&mut self) -> Option<char> {
        let c = self.peek()?;
        self.i += 1;
        Some(match c {
            b'n' => '\n',
            b't' => '\t',
            b'r' => '\r',
            b'0' => '\0',
            b'\\' => '\\',
            b'"' => '"',
            b'\'' => '\'',
            b'x' => {
                let hex = self.text.get(self.i..self.i + 2)?;
                self.i += 2;
                char::from(u8::from_str_radix(hex, 16).ok()?)
            }
            b'u' => {
                if !self.eat(b'{') {
                    return None;
                }
                let end = self.text[self.i..].find('}')? + self.i;
                let code = u32::from_str_radix(&self.text[self.i..end], 16).ok()?;
                self.i = end + 1;
                char::from_u32(code)?
            }
            _ => return None,
        })
    }

    fn raw_string(&mut self) -> Option<String> {
        self.i += 1; // 'r'
        let mut hashes = 0;
        while self.peek() == Some(b'#') {
            hashes += 1;
            self.i += 1;
        }
        self.i += 1; // '"'
        let close = format!("\"{}", "#".repeat(hashes));
        let end = self.text[self.i..].find(&close)? + self.i;
        let out = self.text[self.i..end].to_string();
        self.i = end + close.len();
        Some(out)
    }

    fn char(&mut self) -> Option<char> {
        self.i += 1; // '\''
        let c = self.text[self.i..].chars().next()?;
        self.i += c.len_utf8();
        let c = if c == '\\' { self.escape()? } else { c };
        (self.peek() == Some(b'\'')).then(|| {
            self.i += 1;
            c
        })
    }
}

/// Widest line a container is kept on.
const INLINE_WIDTH: usize = 100;

/// `doc` as RON text, one field or entry per line where a container does not fit on one.
pub fn print(doc: &Document) -> String {
    let mut out = String::new();
    for a in &doc.attributes {
        out.push_str(a);
        out.push('\n');
    }
    write_node(&mut out, &doc.root, 0);
    out.push('\n');
    out
}

/// `node` on one line.
fn inline(node: &Node) -> String {
    let mut out = String::new();
    write_inline(&mut out, node);
    out
}

fn write_inline(out: &mut String, node: &Node) {
    let join = |out: &mut String, items: &mut dyn Iterator<Item = String>| {
        let items: Vec<String> = items.collect();
        out.push_str(&items.join(", "));
    };
    match node {
        Node::Struct { name, fields } => {
            out.push_str(name.as_deref().unwrap_or(""));
            out.push('(');
            join(out, &mut fields.iter().map(|(k, v)| format!("{k}: {}", inline(v))));
            out.push(')');
        }
        Node::Tuple { name, items } => {
            out.push_str(name.as_deref().unwrap_or(""));
            out.push('(');
            join(out, &mut items.iter().map(inline));
            out.push(')');
        }
        Node::List(items) => {
            out.push('[');
            join(out, &mut items.iter().map(inline));
            out.push(']');
        }
        Node::Map(entries) => {
            out.push('{');
            join(out, &mut entries.iter().map(|(k, v)| format!("{}: {}", inline(k), inline(v))));
            out.push('}');
        }
        Node::Str(s) => write_string(out, s),
        Node::Num(n) | Node::Ident(n) => out.push_str(n),
        Node::Char(c) => {
            let _ = write!(out, "'{}'", c.escape_default());
        }
    }
}

fn write_string(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

fn write_node(out: &mut String, node: &Node, indent: usize) {
    let one_line = inline(node);
    if one_line.len() + indent <= INLINE_WIDTH || !is_container(node) {
        out.push_str(&one_line);
        return;
    }
    let pad = " ".repeat(indent + 4);
    let (open, close, name) = match node {
        Node::Struct { name, .. } | Node::Tuple { name, .. } => ('(', ')', name.as_deref().unwrap_or("")),
        Node::List(_) => ('[', ']', ""),
        _ => ('{', '}', ""),
    };
    out.push_str(name);
    out.push(open);
    out.push('\n');
    let line = |out: &mut String, key: Option<String>, value: &Node| {
        out.push_str(&pad);
        if let Some(key) = key {
            out.push_str(&key);
            out.push_str(": ");
        }
        write_node(out, value, indent + 4);
        out.push_str(",\n");
    };
    match node {
        Node::Struct { fields, .. } => fields.iter().for_each(|(k, v)| line(out, Some(k.clone()), v)),
        Node::Tuple { items, .. } | Node::List(items) => items.iter().for_each(|v| line(out, None, v)),
        Node::Map(entries) => entries.iter().for_each(|(k, v)| line(out, Some(inline(k)), v)),
        _ => {}
    }
    out.push_str(&" ".repeat(indent));
    out.push(close);
}

fn is_container(node: &Node) -> bool {
    matches!(node, Node::Struct { .. } | Node::Tuple { .. } | Node::List(_) | Node::Map(_))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_names_identifiers_order_and_duplicates() {
        let text = r##"#![enable(implicit_some)]
// a comment
Graph(name: "g \"x\"\n", /* nested /* comment */ */ resources: {"a": Image(format: D32_SFLOAT, mips: All),
 "a": Buffer(size: "instances * 4"), "b": Image(format: R8_UNORM, size: Fixed(-1, 1e30))},
 passes: [Pass(name: "p", kind: "compute", dispatch: Groups(0x10, 1, +2))], outputs: [], unit: (), c: 'x', raw: r#"a"b"#)"##;
        let doc = parse(text).expect("parses");
        assert_eq!(doc.attributes, ["#![enable(implicit_some)]"]);
        let Node::Struct { name, fields } = &doc.root else { panic!("{doc:?}") };
        assert_eq!(name.as_deref(), Some("Graph"));
        assert_eq!(fields[0], ("name".into(), Node::Str("g \"x\"\n".into())));
        let Node::Map(resources) = &fields[1].1 else { panic!() };
        assert_eq!(resources.len(), 3, "the duplicate key is kept");
        assert_eq!(parse(&print(&doc)), Some(doc.clone()), "{}", print(&doc));
        for bad in ["Graph(", "Graph(name: )", "[1, 2", "{\"a\" 1}", "Graph(a: 1) x", "\"open"] {
            assert_eq!(parse(bad), None, "{bad}");
        }
    }

    /// Printing moves the passes of the printed file itself, so its positions
    /// are not part of the comparison; positions in the graphs it extends are.
    fn without_positions_in_the_printed_file(plan: &str) -> String {
        plan.split(' ')
            .map(|word| if word.starts_with("g.ron:") { "g.ron" } else { word })
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Every shipped graph, printed from its tree, compiles to the same plan.
    #[test]
    fn shipped_graphs_survive_the_round_trip() {
        use cullgraph::graph::{self, FrameInputs, NoDevice};
        let env = NoDevice::new(cullgraph::gpu::ShaderRoot::from_env()).unwrap();
        let kinds = cullgraph::passes::builtin_kinds();
        let plan = |text: &str| {
            let loaded = graph::load_in(text, "g.ron", None, &[], &env, &kinds).map_err(|e| e.to_string())?;
            let plan = graph::compile(&loaded, &FrameInputs::new(64, 48)).map_err(|e| e.to_string())?;
            Ok::<_, String>(without_positions_in_the_printed_file(&plan.to_string()))
        };
        for (name, text) in cullgraph::passes::SHIPPED_GRAPHS.iter().map(|g| (g.name, g.text)) {
            let doc = parse(text).unwrap_or_else(|| panic!("{name} parses"));
            let printed = print(&doc);
            let before = plan(text);
            assert!(before.is_ok(), "{name}: {before:?}");
            assert_eq!(before, plan(&printed), "{name}:\n{printed}");
        }
    }
}
