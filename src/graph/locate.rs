//! Positions of things in a RON file, for errors found after parsing.
//!
//! ron gives positions for its own errors (syntax, unknown fields and variants) but none for the
//! values it returns, and it has no `Spanned<T>`. This module tokenizes the same text and builds a
//! light tree of its structure (structs, tuples, lists, maps, scalars, each with the position of
//! its first token), so that validation can ask for the place of, e.g., `passes[2].reads` entry 1's
//! value or `resources` entry 4's key. The walker is lenient: it accepts everything ron accepts
//! (comments, nested block comments, raw strings, extensions attributes, `Some(..)`), and if the
//! text is broken somewhere it keeps what it built so far (ron reports the syntax error itself).

use super::error::Pos;

/// A token's kind.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    /// Identifier (including `true`, `false`, `inf`, raw `r#name`).
    Ident(String),
    /// A string literal's decoded contents; `plain` when it had no escapes and one line, so that
    /// columns inside it map to columns in the file.
    Str { value: String, plain: bool },
    /// Number, char or byte-string literal (text as written).
    Other(String),
    /// One of `( ) [ ] { } , : # ! .`.
    Punct(char),
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    pos: Pos,
}

fn tokenize(text: &str) -> Vec<Token> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, 1u32, 1u32);
    // Advances over `n` characters, keeping line/col.
    let advance = |i: &mut usize, line: &mut u32, col: &mut u32, n: usize| {
        for _ in 0..n {
            if *i < chars.len() {
                if chars[*i] == '\n' {
                    *line += 1;
                    *col = 1;
                } else {
                    *col += 1;
                }
                *i += 1;
            }
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let pos = Pos { file: 0, line, col };
        let peek = |k: usize| chars.get(i + k).copied();
        if c.is_whitespace() {
            advance(&mut i, &mut line, &mut col, 1);
        } else if c == '/' && peek(1) == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                advance(&mut i, &mut line, &mut col, 1);
            }
        } else if c == '/' && peek(1) == Some('*') {
            let mut depth = 0usize;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    advance(&mut i, &mut line, &mut col, 2);
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    advance(&mut i, &mut line, &mut col, 2);
                    if depth == 0 {
                        break;
                    }
                } else {
                    advance(&mut i, &mut line, &mut col, 1);
                }
            }
        } else if c == '"' || ((c == 'r' || c == 'b') && is_raw_or_byte_string(&chars, i)) {
            let (value, plain, len) = read_string(&chars, i);
            out.push(Token { tok: Tok::Str { value, plain }, pos });
            advance(&mut i, &mut line, &mut col, len);
        } else if c == '\'' {
            // A char literal: 'x', '\n', '\u{..}', '\''.
            let mut j = i + 1;
            while j < chars.len() && chars[j] != '\'' {
                j += if chars[j] == '\\' { 2 } else { 1 };
            }
            let len = (j + 1).min(chars.len()) - i;
            out.push(Token { tok: Tok::Other(chars[i..i + len].iter().collect()), pos });
            advance(&mut i, &mut line, &mut col, len);
        } else if c == 'r' && peek(1) == Some('#') && peek(2).is_some_and(is_ident_start) {
            let mut j = i + 2;
            while j < chars.len() && is_ident_char(chars[j]) {
                j += 1;
            }
            out.push(Token { tok: Tok::Ident(chars[i + 2..j].iter().collect()), pos });
            let n = j - i;
            advance(&mut i, &mut line, &mut col, n);
        } else if is_ident_start(c) {
            let mut j = i;
            while j < chars.len() && is_ident_char(chars[j]) {
                j += 1;
            }
            out.push(Token { tok: Tok::Ident(chars[i..j].iter().collect()), pos });
            let n = j - i;
            advance(&mut i, &mut line, &mut col, n);
        } else if c.is_ascii_digit()
            || ((c == '+' || c == '-' || c == '.') && peek(1).is_some_and(|d| d.is_ascii_digit()))
        {
            let mut j = i + 1;
            while j < chars.len() {
                let d = chars[j];
                let exp_sign = (d == '+' || d == '-') && matches!(chars[j - 1], 'e' | 'E') && !is_hex(&chars[i..j]);
                if d.is_ascii_alphanumeric() || d == '_' || d == '.' || exp_sign {
                    // `..` starts a range, not a fraction.
                    if d == '.' && chars.get(j + 1) == Some(&'.') {
                        break;
                    }
                    j += 1;
                } else {
                    break;
                }
            }
            out.push(Token { tok: Tok::Other(chars[i..j].iter().collect()), pos });
            let n = j - i;
            advance(&mut i, &mut line, &mut col, n);
        } else {
            out.push(Token { tok: Tok::Punct(c), pos });
            advance(&mut i, &mut line, &mut col, 1);
        }
    }
    out
}

fn is_hex(s: &[char]) -> bool {
    s.len() >= 2 && s[0] == '0' && matches!(s[1], 'x' | 'X')
}

fn is_ident_start(c: char) -> bool {
    c.is_alphabetic() || c == '_'
}

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

fn is_raw_or_byte_string(chars: &[char], i: usize) -> bool {
    let mut j = i;
    if chars.get(j) == Some(&'b') {
        j += 1;
    }
    if chars.get(j) == Some(&'r') {
        j += 1;
        while chars.get(j) == Some(&'#') {
            j += 1;
        }
    }
    j > i && chars.get(j) == Some(&'"')
}

/// Reads a (raw, byte) string starting at `i`; returns its contents, whether columns map
/// one-to-one, and its length in characters.
fn read_string(chars: &[char], i: usize) -> (String, bool, usize) {
    let mut j = i;
    if chars[j] == 'b' {
        j += 1;
    }
    let raw = chars.get(j) == Some(&'r');
    let mut hashes = 0;
    if raw {
        j += 1;
        while chars.get(j) == Some(&'#') {
            hashes += 1;
            j += 1;
        }
    }
    j += 1; // opening quote
    let prefix = j - i;
    let mut value = String::new();
    let mut plain = prefix == 1;
    while let Some(&c) = chars.get(j) {
        if c == '"' && (!raw || chars[j + 1..].iter().take(hashes).filter(|&&h| h == '#').count() == hashes) {
            j += 1 + if raw { hashes } else { 0 };
            break;
        }
        if c == '\n' {
            plain = false;
        }
        if c == '\\' && !raw {
            plain = false;
            let next = chars.get(j + 1).copied().unwrap_or('\\');
            value.push(match next {
                'n' => '\n',
                't' => '\t',
                'r' => '\r',
                '0' => '\0',
                other => other,
            });
            j += 2;
            continue;
        }
        value.push(c);
        j += 1;
    }
    (value, plain, j.min(chars.len()) - i)
}

/// A value in the RON text with the position of its first token.
#[derive(Clone, Debug)]
pub struct Node {
    /// Where the value starts (its name, for named structs and tuples).
    pub pos: Pos,
    /// What it is.
    pub kind: NodeKind,
}

/// The shape of a [`Node`].
#[derive(Clone, Debug)]
pub enum NodeKind {
    /// `Name(field: value, ..)` or `(field: value, ..)`.
    Struct {
        /// The name, if written.
        name: Option<String>,
        /// Fields in order: name, position of the name, value.
        fields: Vec<(String, Pos, Node)>,
    },
    /// `Name(a, b)` or `(a, b)`.
    Tuple {
        /// The name, if written.
        name: Option<String>,
        /// Elements.
        items: Vec<Node>,
    },
    /// `[a, b]`.
    List(Vec<Node>),
    /// `{k: v, ..}`.
    Map(Vec<(Node, Node)>),
    /// A string literal.
    Str {
        /// Whether a character offset inside the contents maps to `pos.col + 1 + offset`.
        plain: bool,
    },
    /// Identifier, number, char, unit `()`.
    Scalar(String),
}

/// One step of a path into the tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seg<'a> {
    /// The value of a struct field.
    Field(&'a str),
    /// The name of a struct field.
    FieldName(&'a str),
    /// Element of a list or tuple.
    Index(usize),
    /// The key of a map's n-th entry (in file order).
    Key(usize),
    /// The value of a map's n-th entry (in file order).
    Value(usize),
}

/// The structure of a RON text, for looking up positions.
#[derive(Clone, Debug)]
pub struct Locator {
    root: Option<Node>,
}

impl Locator {
    /// Parses `text` leniently.
    pub fn new(text: &str) -> Self {
        let tokens = tokenize(text);
        let mut p = Parser { tokens: &tokens, i: 0 };
        p.skip_attributes();
        let root = p.value();
        Self { root }
    }

    /// The node at `path`, if all of it exists.
    pub fn node(&self, path: &[Seg<'_>]) -> Option<&Node> {
        let mut node = self.root.as_ref()?;
        for seg in path {
            node = step(node, *seg)?.1;
        }
        Some(node)
    }

    /// The position of `path`; where part of it is missing (a defaulted field), the position of
    /// the deepest part that exists.
    pub fn pos(&self, path: &[Seg<'_>]) -> Pos {
        let Some(mut node) = self.root.as_ref() else { return Pos::START };
        let mut pos = node.pos;
        for seg in path {
            match step(node, *seg) {
                Some((p, n)) => {
                    pos = p;
                    node = n;
                }
                None => break,
            }
        }
        pos
    }

    /// The position of character `offset` inside the string at `path` (the string's own position
    /// when its contents do not map to columns one-to-one).
    pub fn pos_in_string(&self, path: &[Seg<'_>], offset: usize) -> Pos {
        match self.node(path) {
            Some(Node { pos, kind: NodeKind::Str { plain: true, .. } }) => pos.right(1 + offset),
            _ => self.pos(path),
        }
    }

    /// The identifier written at `path` (e.g. an enum unit variant), if it is one.
    pub fn ident(&self, path: &[Seg<'_>]) -> Option<&str> {
        match &self.node(path)?.kind {
            NodeKind::Scalar(s) => Some(s),
            NodeKind::Struct { name: Some(n), .. } | NodeKind::Tuple { name: Some(n), .. } => Some(n),
            _ => None,
        }
    }
}

/// Unwraps `Some(x)` (ron's explicit option syntax) so paths work with and without it.
fn unwrap_some(node: &Node) -> &Node {
    match &node.kind {
        NodeKind::Tuple { name: Some(n), items } if n == "Some" && items.len() == 1 => &items[0],
        _ => node,
    }
}

fn step<'n>(node: &'n Node, seg: Seg<'_>) -> Option<(Pos, &'n Node)> {
    let node = unwrap_some(node);
    match (&node.kind, seg) {
        (NodeKind::Struct { fields, .. }, Seg::Field(f)) => {
            fields.iter().rev().find(|(n, _, _)| n == f).map(|(_, _, v)| (unwrap_some(v).pos, unwrap_some(v)))
        }
        (NodeKind::Struct { fields, .. }, Seg::FieldName(f)) => {
            fields.iter().rev().find(|(n, _, _)| n == f).map(|(_, p, v)| (*p, v))
        }
        (NodeKind::Tuple { items, .. } | NodeKind::List(items), Seg::Index(i)) => items.get(i).map(|n| (n.pos, n)),
        (NodeKind::Map(entries), Seg::Key(i)) => entries.get(i).map(|(k, _)| (k.pos, k)),
        (NodeKind::Map(entries), Seg::Value(i)) => entries.get(i).map(|(_, v)| (v.pos, v)),
        _ => None,
    }
}

struct Parser<'t> {
    tokens: &'t [Token],
    i: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.i)
    }

    fn peek_at(&self, k: usize) -> Option<&Token> {
        self.tokens.get(self.i + k)
    }

    fn is_punct(&self, k: usize, c: char) -> bool {
        matches!(self.peek_at(k), Some(Token { tok: Tok::Punct(p), .. }) if *p == c)
    }

    fn eat_punct(&mut self, c: char) -> bool {
        if self.is_punct(0, c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    /// Skips `#![enable(..)]` attributes.
    fn skip_attributes(&mut self) {
        while self.is_punct(0, '#') {
            while let Some(t) = self.peek() {
                let end = t.tok == Tok::Punct(']');
                self.i += 1;
                if end {
                    break;
                }
            }
        }
    }

    fn value(&mut self) -> Option<Node> {
        let t = self.peek()?.clone();
        match &t.tok {
            Tok::Ident(name) => {
                self.i += 1;
                if self.is_punct(0, '(') {
                    self.i += 1;
                    Some(self.parens(t.pos, Some(name.clone())))
                } else {
                    Some(Node { pos: t.pos, kind: NodeKind::Scalar(name.clone()) })
                }
            }
            Tok::Str { plain, .. } => {
                self.i += 1;
                Some(Node { pos: t.pos, kind: NodeKind::Str { plain: *plain } })
            }
            Tok::Other(s) => {
                self.i += 1;
                Some(Node { pos: t.pos, kind: NodeKind::Scalar(s.clone()) })
            }
            Tok::Punct('(') => {
                self.i += 1;
                Some(self.parens(t.pos, None))
            }
            Tok::Punct('[') => {
                self.i += 1;
                let mut items = Vec::new();
                while !self.eat_punct(']') {
                    let Some(v) = self.value() else { break };
                    items.push(v);
                    if !self.eat_punct(',') && !self.is_punct(0, ']') {
                        break;
                    }
                }
                Some(Node { pos: t.pos, kind: NodeKind::List(items) })
            }
            Tok::Punct('{') => {
                self.i += 1;
                let mut entries = Vec::new();
                while !self.eat_punct('}') {
                    let Some(k) = self.value() else { break };
                    if !self.eat_punct(':') {
                        break;
                    }
                    let Some(v) = self.value() else { break };
                    entries.push((k, v));
                    if !self.eat_punct(',') && !self.is_punct(0, '}') {
                        break;
                    }
                }
                Some(Node { pos: t.pos, kind: NodeKind::Map(entries) })
            }
            Tok::Punct('.') => {
                // A range such as `..5`: keep it as one scalar.
                self.i += 1;
                let mut text = String::from(".");
                while let Some(Token { tok: Tok::Punct('.') | Tok::Punct('='), .. }) = self.peek() {
                    self.i += 1;
                    text.push('.');
                }
                if let Some(Token { tok: Tok::Other(s), .. }) = self.peek() {
                    text.push_str(s);
                    self.i += 1;
                }
                Some(Node { pos: t.pos, kind: NodeKind::Scalar(text) })
            }
            Tok::Punct(_) => None,
        }
    }

    /// After an opening `(`: struct fields, tuple elements or unit `()`.
    fn parens(&mut self, pos: Pos, name: Option<String>) -> Node {
        let is_struct = matches!(self.peek(), Some(Token { tok: Tok::Ident(_), .. })) && self.is_punct(1, ':');
        if is_struct {
            let mut fields = Vec::new();
            while !self.eat_punct(')') {
                let Some(Token { tok: Tok::Ident(f), pos: fpos }) = self.peek().cloned() else { break };
                self.i += 1;
                if !self.eat_punct(':') {
                    break;
                }
                let Some(v) = self.value() else { break };
                fields.push((f, fpos, v));
                if !self.eat_punct(',') && !self.is_punct(0, ')') {
                    break;
                }
            }
            Node { pos, kind: NodeKind::Struct { name, fields } }
        } else {
            let mut items = Vec::new();
            while !self.eat_punct(')') {
                let Some(v) = self.value() else { break };
                items.push(v);
                if !self.eat_punct(',') && !self.is_punct(0, ')') {
                    break;
                }
            }
            Node { pos, kind: NodeKind::Tuple { name, items } }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"#![enable(implicit_some)]
// comment
Graph(
    name: "x", /* block /* nested */ */
    resources: {
        "a": Image(format: D32_SFLOAT, size: Scaled(0.5)),
        "b": Imported(Image(format: R8_UNORM)),
    },
    passes: [
        Pass(name: "p", reads: {"in": "a.prev"}, shader: Some("s.comp"), dispatch: Threads("x * 2", 1, -1e-3)),
    ],
)"#;

    #[test]
    fn finds_positions_of_fields_entries_and_elements() {
        let loc = Locator::new(TEXT);
        let p = |path: &[Seg]| loc.pos(path).to_string();
        assert_eq!(p(&[]), "3:1");
        assert_eq!(p(&[Seg::Field("name")]), "4:11");
        assert_eq!(p(&[Seg::FieldName("resources")]), "5:5");
        assert_eq!(p(&[Seg::Field("resources"), Seg::Key(1)]), "7:9");
        assert_eq!(p(&[Seg::Field("resources"), Seg::Value(0), Seg::Field("size"), Seg::Index(0)]), "6:53");
        assert_eq!(p(&[Seg::Field("resources"), Seg::Value(1), Seg::Index(0), Seg::Field("format")]), "7:37");
        let pass = [Seg::Field("passes"), Seg::Index(0)];
        assert_eq!(p(&[pass[0], pass[1], Seg::Field("reads"), Seg::Value(0)]), "10:39");
        assert_eq!(p(&[pass[0], pass[1], Seg::Field("shader")]), "10:63");
        assert_eq!(p(&[pass[0], pass[1], Seg::Field("dispatch"), Seg::Index(2)]), "10:104");
        // Missing parts fall back to the deepest existing one.
        assert_eq!(p(&[pass[0], pass[1], Seg::Field("writes")]), "10:9");
        let dispatch0 = [pass[0], pass[1], Seg::Field("dispatch"), Seg::Index(0)];
        assert_eq!(loc.pos_in_string(&dispatch0, 4).to_string(), "10:97");
        assert_eq!(loc.ident(&[Seg::Field("resources"), Seg::Value(0), Seg::Field("format")]), Some("D32_SFLOAT"));
    }
}
