//! `cullgraph fuzz graph|gltf`: mutation fuzzing of the RON graph loader, compiler and passes
//! and of the glTF importer, on stable Rust, for a given time. Most inputs are edits of a seed's
//! parsed structure, the rest edits of its bytes ([`corpus`]).
//!
//! A supervisor runs the inputs in a worker process (this same binary, `--worker`), so that a
//! crash (stack overflow, abort) or a hang is caught and classified like a panic: the worker
//! writes each input to `OUT/current.*` before running it and prints one line per input; when it
//! dies or falls silent the supervisor keeps that input, records the class and starts a new
//! worker at the next input. Inputs are derived from the seed and their number, so a run is
//! reproducible. Every input that breaks a promise (see [`Class::is_failure`]) is saved under
//! `OUT/` with its class in the name; `--replay FILE` runs one saved input again.

mod corpus;
mod mutate_bytes;
mod mutate_gltf;
mod mutate_graph;
mod ron_tree;
mod targets;

use super::args::{FuzzArgs, FuzzTarget};
use corpus::Mutator;
use cullgraph::files;
use rand::rngs::SmallRng;
use rand::SeedableRng;
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

/// Runs one saved input again. It is read as the command reads its kind of input (a regular
/// file, at most the size of a graph or a scene), so a FIFO or `/dev/zero` is refused, not
/// waited on or read without end.
fn replay(bench: &Bench, target: FuzzTarget, file: &Path) -> cullgraph::Result<(Class, String)> {
    let refused = |e: String| cullgraph::Error::Invalid(format!("--replay {}: {e}", file.display()));
    Ok(match target {
        FuzzTarget::Graph => {
            let bytes = files::read_limited(file, files::GRAPH_LIMIT, "graph file").map_err(refused)?;
            let text = String::from_utf8_lossy(&bytes).into_owned();
            let dir = text.lines().last().and_then(|l| l.strip_prefix(SEED_DIR_MARK)).map(PathBuf::from);
            bench.graph(&text, dir.as_deref(), &mut || {})
        }
        FuzzTarget::Gltf => {
            // The importer reads it with the same checks; refusing here keeps the answer an
            // error of the flag rather than an outcome of the input.
            files::check_regular(file, files::SCENE_LIMIT, "scene file").map_err(refused)?;
            bench.gltf(file, &mut || {})
        }
    })
}

/// The worker: runs inputs from `args.start` until the deadline, its lines on stdout:
/// `start CASE MUTATOR WELL_FORMED` before an input, `checked CASE` once it has passed the
/// check (graph) or imported (glTF), `done CASE CLASS<tab>DETAIL` after it.
fn worker(args: &FuzzArgs) -> cullgraph::Result<()> {
    std::panic::set_hook(Box::new(|_| {}));
    let bench = Bench::new()?;
    let out = args.out.clone();
    let current = out.join(format!("current.{}", extension(args.target)));
    let deadline = Instant::now() + Duration::from_secs_f64(args.seconds);
    let (graphs, scenes) = match args.target {
        FuzzTarget::Graph => {
            let passes = |text: &str, dir: Option<&Path>| bench.check(text, dir).is_ok();
            (Some(corpus::GraphCorpus::new(&args.seed_dirs, &passes)?), None)
        }
        FuzzTarget::Gltf => (None, Some(corpus::GltfCorpus::new(&args.seed_dirs)?)),
    };
    let stdout = std::io::stdout();
    let say = |line: String| {
        let mut lock = stdout.lock();
        writeln!(lock, "{line}").ok();
        lock.flush().ok();
    };
    let mut case = args.start;
    while Instant::now() < deadline {
        let mut rng = SmallRng::seed_from_u64(args.seed ^ case.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let input = match (&graphs, &scenes) {
            (Some(graphs), _) => graphs.input(&mut rng),
            (_, Some(scenes)) => scenes.input(&mut rng),
            _ => unreachable!("one corpus per target"),
        };
        std::fs::write(&current, &input.bytes)
            .map_err(|e| cullgraph::Error::Io { path: current.display().to_string(), source: e })?;
        say(format!("start {case} {} {}", input.mutator.name(), u8::from(input.well_formed)));
        let mut checked = || say(format!("checked {case}"));
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match args.target {
            FuzzTarget::Graph => {
                bench.graph(&String::from_utf8_lossy(&input.bytes), input.dir.as_deref(), &mut checked)
            }
            FuzzTarget::Gltf => bench.gltf(&current, &mut checked),
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
        say(format!("done {case} {}\t{detail}", class.name()));
        case += 1;
    }
    Ok(())
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

/// The inputs of one mutator, by how far they got.
#[derive(Default, Clone, Copy)]
struct Reach {
    inputs: u64,
    well_formed: u64,
    passed: u64,
    ok: u64,
    failures: u64,
}

/// The input a worker is running.
#[derive(Clone, Copy)]
struct Running {
    case: u64,
    since: Instant,
    mutator: Mutator,
    well_formed: bool,
    passed: bool,
}

/// What the supervisor has seen.
#[derive(Default)]
struct Tally {
    counts: BTreeMap<Class, u64>,
    examples: BTreeMap<Class, Vec<String>>,
    reach: BTreeMap<Mutator, Reach>,
}

impl Tally {
    /// Counts one outcome of the input `running`; a crash or a hang (the worker is gone,
    /// `current` is its input) is kept here, the others by the worker.
    fn record(&mut self, class: Class, detail: &str, running: &Running, current: &Path, ext: &str, out: &Path) {
        *self.counts.entry(class).or_default() += 1;
        let reach = self.reach.entry(running.mutator).or_default();
        reach.inputs += 1;
        reach.well_formed += u64::from(running.well_formed);
        reach.passed += u64::from(running.passed);
        reach.ok += u64::from(class == Class::Ok);
        reach.failures += u64::from(class.is_failure());
        let examples = self.examples.entry(class).or_default();
        if examples.len() < EXAMPLES_PER_CLASS && !detail.is_empty() {
            examples.push(detail.chars().take(300).collect());
        }
        if matches!(class, Class::Crash | Class::Hang) {
            keep(current, class, running.case, ext, out);
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
    super::paths::output_dir("--out", &args.out)?;
    for dir in &args.seed_dirs {
        super::paths::input_dir("--seeds", dir)?;
    }
    std::fs::create_dir_all(&args.out).map_err(io(&args.out))?;
    let ext = extension(args.target);
    let current = args.out.join(format!("current.{ext}"));
    let started = Instant::now();
    let total = Duration::from_secs_f64(args.seconds);
    let mut tally = Tally::default();
    let mut next = 0u64;
    while started.elapsed() < total {
        let left = (total - started.elapsed()).as_secs_f64();
        let (mut child, lines) = spawn_worker(args, next, left)?;
        let mut running: Option<Running> = None;
        loop {
            match lines.recv_timeout(Duration::from_millis(500)) {
                Ok(line) => {
                    let mut words = line.split(' ');
                    match (words.next(), words.next().and_then(|c| c.parse::<u64>().ok())) {
                        (Some("start"), Some(case)) => {
                            let mutator = words.next().and_then(Mutator::from_name).unwrap_or(Mutator::Bytes);
                            let well_formed = words.next() == Some("1");
                            running =
                                Some(Running { case, since: Instant::now(), mutator, well_formed, passed: false });
                        }
                        (Some("checked"), Some(_)) => {
                            if let Some(r) = running.as_mut() {
                                r.passed = true;
                            }
                        }
                        (Some("done"), Some(case)) => {
                            let rest = line.splitn(3, ' ').nth(2).unwrap_or("");
                            let (class, detail) = rest.split_once('\t').unwrap_or((rest, ""));
                            let class = Class::from_name(class).unwrap_or(Class::Unpositioned);
                            if let Some(r) = running.take() {
                                tally.record(class, detail, &r, &current, ext, &args.out);
                            }
                            next = case + 1;
                        }
                        _ => {}
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Some(r) = running.filter(|r| r.since.elapsed() > HANG_LIMIT) {
                        let _ = child.kill();
                        let _ = child.wait();
                        tally.record(Class::Hang, "no answer in 30 s", &r, &current, ext, &args.out);
                        next = r.case + 1;
                        break;
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    let status = child.wait().ok();
                    if let Some(r) = running {
                        let why = status.map(|s| s.to_string()).unwrap_or_default();
                        tally.record(Class::Crash, &why, &r, &current, ext, &args.out);
                        next = r.case + 1;
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
    for class in Class::ALL.into_iter().filter(|c| *c != Class::CheckLied || args.target == FuzzTarget::Graph) {
        out.push_str(&format!("| {} | {} |\n", class.name(), tally.counts.get(&class).copied().unwrap_or(0)));
    }
    let (form, passed) = match args.target {
        FuzzTarget::Graph => ("well-formed RON", "passed check"),
        FuzzTarget::Gltf => ("well-formed GLB and JSON", "imported"),
    };
    out.push_str(&format!(
        "\n| mutations | inputs | {form} | {passed} | ok | broke a promise |\n|---|---:|---:|---:|---:|---:|\n"
    ));
    let share = |n: u64, of: u64| format!("{n} ({:.1} %)", 100.0 * n as f64 / of.max(1) as f64);
    for (mutator, r) in &tally.reach {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            mutator.name(),
            r.inputs,
            share(r.well_formed, r.inputs),
            share(r.passed, r.inputs),
            share(r.ok, r.inputs),
            r.failures
        ));
    }
    for (class, examples) in tally.examples.iter().filter(|(_, e)| !e.is_empty()) {
        out.push_str(&format!("\n{}:\n", class.name()));
        for e in examples {
            out.push_str(&format!("- {e}\n"));
        }
    }
    out
}
