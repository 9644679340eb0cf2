//! Bad graphs: every file under `tests/graphs/bad/` starts with one or more lines
//! `// expect: LINE:COL: MESSAGE` (and optionally `// params: name=value, ...` for `--param`
//! overrides, and `// compile: WIDTHxHEIGHT` to compile after loading, for an empty scene).
//! Loading (and compiling) the file must give exactly those errors, in that order. CPU only:
//! format support and limits come from a fake device, shaders are compiled with shaderc and
//! reflected.
//!
//! `GRAPH_BLESS=1 cargo test --test graph_errors` rewrites the expectations from the actual
//! errors (review the diff!).

use ash::vk;
use cullgraph::gpu::reflect::ShaderInterface;
use cullgraph::gpu::ShaderRoot;
use cullgraph::graph::{self, Environment, GraphErrors, NoDevice};
use cullgraph::passes::builtin_kinds;
use std::path::{Path, PathBuf};

/// A device that cannot use sRGB formats as storage images, has no 8x MSAA and no
/// `D24_UNORM_S8_UINT`, like some real ones; it binds at most 128 MiB of storage buffer (as
/// lavapipe) and 64 KiB of uniform buffer, makes images and render areas of at most 8192, and
/// runs workgroups of at most 1024x512x64 and 1024 threads with 32 KiB of shared memory.
struct FakeDevice {
    shaders: NoDevice,
}

impl FakeDevice {
    fn new() -> Self {
        Self { shaders: NoDevice::new(ShaderRoot::Embedded).expect("shaderc") }
    }
}

impl Environment for FakeDevice {
    fn check_image_format(
        &self,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: vk::SampleCountFlags,
    ) -> Result<(), String> {
        if format == vk::Format::D24_UNORM_S8_UINT {
            return Err("the format is not supported".into());
        }
        let srgb = matches!(format, vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_SRGB);
        if srgb && usage.contains(vk::ImageUsageFlags::STORAGE) {
            return Err("STORAGE is not supported for sRGB formats".into());
        }
        if samples == vk::SampleCountFlags::TYPE_8 {
            return Err("8 samples are not supported".into());
        }
        Ok(())
    }

    fn shader_interface(&self, path: &Path) -> Result<ShaderInterface, String> {
        self.shaders.shader_interface(path)
    }

    fn limits(&self) -> Option<graph::DeviceLimits> {
        Some(graph::DeviceLimits {
            device: "the fake device".into(),
            max_storage_buffer_range: 1 << 27,
            max_uniform_buffer_range: 1 << 16,
            max_image_dimension_2d: 8192,
            max_framebuffer: vk::Extent2D { width: 8192, height: 8192 },
            features: ["post_depth_coverage", "subgroup_compute"].map(String::from).to_vec(),
            compute: graph::ComputeLimits {
                max_shared_memory_bytes: 32768,
                max_work_group_size: [1024, 512, 64],
                max_work_group_invocations: 1024,
            },
        })
    }
}

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/graphs/bad")
}

struct Case {
    expected: Vec<String>,
    params: Vec<(String, String)>,
    compile: Option<String>,
    header_lines: usize,
}

fn header(text: &str) -> Case {
    let mut case = Case { expected: Vec::new(), params: Vec::new(), compile: None, header_lines: 0 };
    for line in text.lines() {
        if let Some(e) = line.strip_prefix("// expect: ") {
            case.expected.push(e.to_string());
        } else if let Some(p) = line.strip_prefix("// params: ") {
            case.params =
                p.split(", ").map(|kv| graph::parse_param_override(kv).expect("params line is name=value")).collect();
        } else if let Some(size) = line.strip_prefix("// compile: ") {
            case.compile = Some(size.to_string());
        } else {
            break;
        }
        case.header_lines += 1;
    }
    case
}

fn actual(text: &str, path: &Path, case: &Case) -> Result<(), GraphErrors> {
    let env = FakeDevice::new();
    let loaded = graph::load(text, &path.display().to_string(), &case.params, &env, &builtin_kinds())?;
    if let Some(size) = &case.compile {
        let (w, h) = size.split_once('x').expect("compile line is WIDTHxHEIGHT");
        let frame = graph::FrameInputs::new(w.parse().expect("width"), h.parse().expect("height"));
        graph::compile(&loaded, &frame)?;
    }
    Ok(())
}

#[test]
fn every_bad_graph_reports_its_exact_errors() {
    let bless = std::env::var_os("GRAPH_BLESS").is_some();
    let mut files: Vec<PathBuf> = std::fs::read_dir(bad_dir())
        .expect("tests/graphs/bad")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    files.sort();
    assert!(files.len() >= 35, "expected at least 35 bad graphs, found {}", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("read bad graph");
        let case = header(&text);
        let file = path.display().to_string();
        let root = format!("{}/", env!("CARGO_MANIFEST_DIR"));
        let got: Vec<String> = match actual(&text, path, &case) {
            Ok(()) => Vec::new(),
            Err(errors) => errors
                .iter()
                .map(|e| {
                    let line =
                        if e.file == file { format!("{}:{}: {}", e.line, e.col, e.message) } else { e.to_string() };
                    line.replace(&root, "").replace('\n', "\\n")
                })
                .collect(),
        };
        if bless {
            let rest: Vec<&str> = text.lines().skip(case.header_lines).collect();
            let mut out: Vec<String> = got.iter().map(|g| format!("// expect: {g}")).collect();
            if !case.params.is_empty() {
                let p: Vec<String> = case.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
                out.push(format!("// params: {}", p.join(", ")));
            }
            if let Some(size) = &case.compile {
                out.push(format!("// compile: {size}"));
            }
            out.extend(rest.iter().map(|s| s.to_string()));
            std::fs::write(path, out.join("\n") + "\n").expect("bless");
            continue;
        }
        if got != case.expected {
            failures.push(format!(
                "{}:\n  expected:\n    {}\n  got:\n    {}",
                path.display(),
                case.expected.join("\n    "),
                got.join("\n    ")
            ));
        }
        if case.expected.is_empty() {
            failures.push(format!("{}: has no `// expect:` line", path.display()));
        }
    }
    assert!(failures.is_empty(), "{} of {} bad graphs differ:\n{}", failures.len(), files.len(), failures.join("\n"));
}

mod never_panics {
    use super::FakeDevice;
    use cullgraph::graph::{self, FrameInputs};
    use proptest::prelude::*;
    use std::path::Path;

    fn seeds() -> Vec<(String, String)> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        [
            "graph/default.ron",
            "graph/no_cull.ron",
            "graph/examples/tint.ron",
            "graph/examples/history.ron",
            "tests/graphs/bad/cycle.ron",
        ]
        .iter()
        .map(|p| {
            let path = root.join(p);
            (path.display().to_string(), std::fs::read_to_string(&path).expect("seed graph"))
        })
        .collect()
    }

    /// One edit: delete a range, insert a snippet, or duplicate a line.
    fn edit(text: &str, kind: u8, at: usize, len: usize, snippet: usize) -> String {
        const SNIPPETS: &[&str] = &[
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
            "1e400",
            "\"x\"",
            "0",
            "Image(format: R8_UNORM)",
            "\"width * \"",
            "//",
            "/*",
            "r#\"",
            "\u{e9}",
            "\n",
            "samples: 3, ",
        ];
        let chars: Vec<char> = text.chars().collect();
        let at = at % (chars.len() + 1);
        match kind % 3 {
            0 => {
                let end = (at + len % 12).min(chars.len());
                chars[..at].iter().chain(&chars[end..]).collect()
            }
            1 => {
                let mut s: String = chars[..at].iter().collect();
                s.push_str(SNIPPETS[snippet % SNIPPETS.len()]);
                s.extend(&chars[at..]);
                s
            }
            _ => {
                let lines: Vec<&str> = text.lines().collect();
                let i = at % lines.len().max(1);
                let mut out: Vec<&str> = lines.clone();
                if let Some(l) = lines.get(i) {
                    out.insert(i, l);
                }
                out.join("\n")
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// Mutated graph files load (or fail with positioned errors) and compile without panics.
        #[test]
        fn mutated_graphs_never_panic(
            seed in 0usize..4,
            edits in prop::collection::vec((any::<u8>(), any::<usize>(), any::<usize>(), any::<usize>()), 1..4),
        ) {
            let seeds = seeds();
            let (file, mut text) = seeds[seed % seeds.len()].clone();
            for (kind, at, len, snippet) in edits {
                text = edit(&text, kind, at, len, snippet);
            }
            let env = FakeDevice::new();
            match graph::load(&text, &file, &[], &env, &cullgraph::passes::builtin_kinds()) {
                Ok(g) => {
                    let _ = graph::compile(&g, &FrameInputs::new(64, 48)).map(|c| (c.to_string(), graph::to_dot(&c)));
                }
                Err(errors) => {
                    prop_assert!(!errors.is_empty());
                    for e in errors.iter() {
                        prop_assert!(e.line >= 1 && e.col >= 1, "{}", e);
                    }
                    let _ = errors.to_string();
                }
            }
        }
    }
}
