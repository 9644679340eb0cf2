//! Reading the files a user names (graphs, shaders, scenes and their buffers) with a limit that
//! fits what each is for: a special file (`/dev/zero`, a FIFO) or a huge one is refused with a
//! clear error instead of being read into unbounded memory or blocking forever.

use std::io::Read;
use std::path::Path;

/// Most bytes of a RON render graph.
pub const GRAPH_LIMIT: u64 = 16 << 20;
/// Most bytes of a shader source file (or a header it includes).
pub const SHADER_LIMIT: u64 = 4 << 20;
/// Most bytes of a glTF or GLB scene file (its JSON and, for GLB, its binary chunk).
pub const SCENE_LIMIT: u64 = 2 << 30;

/// The bytes of the regular file at `path`, at most `limit` of them. `what` names the kind of
/// file in the message of a refusal ("graph file", "shader", ...).
pub fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, String> {
    let len = check_regular(path, limit, what)?;
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(len as usize).map_err(|_| format!("no memory to read the {what} ({len} bytes)"))?;
    // A file that grows while it is read still stops at the limit.
    file.take(limit + 1).read_to_end(&mut bytes).map_err(|e| format!("cannot read the {what}: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(format!("the {what} grew past {limit} bytes while it was read"));
    }
    Ok(bytes)
}

/// The size of the regular file at `path`, refused (without opening it) when it is something
/// else or larger than `limit`: [`read_limited`]'s checks, for a caller that reads the file
/// itself.
pub fn check_regular(path: &Path, limit: u64, what: &str) -> Result<u64, String> {
    // The metadata first: opening a FIFO would block until a writer comes.
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("the {what} is not a regular file (a device, FIFO or directory)"));
    }
    if meta.len() > limit {
        return Err(format!("the {what} is {} bytes; a {what} may have at most {limit}", meta.len()));
    }
    Ok(meta.len())
}

/// Like [`read_limited`], as UTF-8 text.
pub fn read_limited_text(path: &Path, limit: u64, what: &str) -> Result<String, String> {
    String::from_utf8(read_limited(path, limit, what)?).map_err(|e| format!("the {what} is not UTF-8 text: {e}"))
}

/// The first `length` bytes of the regular file at `path` (a glTF buffer read up to its
/// `byteLength`): fewer when the file is shorter, never more.
pub fn read_prefix(path: &Path, length: u64, what: &str) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("the {what} is not a regular file (a device, FIFO or directory)"));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    let mut bytes = Vec::with_capacity(meta.len().min(length) as usize);
    file.take(length).read_to_end(&mut bytes).map_err(|e| format!("cannot read the {what}: {e}"))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_and_oversized_files_are_refused() {
        let err = read_limited(Path::new("/dev/zero"), GRAPH_LIMIT, "graph file").unwrap_err();
        assert!(err.contains("not a regular file"), "{err}");
        let err = read_prefix(Path::new("/dev/urandom"), 16, "buffer").unwrap_err();
        assert!(err.contains("not a regular file"), "{err}");
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.ron");
        std::fs::write(&big, vec![b' '; 2000]).unwrap();
        let err = read_limited(&big, 1000, "graph file").unwrap_err();
        assert!(err.contains("2000 bytes") && err.contains("at most 1000"), "{err}");
        assert_eq!(read_limited(&big, 2000, "graph file").unwrap().len(), 2000);
        assert_eq!(read_prefix(&big, 10, "buffer").unwrap().len(), 10);
        let err = read_limited(&dir.path().join("missing"), 10, "shader").unwrap_err();
        assert!(err.contains("cannot read the shader"), "{err}");
    }

    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            return; // no mkfifo here: the regular-file check above covers the rule
        }
        let err = read_limited(&fifo, GRAPH_LIMIT, "graph file").unwrap_err();
        assert!(err.contains("not a regular file"), "{err}");
    }
}
