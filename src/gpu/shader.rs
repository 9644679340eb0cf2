//! Runtime GLSL compilation with shaderc: `#include` of the headers in `shaders/` (bounded in
//! depth and total size, cycles refused), defines, a cache, and compile errors that name the
//! file and line.
//!
//! Shaders come either from the sources embedded at build time (so a binary carried to another
//! machine works on its own) or from a directory on disk (for editing and hot reload).

use std::collections::{BTreeSet, HashMap};
use std::fmt;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/embedded_shaders.rs"));
}

/// Compiled SPIR-V words.
pub type Spirv = Arc<[u32]>;

/// One message of the GLSL compiler.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// File the message is about (an included header where the error is in one).
    pub file: String,
    /// 1-based line, 0 when the compiler gave none.
    pub line: u32,
    /// `error` or `warning`.
    pub severity: String,
    /// The compiler's text.
    pub message: String,
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: {}: {}", self.file, self.line, self.severity, self.message)
        } else {
            write!(f, "{}: {}: {}", self.file, self.severity, self.message)
        }
    }
}

/// Why a shader could not be compiled.
#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    /// The file is neither embedded nor on disk.
    #[error("shader '{0}' not found")]
    NotFound(String),
    /// The extension does not say which stage the file is.
    #[error("shader '{0}': unknown stage; use .comp, .vert or .frag")]
    UnknownStage(String),
    /// GLSL errors, each with file and line.
    #[error("shader '{path}' failed to compile:\n{}", .diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n"))]
    Compile {
        /// The shader that was compiled.
        path: String,
        /// The compiler's messages.
        diagnostics: Vec<Diagnostic>,
    },
    /// shaderc itself failed (initialisation, internal error).
    #[error("shaderc: {0}")]
    Internal(String),
    /// A shader file on disk could not be read.
    #[error("cannot read shader '{path}': {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
}

/// Where shader sources are read from.
#[derive(Clone, Debug)]
pub enum ShaderRoot {
    /// The copies embedded into the binary at build time.
    Embedded,
    /// A directory laid out like `shaders/`; sources are re-read on every compile that misses the cache.
    Directory(PathBuf),
}

impl ShaderRoot {
    /// `CULLGRAPH_SHADER_DIR` if set, otherwise the embedded sources.
    pub fn from_env() -> Self {
        match std::env::var_os("CULLGRAPH_SHADER_DIR") {
            Some(dir) => ShaderRoot::Directory(dir.into()),
            None => ShaderRoot::Embedded,
        }
    }

    /// The source at `rel`; a file read from disk is noted in `read_log`.
    fn read(&self, rel: &str, read_log: &ReadLog) -> Option<String> {
        match self {
            ShaderRoot::Embedded => {
                embedded::EMBEDDED_SHADERS.iter().find(|(p, _)| *p == rel).map(|(_, s)| s.to_string())
            }
            ShaderRoot::Directory(dir) => read_log.read(&dir.join(rel)),
        }
    }
}

/// The files on disk that compiles read (sources and the headers they include), for watchers.
#[derive(Clone, Default)]
struct ReadLog(Arc<Mutex<BTreeSet<PathBuf>>>);

impl ReadLog {
    /// Reads `path`, noting it when it exists.
    fn read(&self, path: &Path) -> Option<String> {
        let text = crate::files::read_limited_text(path, crate::files::SHADER_LIMIT, "shader").ok()?;
        self.0.lock().unwrap_or_else(|p| p.into_inner()).insert(path.to_path_buf());
        Some(text)
    }
}

/// A preprocessor define.
pub type Define = (String, String);

/// Compiles GLSL shaders to SPIR-V for Vulkan 1.3 and caches the results.
pub struct ShaderCompiler {
    compiler: shaderc::Compiler,
    root: ShaderRoot,
    cache: Mutex<HashMap<(String, Vec<Define>), Spirv>>,
    read_log: ReadLog,
    global_defines: Vec<Define>,
}

impl ShaderCompiler {
    /// A compiler reading sources from `root`.
    pub fn new(root: ShaderRoot) -> Result<Self, ShaderError> {
        let compiler = shaderc::Compiler::new().map_err(|e| ShaderError::Internal(e.to_string()))?;
        Ok(Self {
            compiler,
            root,
            cache: Mutex::new(HashMap::new()),
            read_log: ReadLog::default(),
            global_defines: Vec::new(),
        })
    }

    /// A compiler of its own over the same sources with the same global defines (its cache
    /// starts empty), for something that compiles later on its own, such as an observer.
    pub fn try_clone(&self) -> Result<Self, ShaderError> {
        let mut twin = Self::new(self.root.clone())?;
        twin.global_defines = self.global_defines.clone();
        Ok(twin)
    }

    /// Adds `defines` to every shader this compiler compiles from now on (for variants measured
    /// against each other, such as `ALPHA_TEST_ONLY`; see `shaders/common/material_surface.glsl`).
    pub fn with_global_defines(mut self, defines: &[(&str, &str)]) -> Self {
        self.global_defines.extend(defines.iter().map(|(k, v)| (k.to_string(), v.to_string())));
        self.clear_cache();
        self
    }

    /// Every file on disk the compiles so far read: user shaders given by path, the library's
    /// sources when they come from a directory, and every header they included from disk. A
    /// watcher that reloads when one changes sees edits to included headers too.
    pub fn files_read(&self) -> Vec<PathBuf> {
        self.read_log.0.lock().unwrap_or_else(|p| p.into_inner()).iter().cloned().collect()
    }

    /// Where sources come from.
    pub fn root(&self) -> &ShaderRoot {
        &self.root
    }

    /// Forgets every compiled shader (after files changed on disk).
    pub fn clear_cache(&self) {
        self.cache.lock().unwrap_or_else(|p| p.into_inner()).clear();
    }

    /// Compiles the library shader at `path` (relative to `shaders/`, e.g. `lighting/deferred.comp`).
    pub fn compile(&self, path: &str, defines: &[(&str, &str)]) -> Result<Spirv, ShaderError> {
        let rel = normalize(Path::new(path)).ok_or_else(|| ShaderError::NotFound(path.into()))?;
        let source = self.root.read(&rel, &self.read_log).ok_or_else(|| ShaderError::NotFound(path.into()))?;
        self.compile_source(&rel, &source, defines)
    }

    /// Compiles the shader at `path`: the file on disk if there is one (a user shader), otherwise
    /// `path` inside the shader library (e.g. `lighting/lighting.comp`).
    pub fn compile_path(&self, path: &Path, defines: &[(&str, &str)]) -> Result<Spirv, ShaderError> {
        if !path.is_file() {
            return self.compile(&path.to_string_lossy(), defines);
        }
        let source = crate::files::read_limited_text(path, crate::files::SHADER_LIMIT, "shader")
            .map_err(|e| ShaderError::Read { path: path.display().to_string(), source: std::io::Error::other(e) })?;
        self.read_log.0.lock().unwrap_or_else(|p| p.into_inner()).insert(path.to_path_buf());
        self.compile_source(&path.display().to_string(), &source, defines)
    }

    /// Compiles `source`, named `name` (its extension gives the stage); includes resolve relative
    /// to `name`'s directory first (on disk when `name` is a real path), then against the library.
    pub fn compile_source(&self, name: &str, source: &str, defines: &[(&str, &str)]) -> Result<Spirv, ShaderError> {
        let mut defs: Vec<Define> = defines.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        defs.extend(self.global_defines.iter().cloned());
        defs.sort();
        let key = (format!("{name}\0{source}"), defs);
        if let Some(hit) = self.cache.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
            return Ok(hit.clone());
        }
        profiling::scope!("cullgraph::compile_shader", name);
        let kind = stage_of(name).ok_or_else(|| ShaderError::UnknownStage(name.into()))?;
        let internal = |e: shaderc::Error| ShaderError::Internal(e.to_string());
        let mut options = shaderc::CompileOptions::new().map_err(internal)?;
        options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_3 as u32);
        options.set_target_spirv(shaderc::SpirvVersion::V1_6);
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        for (k, v) in &key.1 {
            options.add_macro_definition(k, Some(v));
        }
        let (root, read_log) = (self.root.clone(), self.read_log.clone());
        let includes = std::cell::RefCell::new(IncludeChain::new(name));
        options.set_include_callback(move |requested, kind, from, depth| {
            includes.borrow_mut().include(requested, kind, from, depth, |requested, kind, from| {
                resolve_include(&root, &read_log, requested, kind, from)
            })
        });
        if let Some(line) = source.lines().position(|l| l.contains('\0')) {
            let diagnostic = Diagnostic {
                file: name.into(),
                line: line as u32 + 1,
                severity: "error".into(),
                message: "the source contains a NUL character".into(),
            };
            return Err(ShaderError::Compile { path: name.into(), diagnostics: vec![diagnostic] });
        }
        let result = self.compiler.compile_into_spirv(source, kind, name, "main", Some(&options));
        let artifact = match result {
            Ok(a) => a,
            Err(shaderc::Error::CompilationError(_, text)) => {
                return Err(ShaderError::Compile { path: name.into(), diagnostics: parse_diagnostics(name, &text) })
            }
            Err(e) => return Err(internal(e)),
        };
        let spirv: Spirv = artifact.as_binary().into();
        self.cache.lock().unwrap_or_else(|p| p.into_inner()).insert(key, spirv.clone());
        Ok(spirv)
    }
}

/// Most `#include`s nested in one another (the library's headers nest 4 deep).
pub const MAX_INCLUDE_DEPTH: usize = 32;
/// Most bytes that the `#include`s of one compile bring in together: without a bound, headers
/// that each include the next twice double the text at every level.
pub const MAX_INCLUDED_BYTES: u64 = 4 * crate::files::SHADER_LIMIT;

/// The `#include`s of one compile, so that a file that includes itself (directly or through
/// others), a chain nested too deeply or a total too large ends as an error at the `#include`
/// instead of a preprocessor that never stops and grows without bound. An include cycle is an
/// error even where include guards would end it.
struct IncludeChain {
    /// The files being included, the shader first: `stack[d]` includes `stack[d + 1]`; each as
    /// its name in messages and as a key that is the same for every spelling of its path.
    stack: Vec<(String, String)>,
    /// Bytes brought in so far.
    bytes: u64,
    /// A refusal of a `#include "..."` that shaderc will ask again as `#include <...>`:
    /// (requested, from, message). The retry gives the same answer.
    refused: Option<(String, String, String)>,
}

impl IncludeChain {
    fn new(shader: &str) -> Self {
        Self { stack: vec![(shader.to_string(), include_key(shader))], bytes: 0, refused: None }
    }

    /// Answers shaderc's request for `requested`, included from `from` at nesting `depth` (1
    /// for the shader's own includes), with `resolve` finding the file.
    fn include(
        &mut self,
        requested: &str,
        kind: shaderc::IncludeType,
        from: &str,
        depth: usize,
        resolve: impl FnOnce(&str, shaderc::IncludeType, &str) -> shaderc::IncludeCallbackResult,
    ) -> shaderc::IncludeCallbackResult {
        if let Some((r, f, message)) = self.refused.take() {
            if kind == shaderc::IncludeType::Standard && r == requested && f == from {
                return Err(message);
            }
        }
        let included = resolve(requested, kind, from)?;
        let refusal = self.refusal(&included, depth);
        if let Some(message) = refusal {
            if kind == shaderc::IncludeType::Relative {
                self.refused = Some((requested.to_string(), from.to_string(), message.clone()));
            }
            return Err(message);
        }
        self.stack.push((included.resolved_name.clone(), include_key(&included.resolved_name)));
        Ok(included)
    }

    /// Why `included`, at nesting `depth`, is refused.
    fn refusal(&mut self, included: &shaderc::ResolvedInclude, depth: usize) -> Option<String> {
        if depth > MAX_INCLUDE_DEPTH {
            return Some(format!("includes nest more than {MAX_INCLUDE_DEPTH} deep"));
        }
        // Includes are asked for depth first: the files open now are the first `depth`.
        self.stack.truncate(depth.max(1));
        let key = include_key(&included.resolved_name);
        if let Some(at) = self.stack.iter().position(|(_, k)| *k == key) {
            let mut cycle: Vec<&str> = self.stack[at..].iter().map(|(n, _)| n.as_str()).collect();
            cycle.push(&included.resolved_name);
            return Some(format!("include cycle: {}", cycle.join(" includes ")));
        }
        self.bytes = self.bytes.saturating_add(included.content.len() as u64);
        if self.bytes > MAX_INCLUDED_BYTES {
            return Some(format!(
                "the includes of this shader bring in more than {} MiB together",
                MAX_INCLUDED_BYTES >> 20
            ));
        }
        if included.content.contains('\0') {
            return Some(format!("'{}' contains a NUL character", included.resolved_name));
        }
        None
    }
}

/// The same string for every spelling of one file's path (`a/./b.glsl`, `a/b.glsl`): its
/// canonical path when it is a file on disk, otherwise the name itself (a library path, which
/// is normalized already).
fn include_key(name: &str) -> String {
    std::fs::canonicalize(name).map_or_else(|_| name.to_string(), |p| p.display().to_string())
}

/// The shader stage from the file extension.
fn stage_of(name: &str) -> Option<shaderc::ShaderKind> {
    match Path::new(name).extension()?.to_str()? {
        "comp" => Some(shaderc::ShaderKind::Compute),
        "vert" => Some(shaderc::ShaderKind::Vertex),
        "frag" => Some(shaderc::ShaderKind::Fragment),
        _ => None,
    }
}

fn resolve_include(
    root: &ShaderRoot,
    read_log: &ReadLog,
    requested: &str,
    kind: shaderc::IncludeType,
    from: &str,
) -> shaderc::IncludeCallbackResult {
    let mut candidates: Vec<PathBuf> = Vec::new();
    if kind == shaderc::IncludeType::Relative {
        let dir = Path::new(from).parent().unwrap_or(Path::new(""));
        candidates.push(dir.join(requested));
    }
    candidates.push(PathBuf::from(requested));
    for candidate in &candidates {
        // A real file next to a user shader outside the library (given by a path, relative to the
        // working directory or not).
        if candidate.is_absolute() || Path::new(from).is_absolute() || Path::new(from).is_file() {
            if let Some(content) = read_log.read(candidate) {
                return Ok(shaderc::ResolvedInclude { resolved_name: candidate.display().to_string(), content });
            }
        }
        if let Some(rel) = normalize(candidate) {
            if let Some(content) = root.read(&rel, read_log) {
                return Ok(shaderc::ResolvedInclude { resolved_name: rel, content });
            }
        }
    }
    Err(format!("cannot find '{requested}' (included from '{from}')"))
}

/// `a/./b/../c` → `a/c`; `None` if the path climbs above the root.
fn normalize(path: &Path) -> Option<String> {
    let mut parts: Vec<String> = Vec::new();
    for c in path.components() {
        match c {
            Component::Normal(p) => parts.push(p.to_string_lossy().into_owned()),
            Component::ParentDir => {
                parts.pop()?;
            }
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    (!parts.is_empty()).then(|| parts.join("/"))
}

/// Splits shaderc's text (`file:line: error: message` per line) into diagnostics.
fn parse_diagnostics(name: &str, text: &str) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let parsed = ["error", "warning"].iter().find_map(|sev| {
            let marker = format!(": {sev}: ");
            let at = line.find(&marker)?;
            let (location, message) = (&line[..at], &line[at + marker.len()..]);
            let (file, line_no) = match location.rsplit_once(':') {
                Some((f, l)) if l.chars().all(|c| c.is_ascii_digit()) && !l.is_empty() => (f, l.parse().unwrap_or(0)),
                _ => (location, 0),
            };
            Some(Diagnostic {
                file: file.into(),
                line: line_no,
                severity: sev.to_string(),
                message: message.trim().into(),
            })
        });
        match parsed {
            Some(d) => out.push(d),
            // Summary lines like "2 errors generated." carry nothing new.
            None if line.ends_with("generated.") => {}
            None => out.push(Diagnostic { file: name.into(), line: 0, severity: "error".into(), message: line.into() }),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_shaderc_messages() {
        let text = "cull/a.comp:12: error: 'x' : undeclared identifier\ncommon/h.glsl:3: warning: something\n1 error generated.";
        let d = parse_diagnostics("cull/a.comp", text);
        assert_eq!(d.len(), 2);
        assert_eq!((d[0].file.as_str(), d[0].line, d[0].severity.as_str()), ("cull/a.comp", 12, "error"));
        assert_eq!(d[0].message, "'x' : undeclared identifier");
        assert_eq!((d[1].file.as_str(), d[1].line), ("common/h.glsl", 3));
    }

    /// The error of compiling `main` in a folder holding `files` (name, text).
    fn include_error(files: &[(String, String)], main: &str) -> String {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).unwrap();
        }
        let compiler = ShaderCompiler::new(ShaderRoot::Embedded).unwrap();
        match compiler.compile_path(&dir.path().join(main), &[]) {
            Err(ShaderError::Compile { diagnostics, .. }) => {
                let d = &diagnostics[0];
                format!("{}:{}: {}", Path::new(&d.file).file_name().unwrap().to_string_lossy(), d.line, d.message)
            }
            other => panic!("expected a compile error, got {other:?}"),
        }
    }

    fn file(name: &str, text: &str) -> (String, String) {
        (name.to_string(), text.to_string())
    }

    const MAIN: &str = "layout(local_size_x = 1) in;\nvoid main() {}\n";

    #[test]
    fn include_cycles_are_errors_at_the_include() {
        let own = include_error(&[file("a.comp", &format!("#version 460\n#include \"a.comp\"\n{MAIN}"))], "a.comp");
        assert!(own.starts_with("a.comp:2: '#include' : include cycle: "), "{own}");
        let pair = include_error(
            &[
                file("a.comp", &format!("#version 460\n#include \"b.glsl\"\n{MAIN}")),
                file("b.glsl", "// guards would not help\n#include \"./a.comp\"\n"),
            ],
            "a.comp",
        );
        assert!(pair.starts_with("b.glsl:2: '#include' : include cycle: "), "{pair}");
        assert!(pair.contains("a.comp includes ") && pair.contains("b.glsl includes "), "{pair}");
    }

    #[test]
    fn includes_nest_at_most_max_include_depth_and_bring_in_a_bounded_total() {
        let n = MAX_INCLUDE_DEPTH + 8;
        let mut chain: Vec<(String, String)> =
            (0..n).map(|i| file(&format!("h{i}.glsl"), &format!("#include \"h{}.glsl\"\n", i + 1))).collect();
        chain.push(file(&format!("h{n}.glsl"), ""));
        chain.push(file("main.comp", &format!("#version 460\n#include \"h0.glsl\"\n{MAIN}")));
        let deep = include_error(&chain, "main.comp");
        let last = MAX_INCLUDE_DEPTH - 1;
        let expected = format!(
            "h{last}.glsl:1: '#include' : includes nest more than {MAX_INCLUDE_DEPTH} deep for header name: h{}.glsl",
            last + 1
        );
        assert_eq!(deep, expected);

        // Each header includes the next twice: 2^24 copies of the last one, unless bounded.
        let padding = "// ".to_string() + &"x".repeat(1000) + "\n";
        let mut doubling: Vec<(String, String)> = (0..24)
            .map(|i| {
                file(
                    &format!("d{i}.glsl"),
                    &format!("{padding}#include \"d{j}.glsl\"\n#include \"d{j}.glsl\"\n", j = i + 1),
                )
            })
            .collect();
        doubling.push(file("d24.glsl", &padding));
        doubling.push(file("main.comp", &format!("#version 460\n#include \"d0.glsl\"\n{MAIN}")));
        let wide = include_error(&doubling, "main.comp");
        assert!(wide.contains("the includes of this shader bring in more than 16 MiB together"), "{wide}");
    }

    #[test]
    fn a_nul_character_is_an_error_not_a_panic() {
        let compiler = ShaderCompiler::new(ShaderRoot::Embedded).unwrap();
        let err = compiler.compile_source("t.comp", "#version 460\nvoid main() {}\0\n", &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "shader 't.comp' failed to compile:\nt.comp:2: error: the source contains a NUL character"
        );
        let header = include_error(
            &[file("h.glsl", "int x;\0"), file("m.comp", &format!("#version 460\n#include \"h.glsl\"\n{MAIN}"))],
            "m.comp",
        );
        assert!(
            header.starts_with("m.comp:2: '#include' : ") && header.contains("contains a NUL character"),
            "{header}"
        );
    }

    #[test]
    fn normalizes_paths() {
        assert_eq!(normalize(Path::new("a/./b/../c.glsl")).as_deref(), Some("a/c.glsl"));
        assert_eq!(normalize(Path::new("../x")), None);
    }
}
