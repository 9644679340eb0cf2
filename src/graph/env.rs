//! What validation needs from the outside world: the device's format support and the
//! interfaces of user shaders. `cullgraph graph check` provides a real device; tests and the
//! device-less path use [`NoDevice`].

use crate::gpu::reflect::ShaderInterface;
use ash::vk;
use std::path::Path;

/// Answers the questions validation cannot answer from the RON file alone.
pub trait Environment {
    /// Whether images of `format` with `samples` samples can be created with `usage` on the device.
    /// `Err` carries a reason ("STORAGE is not supported for R8G8B8_UNORM with optimal tiling").
    fn check_image_format(
        &self,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: vk::SampleCountFlags,
    ) -> Result<(), String>;

    /// The bindings, push constants and workgroup size of the compute shader at `path`
    /// (relative paths resolve against the graph file's directory, then the shader library).
    /// `Err` carries the compile or reflection error.
    fn shader_interface(&self, path: &Path) -> Result<ShaderInterface, String>;

    /// The device's limits that compiled sizes are checked against; `None` (the default)
    /// checks none.
    fn limits(&self) -> Option<super::compile::device_limits::DeviceLimits> {
        None
    }
}

/// An environment without a device: every format is accepted, shaders are compiled and reflected
/// with shaderc from the given library root.
pub struct NoDevice {
    compiler: crate::gpu::ShaderCompiler,
}

impl NoDevice {
    /// Compiles user shaders against `root` (the shader library for `#include`s).
    pub fn new(root: crate::gpu::ShaderRoot) -> Result<Self, crate::gpu::ShaderError> {
        Ok(Self { compiler: crate::gpu::ShaderCompiler::new(root)? })
    }
}

impl Environment for NoDevice {
    fn check_image_format(&self, _: vk::Format, _: vk::ImageUsageFlags, _: vk::SampleCountFlags) -> Result<(), String> {
        Ok(())
    }

    fn shader_interface(&self, path: &Path) -> Result<ShaderInterface, String> {
        shader_interface_with(&self.compiler, path)
    }
}

/// Compiles the shader at `path` with `compiler` and reflects it: the file on disk if it
/// exists, otherwise `path` inside the compiler's shader library (e.g. `lighting/lighting.comp`).
pub fn shader_interface_with(compiler: &crate::gpu::ShaderCompiler, path: &Path) -> Result<ShaderInterface, String> {
    let spirv = match compiler.compile_path(path, &[]) {
        Err(crate::gpu::ShaderError::NotFound(_)) => {
            return Err("not found (looked next to the graph file and in the shader library)".into())
        }
        other => other.map_err(|e| e.to_string())?,
    };
    let mut interface = crate::gpu::reflect::reflect(&spirv).map_err(|e| e.to_string())?;
    // The optimizer strips variable names from the SPIR-V; take them from the source, with the
    // headers it includes from beside it.
    let source = if path.is_file() { source_with_local_includes(path) } else { None };
    if let Some(source) = source {
        let names = binding_names(&source);
        for (binding, info) in interface.bindings.iter_mut() {
            if info.name.as_deref().is_none_or(str::is_empty) {
                info.name = names.get(binding).cloned();
            }
        }
    }
    Ok(interface)
}

/// The text of the shader file `path` with every `#include "file"` that names a file beside it
/// (relative to the including file) inlined, so that bindings declared in such headers have
/// names; includes from the shader library stay as they are. Each file is inlined once (a
/// header included again, or including itself, keeps its `#include` line), no deeper than the
/// compiler allows and no more text than it takes in, so that this ends fast and small on any
/// files. `None` if `path` cannot be read.
fn source_with_local_includes(path: &Path) -> Option<String> {
    let mut inlined = std::collections::HashSet::new();
    let mut budget = crate::gpu::shader::MAX_INCLUDED_BYTES;
    inline_local_includes(path, 0, &mut inlined, &mut budget)
}

fn inline_local_includes(
    path: &Path,
    depth: usize,
    inlined: &mut std::collections::HashSet<std::path::PathBuf>,
    budget: &mut u64,
) -> Option<String> {
    if depth > crate::gpu::shader::MAX_INCLUDE_DEPTH
        || !inlined.insert(std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()))
    {
        return None;
    }
    let source = crate::files::read_limited_text(path, crate::files::SHADER_LIMIT, "shader").ok()?;
    *budget = budget.checked_sub(source.len() as u64)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = String::with_capacity(source.len());
    for line in source.lines() {
        let included = line.trim_start().strip_prefix("#include").map(str::trim).and_then(|rest| {
            let name = rest.strip_prefix('"')?.split('"').next()?;
            let file = dir.join(name);
            file.is_file().then(|| inline_local_includes(&file, depth + 1, inlined, budget)).flatten()
        });
        out.push_str(included.as_deref().unwrap_or(line));
        out.push('\n');
    }
    Some(out)
}

/// GLSL variable names of `layout(.. binding = N ..)` declarations in `source`: the variable
/// name, or for a block without an instance name, the block name. Declarations in included
/// files are not seen here ([`shader_interface_with`] inlines the headers beside a shader file
/// first; bindings of others can still be bound by number).
pub fn binding_names(source: &str) -> std::collections::BTreeMap<u32, String> {
    let text = strip_comments(source);
    let mut out = std::collections::BTreeMap::new();
    let mut rest = text.as_str();
    while let Some(at) = rest.find("layout") {
        let before_ok = at == 0 || !rest[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_');
        rest = &rest[at + "layout".len()..];
        let Some(open) = rest.trim_start().strip_prefix('(') else { continue };
        if !before_ok {
            continue;
        }
        let Some(close) = open.find(')') else { break };
        let qualifiers = &open[..close];
        rest = &open[close + 1..];
        let binding = qualifiers.split(',').find_map(|q| {
            let (k, v) = q.split_once('=')?;
            (k.trim() == "binding").then(|| v.trim().parse::<u32>().ok()).flatten()
        });
        let Some(binding) = binding else { continue };
        let end = rest.find([';', '{']).unwrap_or(rest.len());
        let name = if rest[end..].starts_with('{') {
            let block = last_identifier(&rest[..end]);
            let after = &rest[end..];
            let instance = after.find('}').and_then(|c| {
                let tail = &after[c + 1..];
                let semi = tail.find(';')?;
                last_identifier(&tail[..semi])
            });
            instance.or(block)
        } else {
            last_identifier(&rest[..end])
        };
        if let Some(name) = name {
            out.insert(binding, name);
        }
    }
    out
}

/// The last identifier in `s`, ignoring a trailing array size (`name[4]`).
fn last_identifier(s: &str) -> Option<String> {
    let s = match s.find('[') {
        Some(i) => &s[..i],
        None => s,
    };
    let word: String = s.trim_end().chars().rev().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
    let word: String = word.chars().rev().collect();
    (!word.is_empty() && !word.starts_with(|c: char| c.is_ascii_digit())).then_some(word)
}

/// `source` without `//` and `/* */` comments.
fn strip_comments(source: &str) -> String {
    let mut out = String::with_capacity(source.len());
    let mut chars = source.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, chars.peek()) {
            ('/', Some('/')) => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            ('/', Some('*')) => {
                chars.next();
                let mut prev = ' ';
                for c in chars.by_ref() {
                    if prev == '*' && c == '/' {
                        break;
                    }
                    prev = c;
                }
                out.push(' ');
            }
            _ => out.push(c),
        }
    }
    out
}

/// The real device: format support from `vkGetPhysicalDeviceImageFormatProperties`, shaders
/// compiled and reflected like [`NoDevice`] does (with the caller's compiler and its cache).
pub struct DeviceEnv<'a> {
    ctx: &'a crate::gpu::GpuContext,
    compiler: &'a crate::gpu::ShaderCompiler,
}

impl<'a> DeviceEnv<'a> {
    /// Queries `ctx`'s physical device; compiles user shaders with `compiler`.
    pub fn new(ctx: &'a crate::gpu::GpuContext, compiler: &'a crate::gpu::ShaderCompiler) -> Self {
        Self { ctx, compiler }
    }

    /// The device's name.
    pub fn device_name(&self) -> &str {
        &self.ctx.caps().name
    }
}

impl Environment for DeviceEnv<'_> {
    fn limits(&self) -> Option<super::compile::device_limits::DeviceLimits> {
        let caps = self.ctx.caps();
        let subgroup = vk::SubgroupFeatureFlags::BASIC
            | vk::SubgroupFeatureFlags::VOTE
            | vk::SubgroupFeatureFlags::ARITHMETIC
            | vk::SubgroupFeatureFlags::BALLOT;
        let features = [
            (caps.post_depth_coverage, "post_depth_coverage"),
            (caps.sample_interlock, "fragment_shader_sample_interlock"),
            (caps.subgroup_compute_ops.contains(subgroup), "subgroup_compute"),
        ];
        let features = features.iter().filter(|(on, _)| *on).map(|(_, name)| name.to_string()).collect();
        Some(super::compile::device_limits::DeviceLimits::from_vulkan(&caps.name, &caps.limits, features))
    }

    fn check_image_format(
        &self,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        samples: vk::SampleCountFlags,
    ) -> Result<(), String> {
        let query = |usage: vk::ImageUsageFlags| {
            // SAFETY: a query on a valid physical device of a live instance.
            unsafe {
                self.ctx.instance().get_physical_device_image_format_properties(
                    self.ctx.physical_device(),
                    format,
                    vk::ImageType::TYPE_2D,
                    vk::ImageTiling::OPTIMAL,
                    usage,
                    vk::ImageCreateFlags::empty(),
                )
            }
        };
        match query(usage) {
            Err(vk::Result::ERROR_FORMAT_NOT_SUPPORTED) => {
                // Name the usages that fail on their own.
                let failing: Vec<String> = (0..32)
                    .map(|bit| vk::ImageUsageFlags::from_raw(1 << bit))
                    .filter(|u| usage.contains(*u) && query(*u).is_err())
                    .map(|u| format!("{u:?}"))
                    .collect();
                if failing.is_empty() {
                    Err(format!("the combination of usages {usage:?} is not supported with optimal tiling"))
                } else {
                    Err(format!("{} is not supported for {format:?} with optimal tiling", failing.join(" | ")))
                }
            }
            Err(e) => Err(format!("vkGetPhysicalDeviceImageFormatProperties failed: {e}")),
            Ok(p) if !p.sample_counts.contains(samples) => {
                let counts: Vec<String> = (0..7)
                    .map(|b| 1u32 << b)
                    .filter(|&n| p.sample_counts.as_raw() & n != 0)
                    .map(|n| n.to_string())
                    .collect();
                Err(format!(
                    "{} samples are not supported for this format and usage (supported: {})",
                    samples.as_raw(),
                    counts.join(", ")
                ))
            }
            Ok(_) => Ok(()),
        }
    }

    fn shader_interface(&self, path: &Path) -> Result<ShaderInterface, String> {
        shader_interface_with(self.compiler, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_binding_names_in_glsl() {
        let src = r#"#version 460
// layout(binding = 9) uniform sampler2D commented;
layout(local_size_x = 8) in;
layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D dst;
layout(std430, binding = 2) readonly buffer Counts { uint c[]; } counts;
layout(binding = 3) uniform Params { float k; };
layout(binding=4) uniform sampler2D many[4];
layout(push_constant) uniform Push { uint n; } push;
"#;
        let names = binding_names(src);
        let v: Vec<(u32, &str)> = names.iter().map(|(k, v)| (*k, v.as_str())).collect();
        assert_eq!(v, vec![(0, "src"), (1, "dst"), (2, "counts"), (3, "Params"), (4, "many")]);
    }

    #[test]
    fn inlines_the_headers_beside_a_shader_once_but_not_library_ones() {
        let dir = std::env::temp_dir().join(format!("cullgraph-env-includes-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(
            dir.join("main.comp"),
            "#version 460\n#include \"sub/body.glsl\"\n#include \"common/scene.glsl\"\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("sub/body.glsl"),
            "layout(binding = 3) buffer B { uint w[]; } claims;\n#include \"body.glsl\"\n",
        )
        .unwrap();
        let text = source_with_local_includes(&dir.join("main.comp")).unwrap();
        assert!(text.contains("#include \"common/scene.glsl\""), "library includes stay: {text}");
        assert_eq!(binding_names(&text).get(&3).map(String::as_str), Some("claims"));
        assert_eq!(text.matches("claims;").count(), 1, "a cycle is inlined once: {text}");
        assert!(text.contains("#include \"body.glsl\""), "the include that closes the cycle stays: {text}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
