//! Pipelines created when first used. A pass keeps a variant for each thing a scene may have or
//! lack (emission and occlusion, masked materials) and picks one per frame; the variants a scene
//! never needs are never created. Their shaders are compiled up front, so that a bad shader is
//! still an error when the pass is built, and only the driver's pipeline creation (on a CPU
//! device, most of the cost) waits for the first use.

use crate::gpu::{GpuContext, Pipeline, Spirv};

/// How to create the pipeline.
enum Source {
    /// A graphics pipeline over `gbuffer.vert` (`passes::gbuffer::GeometryShaders`).
    Geometry(crate::passes::gbuffer::GeometryShaders),
    /// A compute pipeline.
    Compute(Spirv),
}

/// A pipeline created on first [`LazyPipeline::get`].
pub struct LazyPipeline {
    name: String,
    source: Source,
    pipeline: Option<Pipeline>,
}

impl LazyPipeline {
    /// A geometry pipeline named `name`, from its compiled shaders.
    pub fn geometry(name: &str, shaders: crate::passes::gbuffer::GeometryShaders) -> Self {
        Self { name: name.into(), source: Source::Geometry(shaders), pipeline: None }
    }

    /// A compute pipeline named `name`, from its compiled shader.
    pub fn compute(name: &str, spirv: Spirv) -> Self {
        Self { name: name.into(), source: Source::Compute(spirv), pipeline: None }
    }

    /// The pipeline, created now if this is its first use.
    pub fn get(&mut self, ctx: &GpuContext) -> crate::Result<&Pipeline> {
        if self.pipeline.is_none() {
            self.pipeline = Some(match &self.source {
                Source::Geometry(shaders) => shaders.create(ctx, &self.name)?,
                Source::Compute(spirv) => Pipeline::compute(ctx, &self.name, spirv)?,
            });
        }
        Ok(self.pipeline.as_ref().expect("created above"))
    }
}
