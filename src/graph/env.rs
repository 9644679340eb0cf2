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

/// Compiles the file at `path` (on disk) with `compiler` and reflects it.
pub fn shader_interface_with(compiler: &crate::gpu::ShaderCompiler, path: &Path) -> Result<ShaderInterface, String> {
    let source = std::fs::read_to_string(path).map_err(|e| format!("cannot read shader '{}': {e}", path.display()))?;
    let name = path.display().to_string();
    let spirv = compiler.compile_source(&name, &source, &[]).map_err(|e| e.to_string())?;
    crate::gpu::reflect::reflect(&spirv).map_err(|e| e.to_string())
}
