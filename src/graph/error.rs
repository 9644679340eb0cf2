//! Errors of loading and compiling a graph: each names a place as `file:line:col` (1-based line
//! and column, counted in characters, of the offending token's first character), and loading
//! reports every error it finds at once, sorted by position.

use std::fmt;

/// A place in a RON file: the file among those a graph was composed from (0: the one loaded),
/// 1-based line and column (in characters).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Pos {
    /// The file, an index into the graph's files.
    pub file: u32,
    /// Line, from 1.
    pub line: u32,
    /// Column in characters, from 1.
    pub col: u32,
}

impl Pos {
    /// Line 1, column 1 of the file loaded (or of the command line).
    pub const START: Pos = Pos { file: 0, line: 1, col: 1 };

    /// Line `line`, column `col` (each at least 1) of the file loaded.
    pub fn at(line: usize, col: usize) -> Pos {
        Pos { file: 0, line: line.clamp(1, u32::MAX as usize) as u32, col: col.clamp(1, u32::MAX as usize) as u32 }
    }

    /// The same line and column in file `file`.
    pub fn in_file(self, file: usize) -> Pos {
        Pos { file: file as u32, ..self }
    }

    /// The position `n` characters to the right on the same line.
    pub fn right(self, n: usize) -> Pos {
        Pos { col: self.col.saturating_add(n as u32), ..self }
    }
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

/// File name used for errors that come from `--param` overrides of unknown params.
pub const COMMAND_LINE: &str = "<command line>";

/// One problem in a graph, at a place.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GraphError {
    /// The file (as given to the loader), or [`COMMAND_LINE`].
    pub file: String,
    /// 1-based line.
    pub line: u32,
    /// 1-based column (characters).
    pub col: u32,
    /// What is wrong, in words (continuation lines, e.g. shader compiler output, are indented).
    pub message: String,
}

impl GraphError {
    /// An error at `pos` of `file`.
    pub fn new(file: &str, pos: Pos, message: impl Into<String>) -> Self {
        Self { file: file.to_string(), line: pos.line, col: pos.col, message: message.into() }
    }

    /// The line and column.
    pub fn pos(&self) -> Pos {
        Pos { file: 0, line: self.line, col: self.col }
    }
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.file, self.line, self.col, self.message)
    }
}

impl std::error::Error for GraphError {}

/// Every error found in one load or compile, sorted by position.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GraphErrors(pub Vec<GraphError>);

impl GraphErrors {
    /// Sorts by (file order of first appearance is kept) line and column; equal positions keep
    /// the order they were found in.
    pub fn sorted(mut errors: Vec<GraphError>) -> Self {
        errors.sort_by_key(|e| (e.file == COMMAND_LINE, e.line, e.col));
        errors.dedup();
        GraphErrors(errors)
    }

    /// Number of errors.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The errors.
    pub fn iter(&self) -> std::slice::Iter<'_, GraphError> {
        self.0.iter()
    }
}

impl fmt::Display for GraphErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for GraphErrors {}

impl From<GraphErrors> for crate::Error {
    fn from(e: GraphErrors) -> Self {
        crate::Error::Invalid(e.to_string())
    }
}

/// Collects errors of one graph, composed from `files`.
#[derive(Debug)]
pub(crate) struct Sink {
    pub files: Vec<String>,
    pub errors: Vec<GraphError>,
}

impl Sink {
    pub fn new(files: &[String]) -> Self {
        Self { files: files.to_vec(), errors: Vec::new() }
    }

    /// Records an error at `pos`.
    pub fn at(&mut self, pos: Pos, message: impl Into<String>) {
        let file = file_of(&self.files, pos);
        self.errors.push(GraphError::new(file, pos, message));
    }

    /// Records an error that has no place in the file.
    pub fn command_line(&mut self, message: impl Into<String>) {
        self.errors.push(GraphError::new(COMMAND_LINE, Pos::START, message));
    }

    pub fn into_result<T>(self, value: T) -> Result<T, GraphErrors> {
        if self.errors.is_empty() {
            Ok(value)
        } else {
            Err(GraphErrors::sorted(self.errors))
        }
    }
}

/// The name of the file of `pos` among `files`.
pub(crate) fn file_of(files: &[String], pos: Pos) -> &str {
    files.get(pos.file as usize).or(files.first()).map_or("", String::as_str)
}

/// Names from `candidates` close to `name` (edit distance at most a third of the longer name,
/// at least 1), closest first, at most `max`.
pub fn close_names<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>, max: usize) -> Vec<&'a str> {
    let lower = name.to_ascii_lowercase();
    let mut scored: Vec<(usize, &str)> = candidates
        .into_iter()
        .map(|c| (edit_distance(&lower, &c.to_ascii_lowercase()), c))
        .filter(|(d, c)| *d <= (c.chars().count().max(name.chars().count()) / 3).max(1))
        .collect();
    scored.sort();
    scored.into_iter().take(max).map(|(_, c)| c).collect()
}

/// Levenshtein distance in characters.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.chars().enumerate() {
        cur[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// `a, b, c` (the names as given).
pub fn list(names: impl IntoIterator<Item = impl AsRef<str>>) -> String {
    names.into_iter().map(|n| n.as_ref().to_string()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_and_close_names() {
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(close_names("albdo", ["albedo", "normal", "depth"], 3), vec!["albedo"]);
    }
}
