//! The built-in pass kinds. Each kind lives in one module (its declaration, checks and node) and
//! one shader folder, and registers through the same [`PassKind`](crate::graph::PassKind)
//! interface as an engine's own kinds; [`builtin_kinds`] lists them, one line each.

pub(crate) mod aa_edges;
pub mod cluster_cull;
pub(crate) mod compute;
pub(crate) mod depth_resolve;
pub(crate) mod fxaa;
pub(crate) mod gbuffer;
pub(crate) mod gbuffer_compressed;
pub mod hiz_build;
pub mod instance_cull;
pub(crate) mod lighting;
pub mod lighting_compressed;
pub(crate) mod lighting_visibility;
pub mod overlay;
pub mod shared;
pub(crate) mod slots;
pub(crate) mod tonemap;
pub(crate) mod transparent;
pub mod transparent_sort;
pub(crate) mod visibility_ids;

use crate::graph::{KindRegistry, LibraryGraph};
use gbuffer::GeometryMode;

/// The graphs shipped in `graph/`, made of the built-in kinds and embedded at build time, so
/// that a binary carried elsewhere has them: graphs extend them by name (`extends:
/// "two_phase"`), and the command line runs them as `builtin:NAME`.
pub const SHIPPED_GRAPHS: &[LibraryGraph] = &[
    LibraryGraph { name: "default", file: "graph/default.ron", text: include_str!("../../graph/default.ron") },
    LibraryGraph { name: "no_cull", file: "graph/no_cull.ron", text: include_str!("../../graph/no_cull.ron") },
    LibraryGraph { name: "frustum", file: "graph/frustum.ron", text: include_str!("../../graph/frustum.ron") },
    LibraryGraph { name: "two_phase", file: "graph/two_phase.ron", text: include_str!("../../graph/two_phase.ron") },
    LibraryGraph {
        name: "two_phase_clusters",
        file: "graph/two_phase_clusters.ron",
        text: include_str!("../../graph/two_phase_clusters.ron"),
    },
    LibraryGraph {
        name: "frustum_clusters",
        file: "graph/frustum_clusters.ron",
        text: include_str!("../../graph/frustum_clusters.ron"),
    },
    LibraryGraph { name: "shadow", file: "graph/shadow.ron", text: include_str!("../../graph/shadow.ron") },
    LibraryGraph {
        name: "shadow_no_cull",
        file: "graph/shadow_no_cull.ron",
        text: include_str!("../../graph/shadow_no_cull.ron"),
    },
    LibraryGraph { name: "one_phase", file: "graph/one_phase.ron", text: include_str!("../../graph/one_phase.ron") },
    LibraryGraph {
        name: "occluder_prepass",
        file: "graph/occluder_prepass.ron",
        text: include_str!("../../graph/occluder_prepass.ron"),
    },
    LibraryGraph {
        name: "occluder_prepass_clusters",
        file: "graph/occluder_prepass_clusters.ron",
        text: include_str!("../../graph/occluder_prepass_clusters.ron"),
    },
    LibraryGraph { name: "overlay", file: "graph/overlay.ron", text: include_str!("../../graph/overlay.ron") },
    LibraryGraph {
        name: "msaa_compressed",
        file: "graph/msaa_compressed.ron",
        text: include_str!("../../graph/msaa_compressed.ron"),
    },
    LibraryGraph {
        name: "msaa_compressed_edges",
        file: "graph/msaa_compressed_edges.ron",
        text: include_str!("../../graph/msaa_compressed_edges.ron"),
    },
    LibraryGraph {
        name: "msaa_compressed_claim",
        file: "graph/msaa_compressed_claim.ron",
        text: include_str!("../../graph/msaa_compressed_claim.ron"),
    },
    LibraryGraph {
        name: "msaa_per_sample",
        file: "graph/msaa_per_sample.ron",
        text: include_str!("../../graph/msaa_per_sample.ron"),
    },
    LibraryGraph {
        name: "msaa_zprepass",
        file: "graph/msaa_zprepass.ron",
        text: include_str!("../../graph/msaa_zprepass.ron"),
    },
    LibraryGraph {
        name: "visibility_buffer",
        file: "graph/visibility_buffer.ron",
        text: include_str!("../../graph/visibility_buffer.ron"),
    },
    LibraryGraph { name: "fxaa", file: "graph/fxaa.ron", text: include_str!("../../graph/fxaa.ron") },
    LibraryGraph { name: "post", file: "graph/post.ron", text: include_str!("../../graph/post.ron") },
];

/// A registry holding every built-in pass kind; register an engine's own kinds on top of it.
pub fn builtin_kinds() -> KindRegistry {
    let mut kinds = KindRegistry::new();
    register_builtin_kinds(&mut kinds).expect("the built-in pass kinds have distinct, valid names");
    kinds
}

/// Registers every built-in pass kind in `kinds`, and the scene quantities their sizes use
/// (an error if one of their names is taken).
pub fn register_builtin_kinds(kinds: &mut KindRegistry) -> crate::Result<()> {
    for quantity in shared::scene_quantities() {
        kinds.register_quantity(quantity)?;
    }
    for graph in SHIPPED_GRAPHS {
        kinds.register_graph(*graph)?;
    }
    kinds.register(gbuffer::GbufferKind(GeometryMode::Clear))?;
    kinds.register(gbuffer::GbufferKind(GeometryMode::Equal))?;
    kinds.register(gbuffer_compressed::GbufferCompressedKind)?;
    kinds.register(lighting_visibility::LightingVisibilityKind)?;
    kinds.register(aa_edges::AaEdgesKind)?;
    kinds.register(lighting_compressed::LightingCompressedKind)?;
    kinds.register(lighting::LightingKind)?;
    kinds.register(fxaa::FxaaKind)?;
    kinds.register(tonemap::TonemapKind)?;
    kinds.register(depth_resolve::DepthResolveKind)?;
    kinds.register(gbuffer::GbufferKind(GeometryMode::Append))?;
    kinds.register(hiz_build::HizBuildKind)?;
    kinds.register(instance_cull::InstanceCullKind)?;
    kinds.register(cluster_cull::ClusterCullKind)?;
    kinds.register(overlay::OverlayKind)?;
    kinds.register(compute::ComputeKind)?;
    kinds.register(transparent_sort::TransparentSortKind)?;
    kinds.register(transparent::TransparentKind)?;
    Ok(())
}
