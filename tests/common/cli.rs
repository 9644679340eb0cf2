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

/// Runs `command` like [`run`], but kills it and fails the test when it has not ended within
/// `limit` (what a command that blocks, on a FIFO say, would otherwise do to the suite).
pub fn run_command_within(mut command: Command, limit: std::time::Duration) -> (i32, String, String) {
    use std::io::Read;
    let mut child = command.stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    // Read while it runs, so that a full pipe cannot stall it.
    let readers: Vec<_> =
        [Box::new(child.stdout.take().unwrap()) as Box<dyn Read + Send>, Box::new(child.stderr.take().unwrap())]
            .into_iter()
            .map(|mut stream| {
                std::thread::spawn(move || {
                    let mut text = String::new();
                    let _ = stream.read_to_string(&mut text);
                    text
                })
            })
            .collect();
    let deadline = std::time::Instant::now() + limit;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{command:?} did not end within {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let mut texts = readers.into_iter().map(|r| r.join().unwrap_or_default());
    (status.code().unwrap_or(-1), texts.next().unwrap_or_default(), texts.next().unwrap_or_default())
}

/// Runs `cullgraph args`, failing the test when it takes longer than `seconds`.
pub fn run_within(args: &[&str], seconds: u64) -> (i32, String, String) {
    let mut command = cullgraph();
    command.args(args);
    run_command_within(command, std::time::Duration::from_secs(seconds))
}

/// Runs `cullgraph args` with its address space limited to `kib` KiB (`ulimit -v`): a machine
/// with less memory than this one.
pub fn run_with_memory_limit(args: &[&str], kib: u64) -> (i32, String, String) {
    let mut command = Command::new("sh");
    let cullgraph = cullgraph();
    for (key, value) in cullgraph.get_envs() {
        if let Some(value) = value {
            command.env(key, value);
        }
    }
    command.arg("-c").arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\"")).arg(cullgraph.get_program()).args(args);
    run_command_within(command, std::time::Duration::from_secs(120))
}
