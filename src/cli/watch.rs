//! Polls files for changes (modification time and size), for `render --watch`.
//!
//! Polling keeps it dependable on every filesystem (containers, network mounts) at the cost of
//! a quarter-second delay, which does not matter for editing a graph by hand.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// A set of files and what they looked like when last checked.
#[derive(Default)]
pub struct FileWatch {
    files: Vec<(PathBuf, Option<(SystemTime, u64)>)>,
}

impl FileWatch {
    /// Watches `paths` (files; a directory means every file below it).
    pub fn new(paths: impl IntoIterator<Item = PathBuf>) -> Self {
        let mut watch = Self::default();
        watch.watch_also(paths);
        watch
    }

    /// Also watches those of `paths` not watched yet, as they are now; the others keep the state
    /// they were last seen in, so that no change made meanwhile is missed.
    pub fn watch_also(&mut self, paths: impl IntoIterator<Item = PathBuf>) {
        let mut files = Vec::new();
        for p in paths {
            collect(&p, &mut files);
        }
        for path in files {
            if !self.files.iter().any(|(p, _)| *p == path) {
                let now = stamp(&path);
                self.files.push((path, now));
            }
        }
        self.files.sort_by(|a, b| a.0.cmp(&b.0));
    }

    /// The files watched.
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.files.iter().map(|(p, _)| p.as_path())
    }

    /// Whether any file changed since the last call (or since creation), and remembers the new state.
    pub fn changed(&mut self) -> bool {
        let mut any = false;
        for (path, seen) in &mut self.files {
            let now = stamp(path);
            if now != *seen {
                *seen = now;
                any = true;
            }
        }
        any
    }
}

fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.modified().ok()?, meta.len()))
}

fn collect(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).into_iter().flatten().flatten() {
            collect(&entry.path(), out);
        }
    } else {
        out.push(path.to_path_buf());
    }
}
