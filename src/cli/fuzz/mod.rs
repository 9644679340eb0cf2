//! `cullgraph fuzz graph|gltf`: mutation fuzzing of the RON graph loader and compiler and of
//! the glTF importer, on stable Rust, for a given time.
//!
//! A supervisor runs the inputs in a worker process (this same binary, `--worker`), so that a
//! crash (stack overflow, abort) or a hang is caught and classified like a panic: the worker
//! writes each input to `OUT/current.*` before running it and prints one line per input; when it
//! dies or falls silent the supervisor keeps that input, records the class and starts a new
//! worker at the next input. Inputs are derived from the seed and their number, so a run is
//! reproducible. Every input that breaks a promise (see [`Class::is_failure`]) is saved under
//! `OUT/` with its class in the name; `--replay FILE` runs one saved input again.

mod mutate;
mod targets;

use super::args::{FuzzArgs, FuzzTarget};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use targets::{Bench, Class};

/// An input that gives no answer for this long is a hang (the slowest accepted graphs render
/// two frames on lavapipe in about a second).
const HANG_LIMIT: Duration = Duration::from_secs(30);
/// Inputs of each failing class kept on disk, at most.
const KEPT_PER_CLASS: usize = 20;
/// Example messages per class in the report.
const EXAMPLES_PER_CLASS: usize = 3;

/// Runs `cullgraph fuzz`.
pub fn run(args: &FuzzArgs) -> cullgraph::Result<()> {
    if let Some(file) = &args.replay {
        let bench = Bench::new()?;
        let (class, detail) = replay(&bench, args.target, file)?;
        println!("{}: {} {}", file.display(), class.name(), detail);
        return if class.is_failure() { Err(cullgraph::Error::Invalid(class.name().to_string())) } else { Ok(()) };
    }
    if args.worker {
        return worker(args);
    }
    supervise(args)
}

/// The extension of the target's input files.
fn extension(target: FuzzTarget) -> &'static str {
    match target {
        FuzzTarget::Graph => "ron",
        FuzzTarget::Gltf => "glb",
    }
}

/// The directory of the graph an input was derived from, recorded in its last line so that a
/// replay finds the shaders it names.
const SEED_DIR_MARK: &str = "// fuzz seed dir: ";

fn replay(bench: &Bench, target: FuzzTarget, file: &Path) -> cullgraph::Result<(Class, String)> {
    let bytes =
        std::fs::read(file).map_err(|e| cullgraph::Error::Io { path: file.display().to_string(), source: e })?;
    Ok(match target {
        FuzzTarget::Graph => {
            let text = String::from_utf8_lossy(&bytes).into_owned();
            let dir = text.lines().last().and_then(|l| l.strip_prefix(SEED_DIR_MARK)).map(PathBuf::from);
            bench.graph(&text, dir.as_deref())
        }
        FuzzTarget::Gltf => bench.gltf(file),
    })
}

/// The worker: runs inputs from `args.start` until the deadline, one line per input on stdout.
fn worker(args: &FuzzArgs) -> cullgraph::Result<()> {
    std::panic::set_hook(Box::new(|_| {}));
    let bench = Bench::new()?;
    let out = args.out.clone();
    let current = out.join(format!("current.{}", extension(args.target)));
    let deadline = Instant::now() + Duration::from_secs_f64(args.seconds.max(0.0));
    let graph_seeds = targets::graph_seeds(&args.seed_dirs);
    let gltf_seeds = gltf_seeds(&args.seed_dirs);
    let stdout = std::io::stdout();
    let mut case = args.start;
    while Instant::now() < deadline {
        let mut rng = SmallRng::seed_from_u64(args.seed ^ case.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let input = match args.target {
            FuzzTarget::Graph => graph_input(&mut rng, &graph_seeds),
            FuzzTarget::Gltf => gltf_input(&mut rng, &gltf_seeds),
        };
        std::fs::write(&current, &input.0)
            .map_err(|e| cullgraph::Error::Io { path: current.display().to_string(), source: e })?;
        writeln!(stdout.lock(), "start {case}").ok();
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match args.target {
            FuzzTarget::Graph => bench.graph(&String::from_utf8_lossy(&input.0), input.1.as_deref()),
            FuzzTarget::Gltf => bench.gltf(&current),
        }));
        let (class, detail) = outcome.unwrap_or_else(|payload| {
            let message = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            (Class::Panic, message)
        });
        let detail = detail.replace('\n', " | ");
        // Kept here: once the line is out, the next input overwrites `current`.
        if class.is_failure() {
            keep(&current, class, case, extension(args.target), &out);
        }
        writeln!(stdout.lock(), "done {case} {}\t{detail}", class.name()).ok();
        stdout.lock().flush().ok();
        case += 1;
    }
    Ok(())
}

/// A mutated graph and the folder of its seed.
fn graph_input(rng: &mut SmallRng, seeds: &[(String, Option<PathBuf>)]) -> (Vec<u8>, Option<PathBuf>) {
    let (seed, dir) = &seeds[rng.random_range(0..seeds.len())];
    let others: Vec<&str> = seeds.iter().map(|(t, _)| t.as_str()).collect();
    let mut text = mutate::graph_text(rng, seed, &others);
    if let Some(dir) = dir {
        text.push_str(&format!("\n{SEED_DIR_MARK}{}", dir.display()));
    }
    (text.into_bytes(), dir.clone())
}

/// glTF documents to mutate: the built-in one and every `.glb` under the seed folders (their
/// JSON and binary chunk).
fn gltf_seeds(dirs: &[PathBuf]) -> Vec<(serde_json::Value, Vec<u8>)> {
    let mut seeds = vec![targets::gltf_seed()];
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(dir) else { continue };
        for path in entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "glb")) {
            let Ok(bytes) = std::fs::read(&path) else { continue };
            let Ok(glb) = gltf::Glb::from_slice(&bytes) else { continue };
            let Ok(doc) = serde_json::from_slice(&glb.json) else { continue };
            seeds.push((doc, glb.bin.map(|b| b.into_owned()).unwrap_or_default()));
        }
    }
    seeds
}

/// A mutated glTF: the document, the binary chunk, or both.
fn gltf_input(rng: &mut SmallRng, seeds: &[(serde_json::Value, Vec<u8>)]) -> (Vec<u8>, Option<PathBuf>) {
    let (doc, bin) = &seeds[rng.random_range(0..seeds.len())];
    let (mut doc, mut bin) = (doc.clone(), bin.clone());
    match rng.random_range(0..4) {
        0 => mutate::binary(rng, &mut bin),
        1 => {
            mutate::gltf_document(rng, &mut doc);
            mutate::binary(rng, &mut bin);
        }
        _ => mutate::gltf_document(rng, &mut doc),
    }
    let mut file = targets::glb(&doc, &bin);
    if rng.random_range(0..8) == 0 {
        mutate::binary(rng, &mut file); // the container itself
    }
    (file, None)
}

/// Copies `input` (input number `case` of class `class`) to `out` as `CLASS-CASE.EXT`, unless
/// [`KEPT_PER_CLASS`] of its class are there already.
fn keep(input: &Path, class: Class, case: u64, ext: &str, out: &Path) {
    let prefix = format!("{}-", class.name().replace(' ', "-"));
    let kept = std::fs::read_dir(out)
        .map(|d| d.flatten().filter(|e| e.file_name().to_string_lossy().starts_with(&prefix)).count())
        .unwrap_or(0);
    if kept < KEPT_PER_CLASS {
        let _ = std::fs::copy(input, out.join(format!("{prefix}{case}.{ext}")));
    }
}

/// What the supervisor has seen.
#[derive(Default)]
struct Tally {
    counts: BTreeMap<Class, u64>,
    examples: BTreeMap<Class, Vec<String>>,
}

impl Tally {
    /// Counts one outcome; a crash or a hang (the worker is gone, `current` is its input) is
    /// kept here, the others by the worker.
    fn record(&mut self, class: Class, detail: &str, input: &Path, case: u64, ext: &str, out: &Path) {
        *self.counts.entry(class).or_default() += 1;
        let examples = self.examples.entry(class).or_default();
        if examples.len() < EXAMPLES_PER_CLASS && !detail.is_empty() {
            examples.push(detail.chars().take(300).collect());
        }
        if matches!(class, Class::Crash | Class::Hang) {
            keep(input, class, case, ext, out);
        }
    }

    fn total(&self) -> u64 {
        self.counts.values().sum()
    }
}

/// A worker process for inputs from `start`, and its lines.
fn spawn_worker(args: &FuzzArgs, start: u64, seconds: f64) -> cullgraph::Result<(Child, mpsc::Receiver<String>)> {
    let exe = std::env::current_exe().map_err(|e| cullgraph::Error::Invalid(format!("cannot find myself: {e}")))?;
    let mut command = Command::new(exe);
    command.arg("fuzz").arg(args.target.name()).arg("--worker");
    command.args(["--start", &start.to_string(), "--seed", &args.seed.to_string()]);
    command.args(["--seconds", &format!("{seconds}")]).arg("--out").arg(&args.out);
    for dir in &args.seed_dirs {
        command.arg("--seeds").arg(dir);
    }
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| cullgraph::Error::Invalid(format!("cannot start a fuzz worker: {e}")))?;
    let stdout = child.stdout.take().expect("piped");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    Ok((child, rx))
}

/// Runs workers until the time is up and writes the report.
fn supervise(args: &FuzzArgs) -> cullgraph::Result<()> {
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |e| cullgraph::Error::Io { path: path.clone(), source: e }
    };
    std::fs::create_dir_all(&args.out).map_err(io(&args.out))?;
    let ext = extension(args.target);
    let current = args.out.join(format!("current.{ext}"));
    let started = Instant::now();
    let total = Duration::from_secs_f64(args.seconds.max(0.0));
    let mut tally = Tally::default();
    let mut next = 0u64;
    while started.elapsed() < total {
        let left = (total - started.elapsed()).as_secs_f64();
        let (mut child, lines) = spawn_worker(args, next, left)?;
        let mut running: Option<(u64, Instant)> = None;
        loop {
            match lines.recv_timeout(Duration::from_millis(500)) {
                Ok(line) => {
                    if let Some(case) = line.strip_prefix("start ").and_then(|c| c.parse().ok()) {
                        running = Some((case, Instant::now()));
                    } else if let Some(rest) = line.strip_prefix("done ") {
                        let (head, detail) = rest.split_once('\t').unwrap_or((rest, ""));
                        let (case, class) = head.split_once(' ').unwrap_or((head, ""));
                        let case: u64 = case.parse().unwrap_or(next);
                        let class = Class::from_name(class).unwrap_or(Class::Unpositioned);
                        tally.record(class, detail, &current, case, ext, &args.out);
                        running = None;
                        next = case + 1;
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Some((case, since)) = running {
                        if since.elapsed() > HANG_LIMIT {
                            let _ = child.kill();
                            let _ = child.wait();
                            tally.record(Class::Hang, "no answer in 30 s", &current, case, ext, &args.out);
                            next = case + 1;
                            break;
                        }
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    let status = child.wait().ok();
                    if let Some((case, _)) = running {
                        let why = status.map(|s| s.to_string()).unwrap_or_default();
                        tally.record(Class::Crash, &why, &current, case, ext, &args.out);
                        next = case + 1;
                    } else if status.is_some_and(|s| !s.success()) && tally.total() == 0 {
                        return Err(cullgraph::Error::Invalid(
                            "the fuzz worker failed before its first input (no Vulkan device?)".into(),
                        ));
                    }
                    break;
                }
            }
        }
    }
    let _ = std::fs::remove_file(&current);
    let mut report = report(args, &tally, started.elapsed());
    let failures: u64 = tally.counts.iter().filter(|(c, _)| c.is_failure()).map(|(_, n)| n).sum();
    if failures > 0 {
        report.push_str(&format!(
            "\nInputs that broke a promise are kept in {} (at most {KEPT_PER_CLASS} per class); \
             `cullgraph fuzz {} --replay FILE` runs one again.\n",
            args.out.display(),
            args.target.name()
        ));
    }
    print!("{report}");
    let path = args.out.join(format!("report-{}.md", args.target.name()));
    std::fs::write(&path, &report).map_err(io(&path))?;
    if failures > 0 {
        return Err(cullgraph::Error::Invalid(format!(
            "{failures} of {} inputs broke a promise; they are kept in {}",
            tally.total(),
            args.out.display()
        )));
    }
    Ok(())
}

fn report(args: &FuzzArgs, tally: &Tally, took: Duration) -> String {
    let mut out = format!(
        "# cullgraph fuzz {} (seed {}): {} inputs in {:.0} s\n\n| outcome | inputs |\n|---|---:|\n",
        args.target.name(),
        args.seed,
        tally.total(),
        took.as_secs_f64()
    );
    for class in Class::ALL {
        out.push_str(&format!("| {} | {} |\n", class.name(), tally.counts.get(&class).copied().unwrap_or(0)));
    }
    for (class, examples) in tally.examples.iter().filter(|(_, e)| !e.is_empty()) {
        out.push_str(&format!("\n{}:\n", class.name()));
        for e in examples {
            out.push_str(&format!("- {e}\n"));
        }
    }
    out
}
