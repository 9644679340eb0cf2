//! The `cullgraph` binary as the command-line tests run it: on the test device, with the
//! validation layer on (a command that hears a validation message fails).

use std::process::Command;

/// `cullgraph` on lavapipe (or `CULLGRAPH_TEST_DEVICE`), validation on.
pub fn cullgraph() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_cullgraph"));
    cmd.env("CULLGRAPH_DEVICE", std::env::var("CULLGRAPH_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()));
    cmd.env("CULLGRAPH_VALIDATION", "1");
    cmd
}

/// Runs `cullgraph args`: (exit status, stdout, stderr).
pub fn run(args: &[&str]) -> (i32, String, String) {
    let out = cullgraph().args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}
