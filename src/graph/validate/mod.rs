//! Loading a graph file: parse (ron), then check everything a user can get wrong and report all
//! of it at once as `file:line:col: message`, sorted by position. Never panics.
//!
//! The checks, in order (a check is skipped where an earlier error would only cascade, e.g. no
//! "nothing writes it" for a resource whose writing binding was itself wrong):
//! params and `--param` overrides; resources (names, duplicates, formats, sizes, mips, samples,
//! expressions); passes (names, kinds, slots, resources, `.prev`, settings, compute shaders and
//! dispatch); outputs; data flow (reads of what nothing writes, history without a writer,
//! dependency cycles); images (formats each slot accepts, the device's support for each image's
//! usage and sample count, sample counts within a pass).

mod compute;
mod conditional;
mod created;
mod dataflow;
mod images;
mod passes;
mod resources;
mod slot_sizes;

pub(crate) use images::sample_errors;
pub(crate) use slot_sizes::{kind_variables, slot_size_errors};

use super::compose::{Composer, Sources};
use super::env::Environment;
use super::error::{list, GraphError, GraphErrors, Pos, Sink};
use super::expr::{Expr, Num};
use super::kinds::{KindCheck, KindRegistry};
use super::locate::Seg;
use super::schema::{self, Literal, NumLit};
use super::validated::{LocatedExpr, Param, ParamValue, ValidatedGraph};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

/// A `--param name=value` override.
pub type ParamOverride = (String, String);

/// Splits `name=value` (for `--param`).
pub fn parse_param_override(s: &str) -> Result<ParamOverride, String> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.to_string())),
        _ => Err(format!("'{s}' is not name=value")),
    }
}

/// Reads and validates the graph file at `path` with the pass kinds of `kinds`.
pub fn load_file(
    path: &Path,
    overrides: &[ParamOverride],
    env: &dyn Environment,
    kinds: &KindRegistry,
) -> Result<ValidatedGraph, GraphErrors> {
    let file = path.display().to_string();
    let text = crate::files::read_limited_text(path, crate::files::GRAPH_LIMIT, "graph file")
        .map_err(|e| GraphErrors(vec![GraphError::new(&file, Pos::START, e)]))?;
    load(&text, &file, overrides, env, kinds)
}

/// Loads and validates a graph whose passes are of the kinds in `kinds` (the built-in ones are
/// `cullgraph::passes::builtin_kinds()`). `file` names the text in messages and locates
/// relative shader paths (its directory).
pub fn load(
    text: &str,
    file: &str,
    overrides: &[ParamOverride],
    env: &dyn Environment,
    kinds: &KindRegistry,
) -> Result<ValidatedGraph, GraphErrors> {
    let dir = match Path::new(file).parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    load_in(text, file, Some(&dir), overrides, env, kinds)
}

/// The general form: `dir` is the folder that relative shader paths of compute passes resolve
/// against first (`None`: the shader library only).
pub fn load_in(
    text: &str,
    file: &str,
    dir: Option<&Path>,
    overrides: &[ParamOverride],
    env: &dyn Environment,
    kinds: &KindRegistry,
) -> Result<ValidatedGraph, GraphErrors> {
    let (parsed, src, edit_errors) = Composer::new(kinds).compose(text, file, dir)?;
    let files = src.names();
    let mut sink = Sink::new(&files);
    sink.errors.extend(edit_errors);
    let mut v =
        Validator { sink, src, env, kinds, uncertain_writes: HashSet::new(), frame_variables: kinds.variables() };
    let params = v.params(&parsed.params, overrides);
    let scope = Scope::new(&params);
    let (mut resources, mut samples) = v.resources(&parsed, &scope);
    let implicit = v.created_resources(&parsed, &mut resources, &mut samples);
    let mut passes = v.passes(&parsed, &resources, &implicit, &scope);
    compute::settle_write_usages(&mut passes, &resources);
    let (outputs, output_pos) = v.outputs(&parsed, &resources);
    let graph = ValidatedGraph {
        name: parsed.name.clone(),
        file: file.to_string(),
        files,
        params,
        resources,
        passes,
        outputs,
        output_pos,
        kinds: kinds.clone(),
        limits: env.limits(),
    };
    dataflow::check(&mut v, &graph, &parsed);
    conditional::check(&mut v, &graph);
    images::check(&mut v, &graph, &samples);
    for pass in &graph.passes {
        let Some(kind) = kinds.get(&pass.kind) else { continue };
        let check = KindCheck {
            graph: &graph,
            pass,
            samples: &samples,
            resolved: &[],
            planned: None,
            limits: graph.limits.as_ref(),
            quantities: None,
        };
        for (pos, message) in kind.kind.validate(&check) {
            v.err(pos, message);
        }
    }
    v.sink.into_result(graph)
}

/// Which names an expression may use.
pub(crate) struct Scope<'p> {
    params: &'p [Param],
}

/// Whether an expression may use the frame's variables or params only.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Vars {
    /// Params, output size and scene quantities.
    Frame,
    /// Params only (evaluated when loading: sample counts).
    ParamsOnly,
}

impl<'p> Scope<'p> {
    fn new(params: &'p [Param]) -> Self {
        Self { params }
    }

    fn param(&self, name: &str) -> Option<&'p Param> {
        self.params.iter().find(|p| p.name == name)
    }

    fn numeric_params(&self) -> impl Iterator<Item = &'p str> {
        self.params.iter().filter(|p| p.value.as_num().is_some()).map(|p| p.name.as_str())
    }

    /// The values of the params (for evaluating params-only expressions now).
    pub fn param_values(&self) -> BTreeMap<String, Num> {
        self.params.iter().filter_map(|p| Some((p.name.clone(), p.value.as_num()?))).collect()
    }
}

pub(crate) struct Validator<'a> {
    /// The files of the graph and where each part of it was written.
    pub src: Sources,
    pub sink: Sink,
    pub env: &'a dyn Environment,
    pub kinds: &'a KindRegistry,
    /// Resources written by passes whose bindings could not all be resolved: "nothing writes
    /// it" errors would only cascade.
    pub uncertain_writes: HashSet<usize>,
    /// Names every expression may use besides params: the output size and the quantities of
    /// the registry.
    pub frame_variables: Vec<&'static str>,
}

impl Validator<'_> {
    pub fn pos(&self, path: &[Seg<'_>]) -> Pos {
        self.src.pos(path)
    }

    pub fn err(&mut self, pos: Pos, message: impl Into<String>) {
        self.sink.at(pos, message);
    }

    /// Params with their defaults, then overrides applied.
    fn params(&mut self, decl: &schema::Entries<Literal>, overrides: &[ParamOverride]) -> Vec<Param> {
        let mut out: Vec<Param> = Vec::new();
        for (i, (name, lit)) in decl.0.iter().enumerate() {
            let pos = self.pos(&[Seg::Field("params"), Seg::Key(i)]);
            if let Some(first) = out.iter().find(|p| &p.name == name) {
                let first = first.pos;
                self.err(pos, format!("duplicate param '{name}' (first declared at {first})"));
                continue;
            }
            if !is_identifier(name) {
                self.err(
                    pos,
                    format!(
                        "param name '{name}' is not an identifier (letters, digits and '_', not starting with a digit)"
                    ),
                );
            } else if self.frame_variables.contains(&name.as_str()) {
                let reserved = self.frame_variables.join(", ");
                self.err(pos, format!("param name '{name}' is reserved (frame variables: {reserved})"));
            }
            let value = match lit {
                Literal::Bool(b) => ParamValue::Bool(*b),
                Literal::Int(i) => ParamValue::Int(*i),
                Literal::Float(f) => ParamValue::Float(*f),
                Literal::Str(s) => ParamValue::Str(s.clone()),
            };
            if let ParamValue::Float(f) = value {
                if !f.is_finite() {
                    self.err(self.pos(&[Seg::Field("params"), Seg::Value(i)]), format!("param '{name}' is not finite"));
                }
            }
            out.push(Param { name: name.clone(), value, pos });
        }
        apply_overrides(&mut out, overrides, &mut self.sink);
        out
    }

    /// Parses a number or expression at `path`; reports syntax errors and names that `vars`
    /// does not allow. `what` starts the message (`size of buffer 'counts'`).
    pub fn num(
        &mut self,
        lit: &NumLit,
        path: &[Seg<'_>],
        what: &str,
        scope: &Scope<'_>,
        vars: Vars,
    ) -> Option<LocatedExpr> {
        let pos = self.pos(path);
        match lit {
            NumLit::Int(i) => Some(LocatedExpr::constant(Num::Int(*i), pos)),
            NumLit::Float(f) => Some(LocatedExpr::constant(Num::Float(*f), pos)),
            NumLit::Expr(text) => {
                let plain = self.src.pos_in_string(path, 0) != pos;
                let located = |expr: Expr| LocatedExpr { expr, pos, plain };
                let expr = match Expr::parse(text) {
                    Ok(e) => e,
                    Err(e) => {
                        self.err(self.src.pos_in_string(path, e.offset), format!("{what}: {}", e.message));
                        return None;
                    }
                };
                let mut ok = true;
                for (name, offset) in expr.variables() {
                    let at = self.src.pos_in_string(path, offset);
                    let message = match scope.param(name) {
                        Some(p) if p.value.as_num().is_none() => {
                            format!("{what}: param '{name}' is a {}, not a number", p.value.type_name())
                        }
                        Some(_) => continue,
                        None if vars == Vars::Frame && self.frame_variables.contains(&name) => continue,
                        None if vars == Vars::ParamsOnly && self.frame_variables.contains(&name) => {
                            format!(
                                "{what}: only params can be used here, not '{name}' (params: {})",
                                params_list(scope)
                            )
                        }
                        None if vars == Vars::ParamsOnly => {
                            format!("{what}: unknown variable '{name}' (params: {})", params_list(scope))
                        }
                        None => {
                            let all: Vec<&str> =
                                self.frame_variables.iter().copied().chain(scope.numeric_params()).collect();
                            format!("{what}: unknown variable '{name}' (variables: {})", all.join(", "))
                        }
                    };
                    self.err(at, message);
                    ok = false;
                }
                ok.then(|| located(expr))
            }
        }
    }
}

fn params_list(scope: &Scope<'_>) -> String {
    let names: Vec<&str> = scope.numeric_params().collect();
    if names.is_empty() {
        "none declared".into()
    } else {
        names.join(", ")
    }
}

/// Applies `--param` overrides: unknown names are errors at `<command line>:1:1`, values that do
/// not parse as the param's type are errors at the param's declaration.
pub(crate) fn apply_overrides(params: &mut [Param], overrides: &[ParamOverride], sink: &mut Sink) {
    for (name, text) in overrides {
        match params.iter_mut().find(|p| &p.name == name) {
            None => {
                let known = if params.is_empty() {
                    "the graph declares none".to_string()
                } else {
                    list(params.iter().map(|p| p.name.as_str()))
                };
                sink.command_line(format!("--param {name}={text}: unknown param '{name}' (params: {known})"));
            }
            Some(p) => match p.value.parse_like(text) {
                Ok(v) => p.value = v,
                Err(e) => {
                    let ty = p.value.type_name();
                    sink.at(p.pos, format!("--param {name}={text}: {e} (param '{name}' is a {ty})"));
                }
            },
        }
    }
}

/// Letters, digits and `_`, not starting with a digit.
pub(crate) fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_alphabetic() || c == '_') && chars.all(|c| c.is_alphanumeric() || c == '_')
}

/// `true`, `2.5`, `"text"` as written in RON.
pub(crate) fn literal_text(lit: &Literal) -> String {
    match lit {
        Literal::Bool(b) => b.to_string(),
        Literal::Int(i) => i.to_string(),
        Literal::Float(f) => format!("{f:?}"),
        Literal::Str(s) => format!("{s:?}"),
    }
}

/// Sorted, comma-separated resource names (for "unknown resource" errors).
pub(crate) fn resource_list(names: &HashMap<String, usize>) -> String {
    let mut v: Vec<&str> = names.keys().map(|s| s.as_str()).collect();
    v.sort_unstable();
    if v.is_empty() {
        "none declared".into()
    } else {
        v.join(", ")
    }
}
