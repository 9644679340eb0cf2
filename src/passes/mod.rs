//! The built-in pass kinds. Each kind lives in one module (its declaration, checks and node) and
//! one shader folder, and registers through the same [`PassKind`](crate::graph::PassKind)
//! interface as an engine's own kinds; [`builtin_kinds`] lists them, one line each.

pub(crate) mod aa_edges;
pub(crate) mod compute;
pub(crate) mod fxaa;
pub(crate) mod gbuffer;
pub(crate) mod gbuffer_compressed;
pub mod hiz_build;
pub(crate) mod instance_cull;
pub(crate) mod lighting;
pub(crate) mod lighting_compressed;
pub(crate) mod lighting_visibility;
pub mod overlay;
pub mod shared;
pub(crate) mod slots;
pub(crate) mod transparent;
pub(crate) mod transparent_sort;
pub(crate) mod visibility_ids;

use crate::graph::KindRegistry;
use gbuffer::GeometryMode;

/// A registry holding every built-in pass kind; register an engine's own kinds on top of it.
pub fn builtin_kinds() -> KindRegistry {
    let mut kinds = KindRegistry::new();
    register_builtin_kinds(&mut kinds).expect("the built-in pass kinds have distinct, valid names");
    kinds
}

/// Registers every built-in pass kind in `kinds` (an error if one of their names is taken).
pub fn register_builtin_kinds(kinds: &mut KindRegistry) -> crate::Result<()> {
    kinds.register(gbuffer::GbufferKind(GeometryMode::Clear))?;
    kinds.register(gbuffer::GbufferKind(GeometryMode::Equal))?;
    kinds.register(gbuffer_compressed::GbufferCompressedKind)?;
    kinds.register(lighting_visibility::LightingVisibilityKind)?;
    kinds.register(aa_edges::AaEdgesKind)?;
    kinds.register(lighting_compressed::LightingCompressedKind)?;
    kinds.register(lighting::LightingKind)?;
    kinds.register(fxaa::FxaaKind)?;
    kinds.register(gbuffer::GbufferKind(GeometryMode::Append))?;
    kinds.register(hiz_build::HizBuildKind)?;
    kinds.register(instance_cull::InstanceCullKind)?;
    kinds.register(overlay::OverlayKind)?;
    kinds.register(compute::ComputeKind)?;
    kinds.register(transparent_sort::TransparentSortKind)?;
    kinds.register(transparent::TransparentKind)?;
    Ok(())
}
