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
//! What would make a frame invalid is refused here rather than left to the device: image
//! bindings that are not 2D with one layer (graph images and their views are), storage images
//! without a format qualifier or with one that is not the bound image's format, and workgroups
//! larger, or with more shared memory, than the device allows (the Vulkan minimums without a
//! device).
//!
//! [`Environment`]: crate::graph::env::Environment

use super::passes::Entry;
use super::{resource_list, Scope, Validator, Vars};
use crate::gpu::reflect::{format_qualifier, BindingInfo, ImageDecl, ImageDim, ShaderInterface};
use crate::graph::compile::device_limits::{ComputeLimits, DeviceLimits};
use crate::graph::error::list;
use crate::graph::formats;
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

/// Whether a graph pass can bind a descriptor of this type.
fn bindable(kind: vk::DescriptorType) -> bool {
    matches!(
        kind,
        vk::DescriptorType::COMBINED_IMAGE_SAMPLER
            | vk::DescriptorType::SAMPLED_IMAGE
            | vk::DescriptorType::STORAGE_IMAGE
            | vk::DescriptorType::STORAGE_BUFFER
            | vk::DescriptorType::UNIFORM_BUFFER
    )
}

/// Why binding `number` of `shader` cannot be bound to any graph resource, whatever the pass
/// binds there: a descriptor a graph cannot bind, an array, an image that is not 2D with one
/// layer (graph images are, and their views), or a storage image without a format qualifier
/// (writing one needs a format feature that devices lack for some formats, and reading one a
/// device feature).
fn binding_problem(number: u32, info: &BindingInfo, shader: &str) -> Option<String> {
    let label = binding_label(number, info);
    let storage = info.kind == vk::DescriptorType::STORAGE_IMAGE;
    if !bindable(info.kind) {
        return Some(format!(
            "binding {label} of shader '{shader}' is a {}, which graph passes cannot bind \
             (use sampled images, storage images, storage buffers or uniform buffers)",
            descriptor_name(info.kind)
        ));
    }
    if info.count != 1 {
        return Some(format!(
            "binding {label} of shader '{shader}' is an array of {}; graph passes bind single resources",
            info.count
        ));
    }
    let image = info.image?;
    if image.dim != ImageDim::D2 || image.arrayed {
        let flat = ImageDecl { dim: ImageDim::D2, arrayed: false, ..image };
        let declared = image.glsl_type(storage);
        let article = if declared.starts_with('i') { "an" } else { "a" };
        return Some(format!(
            "binding {label} of shader '{shader}' is {article} {declared}, but graph images are 2D with one layer: \
             declare it {}",
            flat.glsl_type(storage)
        ));
    }
    if storage && image.format.is_none() {
        return Some(format!(
            "storage image binding {label} of shader '{shader}' has no format qualifier: declare the format of \
             the image bound there, e.g. layout(binding = {number}, rgba8) for R8G8B8A8_UNORM"
        ));
    }
    None
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
        for message in workgroup_errors(shader, &decl.name, &interface, self.env.limits().as_ref()) {
            self.err(shader_pos, message);
        }
        let mut shader_ok = true;
        for (&number, info) in &interface.bindings {
            if let Some(message) = binding_problem(number, info, shader) {
                self.err(shader_pos, message);
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
            if binding_problem(number, info, shader).is_some() {
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
                let gives = formats::sampled_scalar(*format);
                if *format != vk::Format::UNDEFINED && gives != declared {
                    let message = format!(
                        "{head} samples {declared:?} values but '{}' is {}, which gives {gives:?} values",
                        res.name,
                        formats::name(*format)
                    );
                    self.err(val_pos, message);
                    self.drop_binding(e.target);
                    continue;
                }
            }
            // A storage image view must have exactly the format its declaration names.
            if let (Some(declared), ResourceDesc::Image { format, .. }) = (info.image.and_then(|i| i.format), &res.desc)
            {
                if *format != vk::Format::UNDEFINED && declared != *format {
                    let fix = match format_qualifier(*format) {
                        Some(q) => format!("declare it {q}"),
                        None => "no format qualifier names that format, so it cannot be a storage image".into(),
                    };
                    let message = format!(
                        "{head} is declared {} ({}) but '{}' is {}: {fix}",
                        format_qualifier(declared).unwrap_or("?"),
                        formats::name(declared),
                        res.name,
                        formats::name(*format)
                    );
                    // The usage stays: the device's support of the image as storage is checked too.
                    self.err(val_pos, message);
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
            if !unresolved && !bound.contains_key(&number) && binding_problem(number, info, shader).is_none() {
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

/// What a compute shader's workgroup takes beyond the device's `limits` (without a device, beyond
/// the minimum every Vulkan device allows): its size in each dimension, its threads and its
/// shared memory. A pipeline past them is invalid (the validation layer reports
/// `VUID-RuntimeSpirv-Workgroup-06530` for shared memory).
fn workgroup_errors(
    shader: &str,
    pass: &str,
    interface: &ShaderInterface,
    limits: Option<&DeviceLimits>,
) -> Vec<String> {
    let (c, who) = match limits {
        Some(l) => (l.compute, l.device.as_str()),
        None => (ComputeLimits::VULKAN_MINIMUM, "every Vulkan device (no device was asked)"),
    };
    let mut out = Vec::new();
    let head = format!("shader '{shader}' of pass '{pass}'");
    let [x, y, z] = interface.local_size.unwrap_or([1, 1, 1]);
    let [mx, my, mz] = c.max_work_group_size;
    if x > mx || y > my || z > mz {
        out.push(format!(
            "{head} has workgroups of {x}x{y}x{z} threads, more than {who} allows \
             (maxComputeWorkGroupSize {mx}x{my}x{mz})"
        ));
    }
    let threads = x as u64 * y as u64 * z as u64;
    if threads > c.max_work_group_invocations as u64 {
        out.push(format!(
            "{head} has workgroups of {x}x{y}x{z} = {threads} threads, more than {who} allows \
             (maxComputeWorkGroupInvocations {})",
            c.max_work_group_invocations
        ));
    }
    if interface.workgroup_memory_bytes > c.max_shared_memory_bytes as u64 {
        out.push(format!(
            "{head} uses {} bytes of shared memory, more than {who} allows (maxComputeSharedMemorySize {})",
            interface.workgroup_memory_bytes, c.max_shared_memory_bytes
        ));
    }
    out
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
