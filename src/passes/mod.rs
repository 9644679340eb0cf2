//! Built-in passes. Each records its own commands; the render graph decides their order and
//! the barriers between them, and instantiates them by kind name.

pub mod compute;
pub mod gbuffer;
pub mod hiz_build;
pub mod instance_cull;
pub mod lighting;
pub mod overlay;

use crate::gpu::{GpuContext, ShaderCompiler};
use crate::graph::executor::PassNode;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use std::path::Path;

/// Creates the pass instance for a planned pass of kind `pass.kind`.
pub fn create_node(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    pass: &PlannedPass,
    plan: &CompiledGraph,
    graph_dir: Option<&Path>,
) -> crate::Result<Box<dyn PassNode>> {
    Ok(match pass.kind.as_str() {
        "gbuffer" => Box::new(gbuffer::GbufferPass::new(ctx, shaders)?),
        "gbuffer_append" => Box::new(gbuffer::GbufferPass::appending(ctx, shaders)?),
        "instance_cull" => Box::new(instance_cull::InstanceCullPass::new(ctx, shaders, pass)?),
        "lighting" => Box::new(lighting::LightingPass::for_plan(ctx, shaders, pass)?),
        "hiz_build" => Box::new(hiz_build::HizBuildPass::new(ctx, shaders, pass)?),
        "overlay" => Box::new(overlay::OverlayPass::new(ctx, shaders, pass, plan)?),
        crate::graph::kinds::COMPUTE_KIND => Box::new(compute::ComputePass::new(ctx, shaders, pass, graph_dir)?),
        other => return Err(crate::Error::Invalid(format!("pass '{}': no executor for kind '{other}'", pass.name))),
    })
}
