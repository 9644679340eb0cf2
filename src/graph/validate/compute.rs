//! Compute passes: the shader (found, compiled and reflected through the [`Environment`]), its
//! bindings against the graph's `reads`/`writes`, and the dispatch size.
//!
//! Slots are binding numbers (`"1"`) or GLSL variable names (`"src"`). How a binding is used
//! follows from the shader: a sampled image or uniform buffer is read; a storage image or buffer
//! is read when bound in `reads` (the shader must declare it `readonly`) and written when bound
//! in `writes` (it must not be `readonly`). Reflection does not say whether a writable binding
//! also reads, so a write is taken to replace the contents when it is the first write of the
//! resource in the frame (nothing meaningful to keep, unless the host imported it), and to
//! read-modify-write it otherwise.
//!
//! [`Environment`]: crate::graph::env::Environment

use super::passes::Entry;
use super::{resource_list, Scope, Validator, Vars};
use crate::gpu::reflect::BindingInfo;
use crate::graph::error::list;
use crate::graph::locate::Seg;
use crate::graph::plan::Version;
use crate::graph::schema::{DispatchDecl, PassDecl};
use crate::graph::usage::{Stages, Usage};
use crate::graph::validated::{DispatchSpec, Pass, PassBinding, Resource, ResourceDesc};
use ash::vk;
use std::collections::HashMap;

/// Words for a descriptor type.
pub(crate) fn descriptor_name(kind: vk::DescriptorType) -> &'static str {
    match kind {
        vk::DescriptorType::COMBINED_IMAGE_SAMPLER | vk::DescriptorType::SAMPLED_IMAGE => "sampled image",
        vk::DescriptorType::STORAGE_IMAGE => "storage image",
        vk::DescriptorType::STORAGE_BUFFER => "storage buffer",
        vk::DescriptorType::UNIFORM_BUFFER => "uniform buffer",
        vk::DescriptorType::SAMPLER => "sampler",
        vk::DescriptorType::UNIFORM_TEXEL_BUFFER => "uniform texel buffer",
        vk::DescriptorType::STORAGE_TEXEL_BUFFER => "storage texel buffer",
        vk::DescriptorType::INPUT_ATTACHMENT => "input attachment",
        vk::DescriptorType::ACCELERATION_STRUCTURE_KHR => "acceleration structure",
        _ => "descriptor",
    }
}

fn binding_label(number: u32, info: &BindingInfo) -> String {
    match &info.name {
        Some(n) if !n.is_empty() => format!("{number} '{n}'"),
        _ => number.to_string(),
    }
}

impl Validator<'_> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn compute_pass(
        &mut self,
        i: usize,
        decl: &PassDecl,
        pass: &mut Pass,
        entries: &[Entry<'_>],
        resources: &[Resource],
        names: &HashMap<String, usize>,
        scope: &Scope<'_>,
    ) {
        let path = [Seg::Field("passes"), Seg::Index(i)];
        let pass_pos = self.pos(&path);
        let mark_broken = |v: &mut Self| {
            for e in entries.iter().filter(|e| e.in_writes) {
                if let Some((r, _)) = e.target {
                    v.uncertain_writes.insert(r);
                }
            }
        };
        self.dispatch(i, decl, pass, resources, names, scope);
        if decl.dispatch.is_none() {
            self.err(
                pass_pos,
                format!(
                    "compute pass '{}' needs a dispatch (PerPixel(\"image\"), Threads(x, y, z) or Groups(x, y, z))",
                    decl.name
                ),
            );
        }
        let Some(shader) = &decl.shader else {
            self.err(pass_pos, format!("compute pass '{}' needs a shader", decl.name));
            mark_broken(self);
            return;
        };
        let shader_pos = self.pos(&[path[0], path[1], Seg::Field("shader")]);
        let local = self.src.dir_of(&[path[0], path[1]]).map(|d| d.join(shader)).filter(|p| p.is_file());
        let resolved = local.unwrap_or_else(|| std::path::PathBuf::from(shader));
        pass.shader = Some(resolved.clone());
        let interface = match self.env.shader_interface(&resolved) {
            Ok(i) => i,
            Err(e) => {
                let e = e.trim_end().replace('\n', "\n    ");
                self.err(shader_pos, format!("shader '{shader}' of pass '{}': {e}", decl.name));
                mark_broken(self);
                return;
            }
        };
        pass.local_size = interface.local_size.unwrap_or([1, 1, 1]);
        let bindable = |kind: vk::DescriptorType| {
            matches!(
                kind,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER
                    | vk::DescriptorType::SAMPLED_IMAGE
                    | vk::DescriptorType::STORAGE_IMAGE
                    | vk::DescriptorType::STORAGE_BUFFER
                    | vk::DescriptorType::UNIFORM_BUFFER
            )
        };
        let mut shader_ok = true;
        for (&number, info) in &interface.bindings {
            let label = binding_label(number, info);
            if !bindable(info.kind) {
                self.err(
                    shader_pos,
                    format!(
                        "binding {label} of shader '{shader}' is a {}, which graph passes cannot bind \
                         (use sampled images, storage images, storage buffers or uniform buffers)",
                        descriptor_name(info.kind)
                    ),
                );
                shader_ok = false;
            } else if info.count != 1 {
                self.err(
                    shader_pos,
                    format!(
                        "binding {label} of shader '{shader}' is an array of {}; graph passes bind single resources",
                        info.count
                    ),
                );
                shader_ok = false;
            }
        }
        if !shader_ok {
            mark_broken(self);
        }
        let all_bindings = || {
            list(
                interface
                    .bindings
                    .iter()
                    .map(|(n, b)| format!("{} ({})", binding_label(*n, b), descriptor_name(b.kind))),
            )
        };
        let mut bound: HashMap<u32, &str> = HashMap::new();
        let mut unresolved = false;
        for e in entries {
            let field = e.map();
            let key_pos = self.pos(&[path[0], path[1], Seg::Field(field), Seg::Key(e.index)]);
            let val_pos = self.pos(&[path[0], path[1], Seg::Field(field), Seg::Value(e.index)]);
            let found = match e.slot.parse::<u32>() {
                Ok(n) => interface.bindings.get(&n).map(|b| (n, b)),
                Err(_) => {
                    interface.bindings.iter().find(|(_, b)| b.name.as_deref() == Some(e.slot)).map(|(n, b)| (*n, b))
                }
            };
            let Some((number, info)) = found else {
                unresolved = true;
                self.drop_binding(e.target);
                self.err(
                    key_pos,
                    format!(
                        "shader '{shader}' of pass '{}' has no binding \"{}\" (bindings: {})",
                        decl.name,
                        e.slot,
                        all_bindings()
                    ),
                );
                continue;
            };
            if let Some(first) = bound.insert(number, e.slot) {
                self.drop_binding(e.target);
                self.err(
                    key_pos,
                    format!(
                        "pass '{}' binds shader binding {number} twice (\"{first}\" and \"{}\")",
                        decl.name, e.slot
                    ),
                );
                continue;
            }
            if !bindable(info.kind) || info.count != 1 {
                self.drop_binding(e.target);
                continue;
            }
            let Some((r, version)) = e.target else { continue };
            let res = &resources[r];
            let label = binding_label(number, info);
            let what = descriptor_name(info.kind);
            let is_image_binding = matches!(
                info.kind,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER
                    | vk::DescriptorType::SAMPLED_IMAGE
                    | vk::DescriptorType::STORAGE_IMAGE
            );
            let head = format!("pass '{}' {field} \"{}\": binding {label}", decl.name, e.slot);
            if is_image_binding != res.is_image() {
                let is = if res.is_image() { "an image" } else { "a buffer" };
                self.err(val_pos, format!("{head} is a {what} but '{}' is {is}", res.name));
                self.drop_binding(e.target);
                continue;
            }
            // A sampled image returns the scalar type of its format: a usampler2D over a UNORM
            // image (or a sampler2D over a UINT one) reads undefined values.
            if let (Some(declared), ResourceDesc::Image { format, .. }) =
                (info.image.and_then(|i| i.sampled), &res.desc)
            {
                let gives = crate::graph::formats::sampled_scalar(*format);
                if *format != vk::Format::UNDEFINED && gives != declared {
                    let message = format!(
                        "{head} samples {declared:?} values but '{}' is {}, which gives {gives:?} values",
                        res.name,
                        crate::graph::formats::name(*format)
                    );
                    self.err(val_pos, message);
                    self.drop_binding(e.target);
                    continue;
                }
            }
            let c = Stages::Compute;
            let usage = match (info.kind, e.in_writes) {
                (vk::DescriptorType::STORAGE_IMAGE, false) | (vk::DescriptorType::STORAGE_BUFFER, false)
                    if info.writes =>
                {
                    self.err(
                        key_pos,
                        format!("{head} is writable in the shader; declare it readonly or bind it in writes"),
                    );
                    self.drop_binding(e.target);
                    continue;
                }
                (vk::DescriptorType::STORAGE_IMAGE, false) => Usage::StorageImageRead(c),
                (vk::DescriptorType::STORAGE_BUFFER, false) => Usage::StorageBufferRead(c),
                (vk::DescriptorType::UNIFORM_BUFFER, false) => Usage::Uniform(c),
                (_, false) => Usage::Sampled(c),
                (vk::DescriptorType::STORAGE_IMAGE | vk::DescriptorType::STORAGE_BUFFER, true) if !info.writes => {
                    self.err(key_pos, format!("{head} is declared readonly in the shader; bind it in reads"));
                    self.drop_binding(e.target);
                    continue;
                }
                // Settled by `settle_write_usages` once all passes are known.
                (vk::DescriptorType::STORAGE_IMAGE, true) => Usage::StorageImageReadWrite(c),
                (vk::DescriptorType::STORAGE_BUFFER, true) => Usage::StorageBufferReadWrite(c),
                (_, true) => {
                    self.err(key_pos, format!("{head} is a {what}, which a shader can only read; bind it in reads"));
                    self.drop_binding(e.target);
                    continue;
                }
            };
            pass.bindings.push(PassBinding {
                slot: number.to_string(),
                written_slot: e.slot.to_string(),
                resource: r,
                version,
                usage,
                // Compute shaders are not recompiled per sample count: a multisampled
                // declaration takes multisampled images only, a single-sampled one the others.
                multisample_ok: info.image.is_some_and(|i| i.multisampled),
                in_writes: e.in_writes,
                pos: val_pos,
            });
        }
        for (&number, info) in &interface.bindings {
            if !unresolved && !bound.contains_key(&number) && bindable(info.kind) && info.count == 1 {
                self.err(
                    shader_pos,
                    format!(
                        "binding {} ({}) of shader '{shader}' is not bound in pass '{}'",
                        binding_label(number, info),
                        descriptor_name(info.kind),
                        decl.name
                    ),
                );
            }
        }
    }

    fn dispatch(
        &mut self,
        i: usize,
        decl: &PassDecl,
        pass: &mut Pass,
        resources: &[Resource],
        names: &HashMap<String, usize>,
        scope: &Scope<'_>,
    ) {
        let Some(d) = &decl.dispatch else { return };
        let path = [Seg::Field("passes"), Seg::Index(i), Seg::Field("dispatch")];
        pass.dispatch = match d {
            DispatchDecl::PerPixel(name) => {
                let at = self.pos(&[path[0], path[1], path[2], Seg::Index(0)]);
                match names.get(name) {
                    None => {
                        self.err(
                            at,
                            format!(
                                "unknown resource '{name}' in dispatch of pass '{}' (resources: {})",
                                decl.name,
                                resource_list(names)
                            ),
                        );
                        None
                    }
                    Some(&r) if !resources[r].is_image() => {
                        self.err(
                            at,
                            format!("PerPixel dispatch of pass '{}' needs an image, '{name}' is a buffer", decl.name),
                        );
                        None
                    }
                    Some(&r) => Some(DispatchSpec::PerPixel(r)),
                }
            }
            DispatchDecl::Threads(x, y, z) | DispatchDecl::Groups(x, y, z) => {
                let axes = ["x", "y", "z"];
                let mut out = Vec::new();
                for (k, lit) in [x, y, z].into_iter().enumerate() {
                    let what = format!("dispatch {} of pass '{}'", axes[k], decl.name);
                    let p = [path[0], path[1], path[2], Seg::Index(k)];
                    if let Some(e) = self.num(lit, &p, &what, scope, Vars::Frame) {
                        self.check_now(&e, scope, &what, |n| {
                            n.as_whole()
                                .filter(|v| *v >= 0)
                                .ok_or_else(|| format!("must be a whole number >= 0, got {n}"))
                        });
                        out.push(e);
                    }
                }
                let arr: Option<[_; 3]> = out.try_into().ok();
                match (d, arr) {
                    (DispatchDecl::Threads(..), Some(a)) => Some(DispatchSpec::Threads(a)),
                    (_, Some(a)) => Some(DispatchSpec::Groups(a)),
                    _ => None,
                }
            }
        };
    }
}

/// Storage writes of compute passes: a plain write (previous contents discarded) for the first
/// write of a non-imported resource in the frame, read-modify-write otherwise.
pub(super) fn settle_write_usages(passes: &mut [Pass], resources: &[Resource]) {
    let mut written = vec![false; resources.len()];
    for pass in passes.iter_mut() {
        let auto = pass.shader.is_some();
        for b in &mut pass.bindings {
            if b.version != Version::Current || !b.usage.writes() {
                continue;
            }
            if auto && !written[b.resource] && !resources[b.resource].imported {
                b.usage = match b.usage {
                    Usage::StorageImageReadWrite(s) => Usage::StorageImageWrite(s),
                    Usage::StorageBufferReadWrite(s) => Usage::StorageBufferWrite(s),
                    other => other,
                };
            }
        }
        for b in &pass.bindings {
            if b.version == Version::Current && b.usage.writes() {
                written[b.resource] = true;
            }
        }
    }
}
