//! Expressions in graph files: sizes, sample counts, numeric settings and dispatch sizes, e.g.
//! `"ceil_div(instances, 32) * 4"` or `"exposure * 1.5"`.
//!
//! A small hand-written parser rather than `exmex`: exmex evaluates in one number type (so
//! `instances / 32` would be a float, and integer overflow invisible), supports only unary and
//! binary operators (no `ceil_div(a, b)` or `min(a, b, c)` calls), and its errors carry no
//! position. Here errors name the character where they happen, so a graph error points inside
//! the expression string.
//!
//! Grammar: `expr = term (('+'|'-') term)*`, `term = unary (('*'|'/'|'%') unary)*`,
//! `unary = '-' unary | primary`, `primary = number | name | name '(' expr (',' expr)* ')' | '(' expr ')'`.
//!
//! Semantics: whole numbers stay whole (`i64`, overflow is an error) and real numbers are `f64`.
//! `/` and `%` of two whole numbers round toward negative infinity like Python (so sizes divide
//! predictably); any real operand makes the result real. Functions: `ceil_div(a, b)` (whole,
//! rounds up), `min(a, b, ..)`, `max(a, b, ..)`, `floor(x)`, `ceil(x)`, `round(x)` (whole).

use std::collections::BTreeMap;
use std::fmt;

/// A number: whole or real.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Num {
    /// Whole.
    Int(i64),
    /// Real.
    Float(f64),
}

impl Num {
    /// As a real number.
    pub fn as_f64(self) -> f64 {
        match self {
            Num::Int(i) => i as f64,
            Num::Float(f) => f,
        }
    }

    /// As a whole number if it is one (a real must be finite and whole).
    pub fn as_whole(self) -> Option<i64> {
        match self {
            Num::Int(i) => Some(i),
            Num::Float(f) if f.is_finite() && f.fract() == 0.0 && f.abs() < 9.0e15 => Some(f as i64),
            Num::Float(_) => None,
        }
    }
}

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Num::Int(i) => write!(f, "{i}"),
            Num::Float(x) => write!(f, "{x}"),
        }
    }
}

/// An error at a character offset of the expression text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExprError {
    /// Character offset in the expression.
    pub offset: usize,
    /// What is wrong.
    pub message: String,
}

fn err<T>(offset: usize, message: impl Into<String>) -> Result<T, ExprError> {
    Err(ExprError { offset, message: message.into() })
}

#[derive(Clone, Debug, PartialEq)]
enum Node {
    Num(Num),
    Var(String, usize),
    Neg(Box<Node>, usize),
    Bin(char, Box<Node>, Box<Node>, usize),
    Call(String, Vec<Node>, usize),
}

/// A parsed expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    text: String,
    root: Node,
}

const FUNCTIONS: &[&str] = &["ceil", "ceil_div", "floor", "max", "min", "round"];

/// Most tokens of one expression. Bounds the tree, and with it the recursion of evaluating and
/// dropping it: a size in a graph file needs a few dozen.
pub const MAX_TOKENS: usize = 1024;
/// Deepest nesting of parentheses, calls and signs the parser descends into (its recursion).
pub const MAX_NESTING: usize = 64;

impl Expr {
    /// Parses `text`.
    pub fn parse(text: &str) -> Result<Expr, ExprError> {
        let tokens = lex(text)?;
        if let Some(t) = tokens.get(MAX_TOKENS) {
            return err(t.offset, format!("the expression has more than {MAX_TOKENS} tokens"));
        }
        let mut p = Parser { tokens: &tokens, i: 0, end: text.chars().count(), depth: 0 };
        let root = p.expr()?;
        if let Some(t) = p.tokens.get(p.i) {
            return err(t.offset, format!("unexpected '{}'", t.text));
        }
        Ok(Expr { text: text.to_string(), root })
    }

    /// A constant.
    pub fn constant(n: Num) -> Expr {
        Expr { text: n.to_string(), root: Node::Num(n) }
    }

    /// The text it was parsed from.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The constant value, if the expression is a plain number.
    pub fn as_constant(&self) -> Option<Num> {
        match self.root {
            Node::Num(n) => Some(n),
            _ => None,
        }
    }

    /// Every variable it uses, with the offset of each use.
    pub fn variables(&self) -> Vec<(&str, usize)> {
        fn walk<'a>(n: &'a Node, out: &mut Vec<(&'a str, usize)>) {
            match n {
                Node::Num(_) => {}
                Node::Var(v, o) => out.push((v, *o)),
                Node::Neg(a, _) => walk(a, out),
                Node::Bin(_, a, b, _) => {
                    walk(a, out);
                    walk(b, out);
                }
                Node::Call(_, args, _) => args.iter().for_each(|a| walk(a, out)),
            }
        }
        let mut out = Vec::new();
        walk(&self.root, &mut out);
        out
    }

    /// Evaluates with the given variables (a missing one is an error at its use).
    pub fn eval(&self, vars: &BTreeMap<String, Num>) -> Result<Num, ExprError> {
        eval(&self.root, vars)
    }
}

#[derive(Clone, Debug)]
struct Token {
    text: String,
    offset: usize,
}

fn lex(text: &str) -> Result<Vec<Token>, ExprError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit())) {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.' || chars[i] == '_') {
                i += 1;
            }
            if i < chars.len() && matches!(chars[i], 'e' | 'E') {
                let mut j = i + 1;
                if j < chars.len() && matches!(chars[j], '+' | '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            out.push(Token { text: chars[start..i].iter().collect(), offset: start });
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(Token { text: chars[start..i].iter().collect(), offset: start });
        } else if "+-*/%(),".contains(c) {
            out.push(Token { text: c.to_string(), offset: i });
            i += 1;
        } else {
            return err(i, format!("unexpected character '{c}'"));
        }
    }
    Ok(out)
}

struct Parser<'t> {
    tokens: &'t [Token],
    i: usize,
    end: usize,
    /// Current nesting (see [`MAX_NESTING`]).
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&str> {
        self.tokens.get(self.i).map(|t| t.text.as_str())
    }

    fn offset(&self) -> usize {
        self.tokens.get(self.i).map_or(self.end, |t| t.offset)
    }

    fn expr(&mut self) -> Result<Node, ExprError> {
        let mut left = self.term()?;
        while let Some(op @ ("+" | "-")) = self.peek() {
            let op = op.chars().next().unwrap_or('+');
            let at = self.offset();
            self.i += 1;
            let right = self.term()?;
            left = Node::Bin(op, Box::new(left), Box::new(right), at);
        }
        Ok(left)
    }

    fn term(&mut self) -> Result<Node, ExprError> {
        let mut left = self.unary()?;
        while let Some(op @ ("*" | "/" | "%")) = self.peek() {
            let op = op.chars().next().unwrap_or('*');
            let at = self.offset();
            self.i += 1;
            let right = self.unary()?;
            left = Node::Bin(op, Box::new(left), Box::new(right), at);
        }
        Ok(left)
    }

    /// Runs `f` one nesting level deeper, refusing past [`MAX_NESTING`].
    fn nested<T>(&mut self, f: impl FnOnce(&mut Self) -> Result<T, ExprError>) -> Result<T, ExprError> {
        if self.depth >= MAX_NESTING {
            return err(self.offset(), format!("nested more than {MAX_NESTING} levels deep"));
        }
        self.depth += 1;
        let out = f(self);
        self.depth -= 1;
        out
    }

    fn unary(&mut self) -> Result<Node, ExprError> {
        if self.peek() == Some("-") {
            let at = self.offset();
            self.i += 1;
            return Ok(Node::Neg(Box::new(self.nested(Self::unary)?), at));
        }
        if self.peek() == Some("+") {
            self.i += 1;
            return self.nested(Self::unary);
        }
        self.primary()
    }

    fn primary(&mut self) -> Result<Node, ExprError> {
        let at = self.offset();
        let Some(tok) = self.tokens.get(self.i).cloned() else {
            return err(at, "expression ends early");
        };
        self.i += 1;
        let first = tok.text.chars().next().unwrap_or(' ');
        if tok.text == "(" {
            let inner = self.nested(Self::expr)?;
            if self.peek() != Some(")") {
                return err(self.offset(), "missing ')'");
            }
            self.i += 1;
            return Ok(inner);
        }
        if first.is_ascii_digit() || first == '.' {
            return parse_number(&tok.text)
                .map(Node::Num)
                .ok_or_else(|| ExprError { offset: at, message: format!("'{}' is not a number", tok.text) });
        }
        if first.is_alphabetic() || first == '_' {
            if self.peek() == Some("(") {
                if !FUNCTIONS.contains(&tok.text.as_str()) {
                    return err(at, format!("unknown function '{}' (functions: {})", tok.text, FUNCTIONS.join(", ")));
                }
                self.i += 1;
                let mut args = vec![self.nested(Self::expr)?];
                while self.peek() == Some(",") {
                    self.i += 1;
                    args.push(self.nested(Self::expr)?);
                }
                if self.peek() != Some(")") {
                    return err(self.offset(), "missing ')'");
                }
                self.i += 1;
                let expected = match tok.text.as_str() {
                    "ceil_div" => Some(2),
                    "floor" | "ceil" | "round" => Some(1),
                    _ => None,
                };
                match expected {
                    Some(n) if args.len() != n => {
                        return err(at, format!("{}() takes {n} argument(s), got {}", tok.text, args.len()))
                    }
                    None if args.len() < 2 => return err(at, format!("{}() takes at least 2 arguments", tok.text)),
                    _ => {}
                }
                return Ok(Node::Call(tok.text, args, at));
            }
            return Ok(Node::Var(tok.text, at));
        }
        err(at, format!("unexpected '{}'", tok.text))
    }
}

fn parse_number(text: &str) -> Option<Num> {
    let clean: String = text.chars().filter(|&c| c != '_').collect();
    if clean.chars().all(|c| c.is_ascii_digit()) {
        return clean.parse::<i64>().ok().map(Num::Int);
    }
    clean.parse::<f64>().ok().filter(|f| f.is_finite()).map(Num::Float)
}

fn eval(n: &Node, vars: &BTreeMap<String, Num>) -> Result<Num, ExprError> {
    match n {
        Node::Num(v) => Ok(*v),
        Node::Var(name, at) => vars
            .get(name)
            .copied()
            .ok_or_else(|| ExprError { offset: *at, message: format!("unknown variable '{name}'") }),
        Node::Neg(a, at) => match eval(a, vars)? {
            Num::Int(i) => i.checked_neg().map(Num::Int).ok_or_else(|| overflow(*at)),
            Num::Float(f) => Ok(Num::Float(-f)),
        },
        Node::Bin(op, a, b, at) => {
            let (x, y) = (eval(a, vars)?, eval(b, vars)?);
            binary(*op, x, y, *at)
        }
        Node::Call(name, args, at) => {
            let vals = args.iter().map(|a| eval(a, vars)).collect::<Result<Vec<_>, _>>()?;
            call(name, &vals, *at)
        }
    }
}

fn overflow(at: usize) -> ExprError {
    ExprError { offset: at, message: "whole-number overflow".into() }
}

fn binary(op: char, x: Num, y: Num, at: usize) -> Result<Num, ExprError> {
    if let (Num::Int(a), Num::Int(b)) = (x, y) {
        let r = match op {
            '+' => a.checked_add(b),
            '-' => a.checked_sub(b),
            '*' => a.checked_mul(b),
            '/' | '%' if b == 0 => return err(at, "division by zero"),
            '/' => a.checked_div(b).map(|q| if a % b != 0 && (a < 0) != (b < 0) { q - 1 } else { q }),
            _ => a.checked_rem(b).map(|r| if r != 0 && (r < 0) != (b < 0) { r + b } else { r }),
        };
        return r.map(Num::Int).ok_or_else(|| overflow(at));
    }
    let (a, b) = (x.as_f64(), y.as_f64());
    let r = match op {
        '+' => a + b,
        '-' => a - b,
        '*' => a * b,
        '/' | '%' if b == 0.0 => return err(at, "division by zero"),
        '/' => a / b,
        _ => a - b * (a / b).floor(),
    };
    Ok(Num::Float(r))
}

fn call(name: &str, v: &[Num], at: usize) -> Result<Num, ExprError> {
    let whole = |n: Num, what: &str| {
        n.as_whole()
            .ok_or_else(|| ExprError { offset: at, message: format!("{name}() needs whole numbers, {what} is {n}") })
    };
    let round = |f: f64, g: fn(f64) -> f64| {
        let r = g(f);
        if r.is_finite() && r.abs() < 9.0e15 {
            Ok(Num::Int(r as i64))
        } else {
            err(at, format!("{name}() of {f} is out of range"))
        }
    };
    match name {
        "ceil_div" => {
            let (a, b) = (whole(v[0], "the first argument")?, whole(v[1], "the second argument")?);
            if b == 0 {
                return err(at, "division by zero");
            }
            // Round toward positive infinity.
            let q = a.checked_div(b).ok_or_else(|| overflow(at))?;
            let ceil = if a % b != 0 && (a < 0) == (b < 0) { q + 1 } else { q };
            Ok(Num::Int(ceil))
        }
        "floor" => round(v[0].as_f64(), f64::floor),
        "ceil" => round(v[0].as_f64(), f64::ceil),
        "round" => round(v[0].as_f64(), f64::round),
        _ => {
            let pick_max = name == "max";
            let mut best = v[0];
            for &x in &v[1..] {
                let better = match (best, x) {
                    (Num::Int(a), Num::Int(b)) => (b > a) == pick_max && a != b,
                    (a, b) => (b.as_f64() > a.as_f64()) == pick_max && a.as_f64() != b.as_f64(),
                };
                if better {
                    best = x;
                }
            }
            Ok(best)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(text: &str) -> Result<Num, ExprError> {
        let vars: BTreeMap<String, Num> =
            [("instances".to_string(), Num::Int(1001)), ("x".to_string(), Num::Float(0.5))].into_iter().collect();
        Expr::parse(text)?.eval(&vars)
    }

    #[test]
    fn deep_nesting_and_long_expressions_are_refused_at_their_place() {
        // Each would overflow the stack of a recursive parser or evaluator without a bound.
        let nested = |open: &str, close: &str, n: usize| open.repeat(n) + "1" + &close.repeat(n);
        for text in [nested("(", ")", 200), nested("-", "", 200), nested("+", "", 200), nested("max(", ", 1)", 200)] {
            let e = Expr::parse(&text).unwrap_err();
            assert!(e.message.contains("nested more than 64 levels"), "{}", e.message);
            assert!(e.offset > 0 && e.offset <= 5 * MAX_NESTING, "{}", e.offset);
        }
        for text in [nested("(", ")", 100_000), nested("-", "", 100_000), "1".to_string() + &"+1".repeat(100_000)] {
            let e = Expr::parse(&text).unwrap_err();
            assert_eq!((e.offset, e.message.contains("more than 1024 tokens")), (MAX_TOKENS, true), "{}", e.message);
        }
        // Right at the limits, still fine.
        let deep = "(".repeat(MAX_NESTING - 1) + "1" + &")".repeat(MAX_NESTING - 1);
        assert_eq!(ev(&deep), Ok(Num::Int(1)));
        let long = "1".to_string() + &"+1".repeat((MAX_TOKENS - 1) / 2);
        assert_eq!(ev(&long), Ok(Num::Int(1 + (MAX_TOKENS as i64 - 1) / 2)));
    }

    #[test]
    fn evaluates_with_whole_number_semantics() {
        assert_eq!(ev("ceil_div(instances, 32) * 4"), Ok(Num::Int(128)));
        assert_eq!(ev("instances / 2"), Ok(Num::Int(500)));
        assert_eq!(ev("-7 / 2"), Ok(Num::Int(-4)));
        assert_eq!(ev("-7 % 2"), Ok(Num::Int(1)));
        assert_eq!(ev("x * 3"), Ok(Num::Float(1.5)));
        assert_eq!(ev("min(3, 1, 2) + max(1, 2.5)"), Ok(Num::Float(3.5)));
        assert_eq!(ev("ceil(x * 3)"), Ok(Num::Int(2)));
        assert_eq!(ev("2 * (3 + 4)"), Ok(Num::Int(14)));
        assert_eq!(ev("1e3"), Ok(Num::Float(1000.0)));
    }

    #[test]
    fn errors_point_at_characters() {
        assert_eq!(
            ev("instnces + 1").unwrap_err(),
            ExprError { offset: 0, message: "unknown variable 'instnces'".into() }
        );
        assert_eq!(ev("1 +").unwrap_err().offset, 3);
        assert_eq!(ev("(1 + 2").unwrap_err().message, "missing ')'");
        assert_eq!(ev("1 / 0").unwrap_err(), ExprError { offset: 2, message: "division by zero".into() });
        assert_eq!(ev("9223372036854775807 + 1").unwrap_err().message, "whole-number overflow");
        assert_eq!(ev("2 $ 3").unwrap_err(), ExprError { offset: 2, message: "unexpected character '$'".into() });
        assert!(ev("sqrt(4)").unwrap_err().message.starts_with("unknown function 'sqrt'"));
        assert_eq!(ev("ceil_div(1)").unwrap_err().message, "ceil_div() takes 2 argument(s), got 1");
        assert_eq!(ev("1 2").unwrap_err(), ExprError { offset: 2, message: "unexpected '2'".into() });
    }
}
