//! A lighting kind's compute pipeline in two variants: without shadow lookups, for views
//! without shadows (no bindings, no cost: the lookups' code, even when skipped, costs the light
//! loop registers), and with them (`SHADOWS`), made when a view with shadows first needs it.

use super::lazy_pipeline::LazyPipeline;
use super::ShadowMaps;
use crate::gpu::{Bind, GpuContext, Pipeline, ShaderCompiler};

/// See the module documentation.
pub(crate) struct ShadowVariants {
    plain: LazyPipeline,
    shadowed: LazyPipeline,
}

impl ShadowVariants {
    /// Both variants of compute shader `path` with `defines`, named `name`; the shaders are
    /// compiled now, the pipelines made when first picked.
    pub fn compute(name: &str, shaders: &ShaderCompiler, path: &str, defines: &[(&str, &str)]) -> crate::Result<Self> {
        let plain = LazyPipeline::compute(name, shaders.compile(path, defines)?);
        let with: Vec<(&str, &str)> = defines.iter().copied().chain([("SHADOWS", "1")]).collect();
        let shadowed = LazyPipeline::compute(name, shaders.compile(path, &with)?);
        Ok(Self { plain, shadowed })
    }

    /// The pipeline for a view with `maps`, with the maps added to `binds` when it samples them.
    pub fn pick(&mut self, ctx: &GpuContext, maps: ShadowMaps, binds: &mut Vec<Bind>) -> crate::Result<&Pipeline> {
        if maps.on {
            binds.extend(maps.binds());
            self.shadowed.get(ctx)
        } else {
            self.plain.get(ctx)
        }
    }
}
