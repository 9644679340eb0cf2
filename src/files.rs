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

/// Most bytes of all the buffers of one glTF scene together, wherever they are (GLB chunk,
/// `data:` URIs, files beside it): what the scene file itself may hold, so that a buffer in a
/// file of its own costs no more than one embedded in the scene.
pub const BUFFERS_LIMIT: u64 = SCENE_LIMIT;

/// The metadata of `path` if it is a regular file whose size says what reading it gives.
/// Refused: directories, FIFOs (opening one would block until a writer comes), devices, and on
/// Linux the files the kernel generates as they are read (`/proc`, `/sys`, ...), which report
/// a size of 0 or 4096 whatever they hold (`/proc/self/pagemap` reads on for terabytes).
fn regular_file(path: &Path, what: &str) -> Result<std::fs::Metadata, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("the {what} is not a regular file (a device, FIFO or directory)"));
    }
    if let Some(fs) = kernel_filesystem(path) {
        return Err(format!("the {what} is not a regular file (a file the kernel generates, on {fs})"));
    }
    Ok(meta)
}

/// The name of the kernel's pseudo filesystem that `path` lies on, if it does.
#[cfg(target_os = "linux")]
fn kernel_filesystem(path: &Path) -> Option<&'static str> {
    // Magic numbers of statfs(2)'s f_type.
    const PSEUDO: [(u64, &str); 11] = [
        (0x9fa0, "proc"),
        (0x6265_6572, "sysfs"),
        (0x6462_6720, "debugfs"),
        (0x7472_6163, "tracefs"),
        (0x7363_6673, "securityfs"),
        (0x0027_e0eb, "cgroup"),
        (0x6367_7270, "cgroup2"),
        (0x6265_6570, "configfs"),
        (0xde5e_81e4, "efivarfs"),
        (0xcafe_4a11, "bpf"),
        (0x6165_676c, "pstore"),
    ];
    // f_type is a signed or unsigned word depending on the platform; the magic fits 32 bits.
    #[allow(clippy::unnecessary_cast)]
    let magic = rustix::fs::statfs(path).ok()?.f_type as u64 & 0xffff_ffff;
    PSEUDO.iter().find(|(m, _)| *m == magic).map(|(_, name)| *name)
}

#[cfg(not(target_os = "linux"))]
fn kernel_filesystem(_path: &Path) -> Option<&'static str> {
    None
}

/// An empty vector with room for `bytes` bytes, or the error that names the file.
fn buffer_for(bytes: u64, what: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    out.try_reserve_exact(bytes as usize).map_err(|_| format!("cannot allocate {bytes} bytes to read the {what}"))?;
    Ok(out)
}

/// The bytes of the regular file at `path`, at most `limit` of them. `what` names the kind of
/// file in the message of a refusal ("graph file", "shader", ...).
pub fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, String> {
    let meta = regular_file(path, what)?;
    if meta.len() > limit {
        return Err(format!("the {what} is {} bytes; a {what} may have at most {limit}", meta.len()));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    let mut bytes = buffer_for(meta.len(), what)?;
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
    let meta = regular_file(path, what)?;
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
/// `byteLength`, which the caller has capped): fewer when the file is shorter, never more, and
/// never more than the file's size said when it was opened.
pub fn read_prefix(path: &Path, length: u64, what: &str) -> Result<Vec<u8>, String> {
    let meta = regular_file(path, what)?;
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the {what}: {e}"))?;
    let wanted = meta.len().min(length);
    let mut bytes = buffer_for(wanted, what)?;
    file.take(wanted).read_to_end(&mut bytes).map_err(|e| format!("cannot read the {what}: {e}"))?;
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
        let err = read_prefix(dir.path(), 16, "buffer file").unwrap_err();
        assert!(err.contains("not a regular file"), "{err}");
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn files_the_kernel_generates_are_refused() {
        for path in ["/proc/self/pagemap", "/proc/self/status", "/sys/kernel/mm/transparent_hugepage/enabled"] {
            if !Path::new(path).exists() {
                continue;
            }
            let err = read_prefix(Path::new(path), 1 << 20, "buffer file").unwrap_err();
            assert!(err.contains("not a regular file") && err.contains("kernel generates"), "{path}: {err}");
            let err = read_limited(Path::new(path), SCENE_LIMIT, "scene file").unwrap_err();
            assert!(err.contains("not a regular file"), "{path}: {err}");
        }
    }

    #[test]
    fn a_prefix_is_no_longer_than_the_file_says_it_is() {
        let dir = tempfile::tempdir().unwrap();
        let sparse = dir.path().join("sparse.bin");
        let file = std::fs::File::create(&sparse).unwrap();
        // 100 GiB of holes: only what is asked for is read, and allocated.
        file.set_len(100 << 30).unwrap();
        assert_eq!(read_prefix(&sparse, 64, "buffer file").unwrap(), vec![0u8; 64]);
        let err = read_limited(&sparse, SCENE_LIMIT, "scene file").unwrap_err();
        assert!(err.contains("107374182400 bytes") && err.contains("at most 2147483648"), "{err}");
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
