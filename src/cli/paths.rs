//! Checks of the paths a user names on the command line, made before any work: an output that
//! cannot be written as a file (a directory, a FIFO that would block the write until a reader
//! comes, a socket) and an input folder that is not one are refused with an error naming the
//! flag, instead of failing after minutes of rendering or blocking forever.

use cullgraph::{Error, Result};
use std::path::Path;

/// Refuses an output file that exists and is not a regular file or a character device (which
/// takes writes at once: `/dev/null`, and `/dev/full`, whose error then names it).
pub fn output_file(flag: &str, path: &Path) -> Result<()> {
    // The metadata, not an open: opening a FIFO for writing blocks until a reader comes.
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(()); // created when written; a missing folder is created then too
    };
    let kind = meta.file_type();
    if kind.is_file() || is_char_device(&kind) {
        return Ok(());
    }
    let what = if kind.is_dir() { "a directory" } else { "not a regular file (a FIFO, socket or block device)" };
    Err(Error::Invalid(format!("{flag} {}: is {what}; name a file to write", path.display())))
}

/// Refuses an output folder that exists and is not a directory.
pub fn output_dir(flag: &str, path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(meta) if !meta.is_dir() => {
            Err(Error::Invalid(format!("{flag} {}: is not a directory; name a folder to write into", path.display())))
        }
        _ => Ok(()),
    }
}

/// Refuses an input folder that does not exist or is not a directory.
pub fn input_dir(flag: &str, path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => Ok(()),
        Ok(_) => Err(Error::Invalid(format!("{flag} {}: is not a directory", path.display()))),
        Err(e) => Err(Error::Invalid(format!("{flag} {}: {e}", path.display()))),
    }
}

#[cfg(unix)]
fn is_char_device(kind: &std::fs::FileType) -> bool {
    std::os::unix::fs::FileTypeExt::is_char_device(kind)
}

#[cfg(not(unix))]
fn is_char_device(_: &std::fs::FileType) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_and_folders_that_cannot_be_used_are_refused_with_the_flag() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f.png");
        assert!(output_file("--out", &file).is_ok(), "a file still to be made");
        std::fs::write(&file, b"x").unwrap();
        assert!(output_file("--out", &file).is_ok());
        assert!(output_file("--out", Path::new("/dev/null")).is_ok());
        let e = output_file("--stats", dir.path()).unwrap_err().to_string();
        assert!(e.starts_with("--stats ") && e.contains("is a directory"), "{e}");
        let e = output_dir("--out", &file).unwrap_err().to_string();
        assert!(e.contains("is not a directory"), "{e}");
        assert!(output_dir("--out", &dir.path().join("new")).is_ok());
        let e = input_dir("--shader-dir", &dir.path().join("missing")).unwrap_err().to_string();
        assert!(e.starts_with("--shader-dir ") && e.contains("No such file"), "{e}");
        let e = input_dir("--shader-dir", Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("/dev/zero: is not a directory"), "{e}");
        let fifo = dir.path().join("pipe");
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            let e = output_file("--out", &fifo).unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
    }
}
