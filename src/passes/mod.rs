//! The built-in pass kinds. Each kind lives in one module (its declaration, checks and node) and
//! one shader folder, and registers through the same [`PassKind`](crate::graph::PassKind)
//! interface as an engine's own kinds; [`builtin_kinds`] lists them, one line each.

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
pub mod shared;
pub mod slots;
pub mod visibility_ids;

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
    Ok(())
}
