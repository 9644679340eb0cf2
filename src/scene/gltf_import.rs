//! glTF 2.0 import: every (mesh, primitive) pair becomes one cullgraph [`Mesh`](super::Mesh)
//! shared by all nodes that use that mesh, every node with a mesh becomes one [`Instance`] per
//! drawable primitive.
//!
//! Materials keep their textures (every glTF image becomes a scene texture, decoded to RGBA8),
//! samplers, texture transforms and alpha modes.
//!
//! Skins (joints and weights, reduced to the 4 heaviest per vertex), morph targets (position
//! and normal offsets) and animations (translation, rotation, scale and weights; STEP, LINEAR
//! and CUBICSPLINE) go to the meshes' [`MeshDeform`](super::MeshDeform) and the scene's
//! [`SceneAnimation`](super::SceneAnimation); the instances are placed in the rest pose.
//!
//! Broken files give a [`SceneError`] whose place names the file, the node or the mesh,
//! primitive and accessor (or the skin, animation and channel); they never panic. What is
//! dropped or replaced on the way (non-triangle primitives, unusable images, morphed tangents,
//! animations of nothing drawn, unused meshes) is listed in an [`ImportReport`].

mod accessor;
mod animation;
mod buffers;
mod flags;
mod images;
mod lights;
mod materials;
mod morph;
mod nodes;
mod primitive;
mod skin;
mod totals;

use super::camera::{Camera, Projection};
use super::error::SceneError;
use super::source::LoadOptions;
use super::{procedural, Instance, Material, Scene, Transform};
use glam::Vec3;
use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

pub use images::MAX_IMAGE_SIDE;
pub use primitive::{fan_to_list, strip_to_list};

pub use lights::RANGE_CUTOFF as LIGHT_RANGE_CUTOFF;

/// Point lights placed in a file that has none when [`LoadOptions::lights`] is `None`.
pub const DEFAULT_FILE_LIGHTS: usize = 4;

/// What an import left out, for the user to see (nothing is dropped silently).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ImportReport {
    /// Primitives that were not drawn, each with its place and reason
    /// (e.g. `a.gltf: mesh 'Lines' (#2) primitive 0: mode LINES cannot be drawn as triangles`).
    pub skipped_primitives: Vec<String>,
    /// Everything else that was ignored or assumed (textures, animations, extra scenes, ...).
    pub notes: Vec<String>,
}

/// Loads a glTF 2.0 file (`.gltf` with its buffers, or `.glb`), logging what the import left
/// out with `tracing::warn!`.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let (scene, report) = load_with_report(path, options)?;
    // A file with a systematic problem repeats it per primitive: show a few, count the rest.
    const SHOWN: usize = 4;
    let lines: Vec<String> = report
        .skipped_primitives
        .iter()
        .map(|s| format!("skipped primitive: {s}"))
        .chain(report.notes.iter().map(|n| format!("{}: {n}", scene.name)))
        .collect();
    for line in lines.iter().take(SHOWN) {
        tracing::warn!("{line}");
    }
    if lines.len() > SHOWN {
        tracing::warn!(
            "{}: {} more import notes like these (gltf_import::load_with_report lists them all)",
            scene.name,
            lines.len() - SHOWN
        );
    }
    Ok(scene)
}

/// Loads a glTF 2.0 file and returns the scene with the [`ImportReport`] of what was left out.
///
/// Reads the file's `KHR_lights_punctual` lights (the first directional light is the sun); a
/// file without lights gets point lights (`options.lights`, default [`DEFAULT_FILE_LIGHTS`])
/// placed above the scene.
pub fn load_with_report(path: &Path, options: &LoadOptions) -> Result<(Scene, ImportReport), SceneError> {
    let file = path.display().to_string();
    // The checks below are meant to leave the `gltf` crate nothing to panic on; this is the
    // backstop so that a hostile file still ends as an error, never as an aborted host.
    match catch_unwind(AssertUnwindSafe(|| import(path, options))) {
        Ok(result) => result,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(SceneError::Import { file, message: format!("the glTF reader failed on this file: {what}") })
        }
    }
}

/// The (cullgraph mesh, material) of a drawable primitive, `None` for a skipped one.
type DrawnPrimitive = Option<(u32, u32)>;

fn import(path: &Path, options: &LoadOptions) -> Result<(Scene, ImportReport), SceneError> {
    let file = path.display().to_string();
    let import_err = |message: String| SceneError::Import { file: file.clone(), message };
    let short = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| file.clone());
    let mut report = ImportReport::default();
    let light_count = options.lights.unwrap_or(DEFAULT_FILE_LIGHTS);
    if light_count > procedural::MAX_LIGHTS {
        return Err(import_err(format!("lights = {light_count} is out of range (at most {})", procedural::MAX_LIGHTS)));
    }

    let bytes = crate::files::read_limited(path, crate::files::SCENE_LIMIT, "scene file").map_err(import_err)?;
    let gltf = buffers::parse(&bytes, &mut report.notes).map_err(import_err)?;
    drop(bytes);
    let document = gltf.document;
    note_ignored_features(&document, &mut report.notes);

    // The hierarchy and the totals come from the document alone: a scene past a limit is
    // refused before its buffers are read or anything is allocated for it.
    let roots = nodes::roots(&document, &mut report.notes);
    let placed = nodes::walk(&document, roots, &short, &mut report.notes)?;
    let totals = totals::count(&document, &placed, &short)?;
    let mut scene = Scene { name: short.clone(), ..Default::default() };
    reserve(&mut scene, &totals).map_err(import_err)?;

    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let buffers = buffers::load_buffers(&document, base, gltf.blob).map_err(import_err)?;
    let textures = images::load(&document, base, &buffers, &mut report.notes);
    let placeholder: Vec<bool> = textures.iter().map(|(_, p)| *p).collect();
    scene.textures = textures.into_iter().map(|(t, _)| t).collect();
    for material in materials::convert(&document, &placeholder, &mut report.notes) {
        scene.add_material(material);
    }

    let mut meshes = MeshImport { buffers: &buffers, file: &short, shared: HashMap::new(), default_material: None };
    // Per glTF mesh: the (cullgraph mesh, material) of each drawable primitive, once imported.
    let mut imported: Vec<Option<Vec<DrawnPrimitive>>> = vec![None; document.meshes().len()];
    let mut candidates = Vec::new();
    for p in &placed {
        let Some(mesh) = p.node.mesh() else { continue };
        if imported[mesh.index()].is_none() {
            let prims = meshes.import(&mesh, &mut scene, &mut report)?;
            imported[mesh.index()] = Some(prims);
        }
        let what = format!("its {}", mesh_label(&mesh));
        for (prim, drawn) in imported[mesh.index()].iter().flatten().enumerate() {
            let Some((mesh_id, material)) = *drawn else { continue };
            // A node whose geometry reaches past the coordinate range is the user's to hear of
            // (lights placed above it would be refused otherwise, blaming the importer's light).
            let bounds = &scene.meshes[mesh_id as usize].bounds;
            if let Some(e) = crate::scene::validate::bounds_error(&what, bounds, &p.world) {
                return Err(SceneError::invalid(format!("{short}: {}", nodes::node_label(&p.node)), e));
            }
            let deform = scene.meshes[mesh_id as usize].deform.as_deref();
            let skinned = skinned_primitive(p, &mesh, prim, deform, &short, &mut report.notes)?;
            let targets = deform.map_or(0, |d| d.morph_targets.len());
            let instance = scene.instances.len() as u32;
            candidates.push(animation::Candidate { instance, node: p.node.index(), skinned, targets });
            scene.instances.push(Instance { transform: p.world, mesh: mesh_id, material, flags: p.flags });
        }
    }
    scene.animation = animation::build(&document, &placed, &candidates, &buffers, &short, &mut report.notes)?
        .map(std::sync::Arc::new);
    let unused = imported.iter().filter(|m| m.is_none()).count();
    if unused > 0 {
        report.notes.push(format!("{unused} meshes are not used by any node of the drawn scene and were not imported"));
    }
    if scene.instances.is_empty() {
        let why = match report.skipped_primitives.first() {
            None => "no node of the drawn scene has a mesh".to_string(),
            Some(first) => format!("{} primitive(s) skipped, the first: {first}", report.skipped_primitives.len()),
        };
        return Err(import_err(format!("nothing to draw: {why}")));
    }

    scene.camera = placed.iter().find_map(|p| camera_of(&document, p, &mut report.notes));
    let (sun, file_lights) = lights::import(&document, &placed, &mut report.notes);
    if let Some(sun) = sun {
        scene.sun = sun;
    }
    if !file_lights.is_empty() || sun.is_some() {
        scene.lights = file_lights;
    } else if let Some(bounds) = scene.world_bounds() {
        let n = light_count;
        scene.lights = procedural::lights::scatter(&bounds, n, options.seed);
        if n > 0 {
            report.notes.push(format!("the file has no lights; {n} point lights were placed above the scene"));
        }
    }
    Ok((scene, report))
}

/// Reserves the scene's pools and instance list for `totals`, fallibly: memory the host cannot
/// give is an error naming what it was for, not an aborted process.
fn reserve(scene: &mut Scene, totals: &totals::Totals) -> Result<(), String> {
    let fail = |n: usize, what: &str| format!("cannot allocate memory for the scene's {n} {what}");
    scene.instances.try_reserve_exact(totals.instances).map_err(|_| fail(totals.instances, "instances"))?;
    scene.vertices.try_reserve_exact(totals.vertices).map_err(|_| fail(totals.vertices, "vertices"))?;
    scene.indices.try_reserve_exact(totals.indices).map_err(|_| fail(totals.indices, "indices"))?;
    Ok(())
}

/// `mesh 'name' (#i)`, or `mesh #i` for an unnamed mesh.
fn mesh_label(mesh: &gltf::Mesh<'_>) -> String {
    match mesh.name() {
        Some(name) => format!("mesh '{name}' (#{})", mesh.index()),
        None => format!("mesh #{}", mesh.index()),
    }
}

/// The import of meshes into one scene's pools.
struct MeshImport<'a> {
    buffers: &'a [Vec<u8>],
    /// The file name, first in every place.
    file: &'a str,
    /// The cullgraph mesh of each distinct primitive geometry already imported (or why it is
    /// skipped): primitives that share their accessors share their mesh, whatever glTF mesh
    /// they belong to.
    shared: HashMap<totals::PrimitiveKey, Result<u32, String>>,
    /// The material given to primitives without one, once a primitive needs it.
    default_material: Option<u32>,
}

impl MeshImport<'_> {
    /// Adds the drawable primitives of `mesh` to the scene's pools (one cullgraph mesh per
    /// distinct geometry) and returns their (mesh, material) pairs; primitives that cannot be
    /// drawn go to the report.
    fn import(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        scene: &mut Scene,
        report: &mut ImportReport,
    ) -> Result<Vec<DrawnPrimitive>, SceneError> {
        let label = mesh_label(mesh);
        let no_lod =
            flags::mesh_keeps_detail(mesh).map_err(|m| SceneError::invalid(format!("{}: {label}", self.file), m))?;
        let base_name = mesh.name().map(str::to_string).unwrap_or_else(|| format!("mesh#{}", mesh.index()));
        let mut prims = Vec::new();
        for prim in mesh.primitives() {
            let place = format!("{}: {label} primitive {}", self.file, prim.index());
            let key = totals::PrimitiveKey::of(&prim);
            let converted = match self.shared.get(&key) {
                Some(converted) => converted.clone(),
                None => {
                    let converted = match primitive::convert(&prim, self.buffers, &place)? {
                        primitive::Converted::Skipped(why) => Err(why),
                        primitive::Converted::Mesh(mut data, mesh_place, notes) => {
                            report.notes.extend(notes);
                            data.no_lod = no_lod;
                            if !data.morph_targets.is_empty() {
                                data.morph_weights = mesh.weights().map(<[f32]>::to_vec).unwrap_or_default();
                            }
                            Ok(scene.add_mesh(&format!("{base_name}/{}", prim.index()), &data, &mesh_place)?)
                        }
                    };
                    self.shared.insert(key, converted.clone());
                    converted
                }
            };
            let id = match converted {
                Ok(id) => id,
                Err(why) => {
                    report.skipped_primitives.push(format!("{place}: {why}"));
                    prims.push(None);
                    continue;
                }
            };
            // glTF materials were added first, in file order, so their indices carry over.
            let material = match prim.material().index() {
                Some(i) => i as u32,
                None => *self.default_material.get_or_insert_with(|| scene.add_material(Material::default())),
            };
            prims.push(Some((id, material)));
        }
        Ok(prims)
    }
}

/// Whether primitive `prim` of `mesh`, placed at `placed`, is deformed by the node's skin: the
/// node has one and the primitive has joints. Refuses joint indices past the skin's joints; notes
/// a skin without joints to move and joints without a skin.
fn skinned_primitive(
    placed: &nodes::Placed<'_>,
    mesh: &gltf::Mesh<'_>,
    prim: usize,
    deform: Option<&crate::scene::MeshDeform>,
    file: &str,
    notes: &mut Vec<String>,
) -> Result<bool, SceneError> {
    let node = nodes::node_label(&placed.node);
    match (placed.node.skin(), deform.filter(|d| d.is_skinned())) {
        (None, None) => Ok(false),
        (Some(skin), None) => {
            notes.push(format!(
                "{node} has {} but its {} primitive {prim} has no JOINTS_0; it is drawn rigidly",
                skin::skin_label(&skin),
                mesh_label(mesh)
            ));
            Ok(false)
        }
        (None, Some(_)) => {
            notes.push(format!(
                "{node}: its {} primitive {prim} has joints but the node has no skin; it is drawn in its bind pose",
                mesh_label(mesh)
            ));
            Ok(false)
        }
        (Some(skin), Some(d)) => {
            let joints = skin.joints().len();
            if d.joint_count as usize > joints {
                let accessors: Vec<String> = mesh
                    .primitives()
                    .nth(prim)
                    .map(|p| {
                        (0..)
                            .map_while(|set| p.get(&gltf::mesh::Semantic::Joints(set)).map(|a| (set, a.index())))
                            .map(|(set, a)| format!("JOINTS_{set} accessor {a}"))
                            .collect()
                    })
                    .unwrap_or_default();
                return Err(SceneError::invalid(
                    format!("{file}: {node}: its {} primitive {prim}, {}", mesh_label(mesh), accessors.join(", ")),
                    format!(
                        "joint index {} is out of range: {} has {joints} joints",
                        d.joint_count - 1,
                        skin::skin_label(&skin)
                    ),
                ));
            }
            Ok(true)
        }
    }
}

/// The camera of a node that has one, if it is usable.
fn camera_of(document: &gltf::Document, placed: &nodes::Placed<'_>, notes: &mut Vec<String>) -> Option<Camera> {
    let camera = placed.node.camera()?;
    // The gltf crate unwraps the projection its `type` names, which its validation does not
    // require to be there.
    let json = document.as_json().cameras.get(camera.index())?;
    let (kind, present) = match json.type_ {
        gltf::json::validation::Checked::Valid(gltf::json::camera::Type::Perspective) => {
            ("perspective", json.perspective.is_some())
        }
        gltf::json::validation::Checked::Valid(gltf::json::camera::Type::Orthographic) => {
            ("orthographic", json.orthographic.is_some())
        }
        gltf::json::validation::Checked::Invalid => ("invalid", false),
    };
    if !present {
        notes.push(format!(
            "{}: camera {} ignored: its type is {kind} but it has no {kind} properties",
            nodes::node_label(&placed.node),
            camera.index()
        ));
        return None;
    }
    let w: &Transform = &placed.world;
    let forward = w.linear.mul_vec3(Vec3::NEG_Z).try_normalize()?;
    let up = w.linear.mul_vec3(Vec3::Y).try_normalize().unwrap_or(Vec3::Y);
    let (projection, near) = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            (Projection::Perspective { fov_y_deg: p.yfov().to_degrees() }, p.znear())
        }
        gltf::camera::Projection::Orthographic(o) => {
            (Projection::Orthographic { height: 2.0 * o.ymag().abs(), far: o.zfar() }, o.znear().max(1e-3))
        }
    };
    let eye = w.translation;
    let cam = Camera { eye, target: eye + forward.as_dvec3() * 10.0, up, projection, near, ..Default::default() };
    match cam.validate() {
        Ok(()) => Some(cam),
        Err(why) => {
            notes.push(format!("{}: camera ignored: {why}", nodes::node_label(&placed.node)));
            None
        }
    }
}

/// Extensions the import applies.
const SUPPORTED_EXTENSIONS: [&str; 2] = ["KHR_texture_transform", "KHR_lights_punctual"];

/// Notes for parts of the file that cullgraph does not use.
fn note_ignored_features(document: &gltf::Document, notes: &mut Vec<String>) {
    let used: Vec<&str> = document.extensions_used().filter(|e| !SUPPORTED_EXTENSIONS.contains(e)).collect();
    if !used.is_empty() {
        notes.push(format!("extensions are ignored: {}", used.join(", ")));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_file_is_an_import_error() {
        let e = load(Path::new("/nonexistent/x.glb"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(e, SceneError::Import { .. }), "{e}");
        assert!(e.to_string().contains("cannot read the scene file"), "{e}");
    }
}
