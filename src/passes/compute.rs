//! The generic compute pass: a user's GLSL compute shader whose bindings are the graph's slots.
//!
//! If the shader declares push constants, it receives (truncated to its block's size)
//! `uvec4(output width, output height, frame number, 0)`.

use crate::gpu::{Bind, GpuContext, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::{PassContext, Physical};
use crate::graph::plan::PlannedPass;
use crate::graph::{NodeSetup, PassKind, PassKindInfo, PassNode, COMPUTE_KIND};
use ash::vk;
use std::path::Path;

/// A user compute shader bound to graph resources.
pub struct ComputePass {
    pipeline: Pipeline,
    sampler: Sampler,
    dispatch: [u32; 3],
}

impl ComputePass {
    /// Compiles the pass's shader (`pass.shader`, relative paths against `graph_dir`).
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        graph_dir: Option<&Path>,
    ) -> crate::Result<Self> {
        let invalid = |m: String| crate::Error::Invalid(format!("pass '{}': {m}", pass.name));
        let shader = pass.shader.as_ref().ok_or_else(|| invalid("a compute pass needs a shader".into()))?;
        let path = match graph_dir {
            Some(dir) if shader.is_relative() && dir.join(shader).exists() => dir.join(shader),
            _ => shader.clone(),
        };
        let spirv = shaders.compile_path(&path, &[])?;
        let dispatch = pass.dispatch.ok_or_else(|| invalid("a compute pass needs a dispatch size".into()))?;
        Ok(Self {
            pipeline: Pipeline::compute(ctx, &pass.name, &spirv)?,
            sampler: Sampler::nearest_clamp(ctx)?,
            dispatch,
        })
    }
}

impl PassNode for ComputePass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let mut binds = Vec::new();
        for b in rec.slots.all() {
            let number: u32 = b.slot.parse().map_err(|_| {
                crate::Error::Invalid(format!("compute slot '{}' is not a binding number after compilation", b.slot))
            })?;
            let kind = self.pipeline.interface().bindings.get(&number).map(|i| i.kind);
            match (rec.slots.physical(b), kind) {
                (Some(Physical::Buffer(buf)), _) => binds.push(Bind::Buffer(number, buf.handle())),
                (Some(Physical::Image(img)), Some(vk::DescriptorType::STORAGE_IMAGE)) => {
                    binds.push(Bind::StorageImage(number, img.view()))
                }
                (Some(Physical::Image(img)), _) => binds.push(Bind::Sampled(
                    number,
                    img.sampled_view(),
                    self.sampler.handle(),
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                )),
                (None | Some(Physical::Unbound), _) => {}
            }
        }
        self.pipeline.bind(rec.cmd);
        self.pipeline.push_bindings(rec.cmd, &binds);
        let push_bytes = self.pipeline.interface().push_constant_bytes.min(16) as usize;
        if push_bytes > 0 {
            let e = rec.frame.extent;
            let words = [e.width, e.height, rec.frame.frame as u32, 0];
            self.pipeline.push_constant_bytes(rec.cmd, &bytemuck::cast_slice(&words)[..push_bytes]);
        }
        let [x, y, z] = self.dispatch;
        // SAFETY: cmd recording with the pipeline bound.
        unsafe { rec.ctx.device().cmd_dispatch(rec.cmd, x, y, z) };
        Ok(())
    }
}

/// The `compute` pass kind.
pub struct ComputeKind;

impl PassKind for ComputeKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: COMPUTE_KIND,
            doc: "a user compute shader; its slots are the shader's bindings (by binding number or variable name)",
            reads: vec![],
            writes: vec![],
            settings: vec![],
            slots_from_shader: true,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(ComputePass::new(s.ctx, s.shaders, s.pass, s.graph_dir)?))
    }
}
