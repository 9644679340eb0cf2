//! Byte-level mutations, the share of the fuzzers' inputs that tests the parsers themselves:
//! text edits of RON graphs (deletions, duplications, tokens that break or stretch the grammar,
//! splices from other seeds) and corrupted or truncated bytes (a GLB's JSON, binary chunk or
//! container).

use rand::rngs::SmallRng;
use rand::Rng;

/// Tokens that are likely to reach a new branch of the loader or the compiler when inserted
/// anywhere in a graph.
const GRAPH_TOKENS: &[&str] = &[
    "\"",
    ",",
    "(",
    ")",
    "{",
    "}",
    "[",
    "]",
    ":",
    ".prev",
    "history: true, ",
    "-1",
    "0",
    "1e400",
    "1e30",
    "4294967296",
    "-2147483649",
    "NaN",
    "inf",
    "\"x\"",
    "//",
    "/*",
    "*/",
    "r#\"",
    "\u{e9}",
    "\n",
    "samples: 3, ",
    "samples: 8, ",
    "mips: All, ",
    "mips: 99, ",
    "size: Fixed(0, 0), ",
    "size: Fixed(16384, 16384), ",
    "size: Scaled(1e-9), ",
    "size: Scaled(100), ",
    "\"width * height * 4096\"",
    "\"instances * 1e12\"",
    "\"ceil_div(width, 0)\"",
    "\"max(1, \"",
    "((((((((",
    "----------",
    "Image(format: R8_UNORM)",
    "Image(format: D32_SFLOAT, samples: 4)",
    "Buffer(size: 4)",
    "Buffer(size: 1099511627776)",
    "Imported(Buffer(size: 16))",
    "Imported(Image(format: R8G8B8A8_UNORM))",
    "kind: \"compute\", ",
    "kind: \"overlay\", ",
    "kind: \"hiz_build\", ",
    "kind: \"instance_cull\", ",
    "shader: \"/dev/zero\", ",
    "shader: \"../../../../etc/passwd\", ",
    "dispatch: PerPixel(\"color\"), ",
    "dispatch: Threads(65536, 1, 1), ",
    "dispatch: Groups(0, 0, 0), ",
    "\"stats\": \"color\", ",
    "\"depth\": \"color\", ",
    "\"output\": \"depth\", ",
    "D32_SFLOAT_S8_UINT",
    "R32G32B32A32_SFLOAT",
    "R8G8B8_UNORM",
    "BC1_RGB_UNORM_BLOCK",
];

/// A mutated copy of `seed`, with one to three edits; `others` are spliced from. Half of the
/// edits keep the syntax (a number or a quoted string replaced), so that most inputs reach
/// validation and compiling rather than stopping at the parser.
pub fn graph_text(rng: &mut SmallRng, seed: &str, others: &[&str]) -> String {
    let mut text: Vec<char> = seed.chars().collect();
    for _ in 0..rng.random_range(1..=3) {
        let at = rng.random_range(0..=text.len());
        match rng.random_range(0..12) {
            6..=8 => replace_string(rng, &mut text, others),
            9..=11 => replace_number(rng, &mut text, at),
            0 => {
                let end = (at + rng.random_range(1..40)).min(text.len());
                text.drain(at..end);
            }
            1 => {
                let token = GRAPH_TOKENS[rng.random_range(0..GRAPH_TOKENS.len())];
                text.splice(at..at, token.chars());
            }
            2 => {
                let end = (at + rng.random_range(1..200)).min(text.len());
                let copy: Vec<char> = text[at..end].to_vec();
                let to = rng.random_range(0..=text.len());
                text.splice(to..to, copy);
            }
            3 => replace_number(rng, &mut text, at),
            4 if !others.is_empty() => {
                let other: Vec<char> = others[rng.random_range(0..others.len())].chars().collect();
                let from = rng.random_range(0..=other.len());
                let end = (from + rng.random_range(1..300)).min(other.len());
                text.splice(at..at, other[from..end].iter().copied());
            }
            _ => {
                // Swap two lines.
                let lines: Vec<String> = text.iter().collect::<String>().lines().map(str::to_string).collect();
                if lines.len() > 2 {
                    let (a, b) = (rng.random_range(0..lines.len()), rng.random_range(0..lines.len()));
                    let mut lines = lines;
                    lines.swap(a, b);
                    text = lines.join("\n").chars().collect();
                }
            }
        }
    }
    text.into_iter().collect()
}

/// Replaces one quoted string of `text` with another taken from `others` (resource, pass, slot,
/// kind, format and param names of all seeds) or an odd one.
fn replace_string(rng: &mut SmallRng, text: &mut Vec<char>, others: &[&str]) {
    let quotes: Vec<usize> = (0..text.len()).filter(|&i| text[i] == '"').collect();
    if quotes.len() < 2 {
        return;
    }
    let pair = rng.random_range(0..quotes.len() / 2) * 2;
    let (start, end) = (quotes[pair] + 1, quotes[pair + 1]);
    let replacement: String = match rng.random_range(0..6) {
        0 => ["", " ", "x.prev", "a.b.c", "\\u{0}", "builtin:none"][rng.random_range(0..6)].to_string(),
        _ => {
            let other = others[rng.random_range(0..others.len())];
            let strings: Vec<&str> = other.split('"').skip(1).step_by(2).filter(|s| s.len() < 80).collect();
            if strings.is_empty() {
                return;
            }
            strings[rng.random_range(0..strings.len())].to_string()
        }
    };
    text.splice(start..end, replacement.chars());
}

/// Numbers that sit on an edge: zero, negative, not whole, beyond 32 bits, not finite.
const EDGE_NUMBERS: &[&str] =
    &["0", "-1", "0.5", "1e-40", "1e30", "1e308", "4294967295", "4294967296", "9223372036854775808", "65535", "65536"];

/// Replaces the number at or after `at` (if any) with an edge value.
fn replace_number(rng: &mut SmallRng, text: &mut Vec<char>, at: usize) {
    let Some(start) = (at..text.len()).find(|&i| text[i].is_ascii_digit()) else { return };
    let end = (start..text.len()).find(|&i| !(text[i].is_ascii_digit() || text[i] == '.')).unwrap_or(text.len());
    let value = EDGE_NUMBERS[rng.random_range(0..EDGE_NUMBERS.len())];
    text.splice(start..end, value.chars());
}

/// Corrupts `bin`: a few bytes set to random values, or the tail cut.
pub fn binary(rng: &mut SmallRng, bin: &mut Vec<u8>) {
    if bin.is_empty() {
        return;
    }
    if rng.random_range(0..4) == 0 {
        let keep = rng.random_range(0..bin.len());
        bin.truncate(keep);
        return;
    }
    for _ in 0..rng.random_range(1..8) {
        let i = rng.random_range(0..bin.len());
        bin[i] = rng.random();
    }
}
