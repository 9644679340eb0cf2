//! Built-in passes. Each records its own commands; the render graph decides their order and
//! the barriers between them, and instantiates them by kind name.

pub mod aa_edges;
pub mod compute;
pub mod fxaa;
pub mod gbuffer;
pub mod gbuffer_compressed;
pub mod hiz_build;
pub mod instance_cull;
pub mod lighting;
pub mod lighting_compressed;
pub mod lighting_visibility;
pub mod overlay;
pub mod visibility_ids;

use crate::gpu::{GpuContext, ShaderCompiler};
use crate::graph::executor::PassNode;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use gbuffer::GeometryMode;
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
        "gbuffer" => Box::new(gbuffer::GbufferPass::for_plan(ctx, shaders, pass, plan, GeometryMode::Clear)?),
        "gbuffer_append" => Box::new(gbuffer::GbufferPass::for_plan(ctx, shaders, pass, plan, GeometryMode::Append)?),
        "gbuffer_equal" => Box::new(gbuffer::GbufferPass::for_plan(ctx, shaders, pass, plan, GeometryMode::Equal)?),
        "gbuffer_compressed" => Box::new(gbuffer_compressed::GbufferCompressedPass::new(ctx, shaders, pass, plan)?),
        "lighting_compressed" => Box::new(lighting_compressed::LightingCompressedPass::new(ctx, shaders, pass, plan)?),
        "lighting_visibility" => Box::new(lighting_visibility::LightingVisibilityPass::new(ctx, shaders, pass, plan)?),
        "aa_edges" => Box::new(aa_edges::AaEdgesPass::new(ctx, shaders, pass, plan)?),
        "instance_cull" => Box::new(instance_cull::InstanceCullPass::new(ctx, shaders, pass)?),
        "fxaa" => Box::new(fxaa::FxaaPass::new(ctx, shaders, pass)?),
        "lighting" => Box::new(lighting::LightingPass::for_plan(ctx, shaders, pass, plan)?),
        "hiz_build" => Box::new(hiz_build::HizBuildPass::new(ctx, shaders, pass)?),
        "overlay" => Box::new(overlay::OverlayPass::new(ctx, shaders, pass, plan)?),
        crate::graph::kinds::COMPUTE_KIND => Box::new(compute::ComputePass::new(ctx, shaders, pass, graph_dir)?),
        other => return Err(crate::Error::Invalid(format!("pass '{}': no executor for kind '{other}'", pass.name))),
    })
}
