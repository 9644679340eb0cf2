//! What a glTF scene will hold (instances, vertices, indices, textures), counted from the
//! document alone before any buffer is read or anything is allocated, and checked against the
//! scene limits (`validate::MAX_*`). A file of a few hundred kilobytes can place millions of
//! instances or copies of its geometry; it is refused with the node or accessor that takes the
//! scene past a limit, instead of running out of memory.

use super::nodes::{node_label, Placed};
use super::primitive::mode_name;
use super::{accessor, mesh_label};
use crate::scene::error::SceneError;
use crate::scene::validate::{MAX_INDICES, MAX_INSTANCES, MAX_TEXTURES, MAX_VERTICES};
use gltf::mesh::{Mode, Semantic};
use gltf::{Document, Primitive};
use std::collections::HashSet;

/// What a primitive's geometry depends on: two primitives with the same key become the same
/// cullgraph mesh, read once (a file that repeats one primitive 20,000 times costs one mesh).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) struct PrimitiveKey {
    mode: &'static str,
    indices: Option<usize>,
    position: Option<usize>,
    normal: Option<usize>,
    uv: Option<usize>,
    tangent: Option<usize>,
    /// The accessors of the joint influences (`JOINTS_n`, `WEIGHTS_n`) and morph targets.
    deform: Vec<Option<usize>>,
}

impl PrimitiveKey {
    /// The key of `primitive`.
    pub(super) fn of(primitive: &Primitive<'_>) -> Self {
        let attribute = |s: Semantic| primitive.get(&s).map(|a| a.index());
        Self {
            mode: mode_name(primitive.mode()),
            indices: primitive.indices().map(|a| a.index()),
            position: attribute(Semantic::Positions),
            normal: attribute(Semantic::Normals),
            uv: attribute(Semantic::TexCoords(0)),
            tangent: attribute(Semantic::Tangents),
            deform: deform_accessors(primitive),
        }
    }
}

/// The accessors that deform `primitive`, in a fixed order: the joint and weight sets, then
/// each morph target's positions, normals and tangents.
fn deform_accessors(primitive: &Primitive<'_>) -> Vec<Option<usize>> {
    let mut out = Vec::new();
    for set in 0.. {
        let (j, w) = (primitive.get(&Semantic::Joints(set)), primitive.get(&Semantic::Weights(set)));
        if j.is_none() && w.is_none() {
            break;
        }
        out.extend([j.map(|a| a.index()), w.map(|a| a.index())]);
    }
    for target in primitive.morph_targets() {
        out.extend([target.positions(), target.normals(), target.tangents()].map(|a| a.map(|a| a.index())));
    }
    out
}

/// Whether a primitive of this mode is drawn (the others are skipped with a report).
pub(super) fn drawable(mode: Mode) -> bool {
    matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)
}

/// The scene's totals, each within its limit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Totals {
    /// Instances: every drawable primitive of every placed node.
    pub instances: usize,
    /// Vertices of the distinct drawable primitives (at most; an unreadable accessor counts 0,
    /// its read reports it).
    pub vertices: usize,
    /// Triangle-list indices of the distinct drawable primitives (at most: strips and fans
    /// lose their degenerate triangles).
    pub indices: usize,
}

/// Counts what `placed` will hold and checks it, and the document's images, against the scene
/// limits. `file` prefixes error places.
pub(super) fn count(document: &Document, placed: &[Placed<'_>], file: &str) -> Result<Totals, SceneError> {
    let images = document.images().len();
    if images > MAX_TEXTURES {
        return Err(SceneError::invalid(
            format!("{file}: image {MAX_TEXTURES}"),
            format!("the file has {images} images; a scene may hold at most {MAX_TEXTURES} textures"),
        ));
    }
    let mut totals = Totals::default();
    // Per glTF mesh: its drawable primitives, once counted.
    let mut drawn: Vec<Option<usize>> = vec![None; document.meshes().len()];
    let mut seen = HashSet::new();
    for p in placed {
        let Some(mesh) = p.node.mesh() else { continue };
        let prims = match drawn[mesh.index()] {
            Some(n) => n,
            None => {
                let n = count_mesh(&mesh, file, &mut seen, &mut totals)?;
                drawn[mesh.index()] = Some(n);
                n
            }
        };
        totals.instances += prims;
        if totals.instances > MAX_INSTANCES {
            return Err(SceneError::invalid(
                format!("{file}: {}", node_label(&p.node)),
                format!(
                    "the {prims} primitives of its {} take the scene past {MAX_INSTANCES} instances, the most a scene may hold ({} placed before it)",
                    mesh_label(&mesh),
                    totals.instances - prims
                ),
            ));
        }
    }
    Ok(totals)
}

/// Adds the vertices and indices of `mesh`'s distinct drawable primitives not `seen` before to
/// `totals`; returns how many drawable primitives the mesh has.
fn count_mesh(
    mesh: &gltf::Mesh<'_>,
    file: &str,
    seen: &mut HashSet<PrimitiveKey>,
    totals: &mut Totals,
) -> Result<usize, SceneError> {
    let mut drawable_count = 0;
    for prim in mesh.primitives().filter(|p| drawable(p.mode())) {
        drawable_count += 1;
        if !seen.insert(PrimitiveKey::of(&prim)) {
            continue;
        }
        let Some(position) = prim.get(&Semantic::Positions) else { continue };
        let vertices = accessor::declared_count(&position).unwrap_or(0);
        let listed = match prim.indices() {
            Some(indices) => accessor::declared_count(&indices).unwrap_or(0),
            None => vertices,
        };
        let indices = match prim.mode() {
            Mode::Triangles => listed,
            _ => listed.saturating_sub(2).saturating_mul(3),
        };
        let place = |what: &str, index: usize| {
            format!("{file}: {} primitive {}, {what} accessor {index}", mesh_label(mesh), prim.index())
        };
        totals.vertices = totals.vertices.saturating_add(vertices);
        if totals.vertices > MAX_VERTICES {
            return Err(SceneError::invalid(
                place("POSITION", position.index()),
                format!(
                    "its {vertices} vertices take the scene past {MAX_VERTICES} vertices, the most a scene may hold ({} before it)",
                    totals.vertices - vertices
                ),
            ));
        }
        totals.indices = totals.indices.saturating_add(indices);
        if totals.indices > MAX_INDICES {
            let (what, index) = prim.indices().map_or(("POSITION", position.index()), |a| ("indices", a.index()));
            return Err(SceneError::invalid(
                place(what, index),
                format!(
                    "its {indices} triangle-list indices take the scene past {MAX_INDICES} indices, the most a scene may hold ({} before it)",
                    totals.indices - indices
                ),
            ));
        }
    }
    Ok(drawable_count)
}
