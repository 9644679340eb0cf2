//! Pass declarations: names, kinds, slots and the resources bound to them, settings, and the
//! shader/dispatch fields that only compute passes take.

use super::created::ImplicitBinding;
use super::slot_sizes::too_small;
use super::{literal_text, resource_list, Scope, Validator, Vars};
use crate::graph::error::{close_names, list};
use crate::graph::expr::Expr;
use crate::graph::kinds::{Bytes, PassKindInfo, SettingDefault, COMPUTE_KIND};
use crate::graph::locate::Seg;
use crate::graph::plan::{SettingValue, Version};
use crate::graph::schema::{GraphFile, Literal, PassDecl};
use crate::graph::validated::ParamValue;
use crate::graph::validated::{Pass, PassBinding, PassSetting, Resource, ResourceDesc, SettingSource};
use std::collections::{BTreeMap, HashMap};

/// A `reads`/`writes` entry after its resource was looked up.
pub(super) struct Entry<'d> {
    /// Slot as written.
    pub slot: &'d str,
    /// Index in its map.
    pub index: usize,
    /// In `writes`?
    pub in_writes: bool,
    /// The resource and version, if the name resolved.
    pub target: Option<(usize, Version)>,
}

impl Entry<'_> {
    pub fn map(&self) -> &'static str {
        if self.in_writes {
            "writes"
        } else {
            "reads"
        }
    }
}

impl Validator<'_> {
    /// A binding was dropped because of an error: its resource may be written in the intended
    /// graph, so "written by no pass" would only cascade.
    pub(super) fn drop_binding(&mut self, target: Option<(usize, Version)>) {
        if let Some((r, _)) = target {
            self.uncertain_writes.insert(r);
        }
    }

    pub(super) fn passes(
        &mut self,
        file: &GraphFile,
        resources: &[Resource],
        implicit: &[Vec<ImplicitBinding>],
        scope: &Scope<'_>,
    ) -> Vec<Pass> {
        let names: HashMap<String, usize> = resources.iter().enumerate().map(|(i, r)| (r.name.clone(), i)).collect();
        let mut out: Vec<Pass> = Vec::new();
        for (i, decl) in file.passes.iter().enumerate() {
            let path = [Seg::Field("passes"), Seg::Index(i)];
            let name_pos = self.pos(&[path[0], path[1], Seg::Field("name")]);
            if decl.name.trim().is_empty() {
                self.err(name_pos, "pass name must not be empty");
            } else if let Some(first) = out.iter().find(|p| p.name == decl.name) {
                let first = first.pos;
                self.err(name_pos, format!("duplicate pass name '{}' (first declared at {first})", decl.name));
            }
            let kind = self.kinds.info(&decl.kind);
            if kind.is_none() {
                let mut known: Vec<&str> = self.kinds.infos().map(|k| k.name).collect();
                known.sort_unstable();
                self.err(
                    self.pos(&[path[0], path[1], Seg::Field("kind")]),
                    format!("unknown pass kind '{}' in pass '{}' (kinds: {})", decl.kind, decl.name, known.join(", ")),
                );
            }
            let entries = self.entries(i, decl, &names, resources);
            if kind.is_none() {
                for e in entries.iter().filter(|e| e.in_writes) {
                    if let Some((r, _)) = e.target {
                        self.uncertain_writes.insert(r);
                    }
                }
            }
            let mut pass = Pass {
                name: decl.name.clone(),
                pos: name_pos,
                kind: decl.kind.clone(),
                bindings: Vec::new(),
                settings: Vec::new(),
                shader: None,
                dispatch: None,
                dispatch_pos: self.pos(&[path[0], path[1], Seg::Field("dispatch")]),
                local_size: [1, 1, 1],
            };
            if let Some(kind) = kind {
                if kind.slots_from_shader {
                    self.compute_pass(i, decl, &mut pass, &entries, resources, &names, scope);
                } else {
                    self.fixed_pass_fields(i, decl, kind);
                    self.kind_bindings(i, decl, kind, &mut pass, &entries, resources);
                    for b in implicit.get(i).into_iter().flatten() {
                        let Some(slot) = kind.slot(b.slot) else { continue };
                        pass.bindings.push(PassBinding {
                            slot: slot.name.to_string(),
                            written_slot: slot.name.to_string(),
                            resource: b.resource,
                            version: Version::Current,
                            usage: slot.usage,
                            multisample_ok: slot.multisample_ok,
                            in_writes: true,
                            pos: name_pos,
                        });
                    }
                }
                pass.settings = self.settings(i, decl, kind, scope);
            }
            self.double_bindings(&pass, resources);
            out.push(pass);
        }
        out
    }

    /// Looks up the resource of every `reads`/`writes` entry; reports unknown names, `.prev`
    /// misuse and slots bound twice in one map.
    fn entries<'d>(
        &mut self,
        i: usize,
        decl: &'d PassDecl,
        names: &HashMap<String, usize>,
        resources: &[Resource],
    ) -> Vec<Entry<'d>> {
        let mut out = Vec::new();
        for (in_writes, map) in [(false, &decl.reads), (true, &decl.writes)] {
            let field = if in_writes { "writes" } else { "reads" };
            for (j, (slot, value)) in map.0.iter().enumerate() {
                let key_pos = self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field(field), Seg::Key(j)]);
                let val_pos = self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field(field), Seg::Value(j)]);
                if map.0[..j].iter().any(|(s, _)| s == slot) {
                    self.err(key_pos, format!("slot \"{slot}\" is bound twice in pass '{}' {field}", decl.name));
                    continue;
                }
                let (base, version) = match value.strip_suffix(".prev") {
                    Some(b) => (b, Version::Previous),
                    None => (value.as_str(), Version::Current),
                };
                let target = match names.get(base) {
                    None => {
                        self.err(
                            val_pos,
                            format!(
                                "unknown resource '{base}' in pass '{}' {field} \"{slot}\" (resources: {})",
                                decl.name,
                                resource_list(names)
                            ),
                        );
                        // The resource meant was probably a close one: do not also report it unwritten.
                        for close in close_names(base, names.keys().map(|k| k.as_str()), 3) {
                            self.uncertain_writes.insert(names[close]);
                        }
                        None
                    }
                    Some(&r) if version == Version::Previous && in_writes => {
                        self.err(
                            val_pos,
                            format!(
                                "pass '{}' writes \"{slot}\" to '{value}': last frame's contents cannot be written",
                                decl.name
                            ),
                        );
                        self.uncertain_writes.insert(r);
                        None
                    }
                    Some(&r) if version == Version::Previous && !resources[r].history => {
                        self.err(
                            val_pos,
                            format!(
                                "'{value}' in pass '{}' reads \"{slot}\": '{base}' is not a history resource \
                                 (declare it with history: true)",
                                decl.name
                            ),
                        );
                        None
                    }
                    Some(&r) => Some((r, version)),
                };
                out.push(Entry { slot, index: j, in_writes, target });
            }
        }
        out
    }

    /// `shader` and `dispatch` belong to compute passes only.
    fn fixed_pass_fields(&mut self, i: usize, decl: &PassDecl, kind: &PassKindInfo) {
        for (field, present) in [("shader", decl.shader.is_some()), ("dispatch", decl.dispatch.is_some())] {
            if present {
                self.err(
                    self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::FieldName(field)]),
                    format!(
                        "pass '{}' of kind '{}' takes no {field} (only '{COMPUTE_KIND}' passes do)",
                        decl.name, kind.name
                    ),
                );
            }
        }
    }

    /// Bindings of a built-in kind: slot names, directions, image/buffer, required slots.
    #[allow(clippy::too_many_arguments)]
    fn kind_bindings(
        &mut self,
        i: usize,
        decl: &PassDecl,
        kind: &PassKindInfo,
        pass: &mut Pass,
        entries: &[Entry<'_>],
        resources: &[Resource],
    ) {
        for e in entries {
            let field = e.map();
            let key_pos = self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field(field), Seg::Key(e.index)]);
            let val_pos = self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field(field), Seg::Value(e.index)]);
            let (own, other) = if e.in_writes { (&kind.writes, &kind.reads) } else { (&kind.reads, &kind.writes) };
            let Some(slot) = own.iter().find(|s| s.name == e.slot) else {
                if other.iter().any(|s| s.name == e.slot) {
                    let (is, move_to) = if e.in_writes { ("read", "reads") } else { ("written", "writes") };
                    self.err(
                        key_pos,
                        format!(
                            "slot \"{}\" of kind '{}' is {is}, not {}: move it to {move_to} (pass '{}')",
                            e.slot,
                            kind.name,
                            if e.in_writes { "written" } else { "read" },
                            decl.name
                        ),
                    );
                } else {
                    let names = |v: &[crate::graph::kinds::SlotDecl]| {
                        if v.is_empty() {
                            "none".to_string()
                        } else {
                            list(v.iter().map(|s| s.name))
                        }
                    };
                    self.err(
                        key_pos,
                        format!(
                            "unknown slot \"{}\" in pass '{}' (kind '{}' reads: {}; writes: {})",
                            e.slot,
                            decl.name,
                            kind.name,
                            names(&kind.reads),
                            names(&kind.writes)
                        ),
                    );
                }
                self.drop_binding(e.target);
                continue;
            };
            let Some((r, version)) = e.target else { continue };
            let res = &resources[r];
            if !slot.usage.is_image_or_buffer() && slot.usage.is_image() != res.is_image() {
                let (is, takes) = if res.is_image() { ("an image", "a buffer") } else { ("a buffer", "an image") };
                self.err(
                    val_pos,
                    format!(
                        "pass '{}' {field} \"{}\": '{}' is {is} but the slot takes {takes}",
                        decl.name, e.slot, res.name
                    ),
                );
                self.drop_binding(e.target);
                continue;
            }
            let binding = PassBinding {
                slot: slot.name.to_string(),
                written_slot: e.slot.to_string(),
                resource: r,
                version,
                usage: slot.usage,
                multisample_ok: slot.multisample_ok,
                in_writes: e.in_writes,
                pos: val_pos,
            };
            // A constant requirement against a constant size needs no scene: say it now, not at
            // compile.
            let need = slot.bytes.expr().and_then(|e| Expr::parse(e).ok()).and_then(|e| e.eval(&BTreeMap::new()).ok());
            if let (Some(need), ResourceDesc::Buffer { size }) = (need.and_then(|n| n.as_whole()), &res.desc) {
                let exact = matches!(slot.bytes, Bytes::Exactly(_));
                let bytes = size.expr.eval(&BTreeMap::new()).ok().map(|n| n.as_f64());
                let wrong = |b: f64| b >= 0.0 && (b < need as f64 || (exact && b != need as f64));
                if let Some(bytes) = bytes.filter(|b| wrong(*b)) {
                    let message = too_small(&decl.name, &binding, &res.name, bytes as u64, slot.bytes, need as u64, "");
                    self.err(val_pos, message);
                }
            }
            pass.bindings.push(binding);
        }
        let pass_pos = self.pos(&[Seg::Field("passes"), Seg::Index(i)]);
        for (in_writes, slots) in [(false, &kind.reads), (true, &kind.writes)] {
            let field = if in_writes { "writes" } else { "reads" };
            let unknown_slot = entries.iter().any(|e| e.in_writes == in_writes && kind.slot(e.slot).is_none());
            for s in slots.iter().filter(|s| s.required && !unknown_slot) {
                if !entries.iter().any(|e| e.slot == s.name) {
                    let at = if (if in_writes { &decl.writes } else { &decl.reads }).0.is_empty() {
                        pass_pos
                    } else {
                        self.pos(&[Seg::Field("passes"), Seg::Index(i), Seg::Field(field)])
                    };
                    let dir = if in_writes { "write" } else { "read" };
                    self.err(
                        at,
                        format!(
                            "pass '{}' does not bind its required {dir} slot \"{}\" ({})",
                            decl.name, s.name, s.doc
                        ),
                    );
                }
            }
        }
    }

    /// A pass may bind one resource version once (a second binding would need two layouts or
    /// two accesses of one resource inside one pass).
    fn double_bindings(&mut self, pass: &Pass, resources: &[Resource]) {
        for (n, b) in pass.bindings.iter().enumerate() {
            if let Some(first) = pass.bindings[..n].iter().find(|o| o.resource == b.resource && o.version == b.version)
            {
                let name = &resources[b.resource].name;
                let name = if b.version == Version::Previous { format!("{name}.prev") } else { name.clone() };
                self.err(
                    b.pos,
                    format!(
                        "pass '{}' binds '{name}' twice (slots \"{}\" and \"{}\")",
                        pass.name, first.written_slot, b.written_slot
                    ),
                );
            }
        }
    }

    /// Settings: names the kind declares, values of the right type.
    fn settings(&mut self, i: usize, decl: &PassDecl, kind: &PassKindInfo, scope: &Scope<'_>) -> Vec<PassSetting> {
        let mut out: Vec<PassSetting> = Vec::new();
        for (j, (name, lit)) in decl.settings.0.iter().enumerate() {
            let key = [Seg::Field("passes"), Seg::Index(i), Seg::Field("settings"), Seg::Key(j)];
            let val = [Seg::Field("passes"), Seg::Index(i), Seg::Field("settings"), Seg::Value(j)];
            let (key_pos, val_pos) = (self.pos(&key), self.pos(&val));
            if out.iter().any(|s| &s.name == name) || decl.settings.0[..j].iter().any(|(n, _)| n == name) {
                self.err(key_pos, format!("setting '{name}' is given twice in pass '{}'", decl.name));
                continue;
            }
            let Some(s) = kind.settings.iter().find(|s| s.name == name) else {
                let known = if kind.settings.is_empty() {
                    format!("kind '{}' takes no settings", kind.name)
                } else {
                    format!("settings: {}", list(kind.settings.iter().map(|s| s.name)))
                };
                self.err(key_pos, format!("unknown setting '{name}' in pass '{}' ({known})", decl.name));
                continue;
            };
            let what = format!("setting '{name}' of pass '{}'", decl.name);
            let wrong = |takes: String| format!("{what} takes {takes}, got {}", literal_text(lit));
            let param = |n: &str| scope.param(n).map(|p| &p.value);
            let source = match (&s.default, lit) {
                (SettingDefault::Bool(_), Literal::Bool(b)) => Some(SettingSource::Value(SettingValue::Bool(*b))),
                (SettingDefault::Bool(_), Literal::Str(p)) if matches!(param(p), Some(ParamValue::Bool(_))) => {
                    Some(SettingSource::Param(p.clone()))
                }
                (SettingDefault::Bool(_), Literal::Str(p)) if param(p).is_some() => {
                    let ty = param(p).map_or("", |v| v.type_name());
                    self.err(val_pos, format!("{what}: param '{p}' is a {ty}, not a bool"));
                    None
                }
                (SettingDefault::Bool(_), _) => {
                    self.err(val_pos, wrong("true or false (or a bool param's name)".into()));
                    None
                }
                (SettingDefault::Int(_), Literal::Int(v)) => Some(SettingSource::Value(SettingValue::Int(*v))),
                (SettingDefault::Float(_), Literal::Int(v)) => {
                    Some(SettingSource::Value(SettingValue::Float(*v as f64)))
                }
                (SettingDefault::Float(_), Literal::Float(v)) => Some(SettingSource::Value(SettingValue::Float(*v))),
                (SettingDefault::Int(_) | SettingDefault::Float(_), Literal::Str(text)) => {
                    let lit = crate::graph::schema::NumLit::Expr(text.clone());
                    self.num(&lit, &val, &what, scope, Vars::Frame).map(|e| {
                        if matches!(s.default, SettingDefault::Int(_)) {
                            self.check_now(&e, scope, &what, |n| {
                                n.as_whole().ok_or_else(|| format!("is not a whole number ({n})"))
                            });
                        }
                        SettingSource::Expr(e)
                    })
                }
                (SettingDefault::Int(_), _) => {
                    self.err(val_pos, wrong("a whole number or an expression".into()));
                    None
                }
                (SettingDefault::Float(_), _) => {
                    self.err(val_pos, wrong("a number or an expression".into()));
                    None
                }
                (SettingDefault::Choice(options), Literal::Str(v)) => match param(v) {
                    Some(ParamValue::Str(pv)) => {
                        if !options.contains(&pv.as_str()) {
                            self.err(
                                val_pos,
                                format!("{what}: param '{v}' is \"{pv}\", not one of {}", options.join(", ")),
                            );
                        }
                        Some(SettingSource::Param(v.clone()))
                    }
                    Some(other) => {
                        self.err(val_pos, format!("{what}: param '{v}' is a {}, not a string", other.type_name()));
                        None
                    }
                    None if options.contains(&v.as_str()) => {
                        Some(SettingSource::Value(SettingValue::Choice(v.clone())))
                    }
                    None => {
                        self.err(
                            val_pos,
                            format!(
                                "{what} must be one of {} (or a string param's name), got \"{v}\"",
                                options.join(", ")
                            ),
                        );
                        None
                    }
                },
                (SettingDefault::Choice(options), _) => {
                    self.err(val_pos, wrong(format!("one of {} (a string)", options.join(", "))));
                    None
                }
            };
            if let Some(SettingSource::Value(value)) = &source {
                if let Some(why) = s.range_error(value) {
                    self.err(val_pos, format!("{what} {why}"));
                }
            }
            if let Some(source) = source {
                out.push(PassSetting { name: name.clone(), ty: s.default.clone(), source, pos: val_pos });
            }
        }
        out
    }
}
