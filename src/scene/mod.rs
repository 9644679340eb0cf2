//! The scene model: one vertex/index pool, a mesh table with local bounds, materials, instances
//! and lights; glTF import and procedural generators fill it.
//!
//! Instance translations are `f64` on the CPU so that worlds far from the origin keep their
//! precision; the GPU receives them as hi/lo `f32` pairs and subtracts the eye position first.

pub mod animation;
pub mod bounds;
pub mod camera;
pub mod camera_path;
pub mod cascades;
pub mod clusters;
pub mod deform;
pub mod error;
pub mod gltf_import;
pub mod light_faces;
pub mod lod;
pub mod merge;
pub mod mesh;
pub mod pool_ranges;
pub mod posing;
pub mod procedural;
pub mod projection;
pub mod source;
mod tangents;
pub mod texture;
pub mod validate;
pub mod world;

pub use animation::{InstancePose, SceneAnimation};
pub use bounds::{Aabb, Sphere};
pub use camera::Camera;
pub use camera_path::CameraPath;
pub use deform::{MeshDeform, MorphTarget};
pub use error::SceneError;
pub use lod::{LodChain, LodLevel, MAX_LOD_LEVELS};
pub use mesh::{decode_octahedral, encode_octahedral, encode_tangent, MeshData, MeshParts, Vertex};
pub use projection::{Projection, ProjectionParts};
pub use source::SceneSource;
pub use texture::{AlphaMode, Texture, TextureRef, TextureSlot};

use glam::{DVec3, Mat3, Vec3};

/// Instance flag: a large, cheap object that the occluder pre-pass may draw first. In glTF:
/// node extras `{"cullgraph": {"occluder": true}}` (that node and those below it).
pub const FLAG_OCCLUDER: u32 = 1 << 0;

/// The largest world coordinate (of an instance, light or camera) a scene may use: 2^40, about
/// 1.1e12 units. The GPU gets positions as a float on a power-of-two grid plus a float
/// remainder, subtracted from the eye's exactly; below 2^24 the grid is whole units and
/// whole-unit offsets change no bit, and up to 2^40 a position keeps 1/256 unit or better.
/// Farther out the remainder rounds to whole units and more, so the image would be wrong.
pub const MAX_COORDINATE: f64 = (1u64 << 40) as f64;

/// Why a world position is refused, if it is: not finite, or beyond [`MAX_COORDINATE`].
pub fn position_error(what: &str, p: glam::DVec3) -> Option<String> {
    if !p.is_finite() {
        Some(format!("{what} {p} is not finite"))
    } else if p.abs().max_element() > MAX_COORDINATE {
        Some(format!(
            "{what} {p} is beyond ±{MAX_COORDINATE:.0} (2^40) units, where positions stop keeping 1/256 unit of precision on the GPU"
        ))
    } else {
        None
    }
}
/// Instance flag: render this object with one sample per pixel (selective anti-aliasing). In
/// glTF: node extras `{"cullgraph": {"no_aa": true}}`.
pub const FLAG_NO_AA: u32 = 1 << 1;

/// Set by the renderer, never by scenes: a GPU slot that holds no instance (room a draw group
/// keeps for instances to come, or one removed). Its instance record is all zeros, which draws
/// nothing, and culling skips it.
pub const FLAG_EMPTY_SLOT: u32 = 1 << 6;

/// A range of the shared index pool with its local-space bounds; one draw group.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Name for messages and stats (glTF mesh name plus primitive index, or generator kind).
    pub name: String,
    /// First index in [`Scene::indices`].
    pub first_index: u32,
    /// Number of indices (a multiple of 3).
    pub index_count: u32,
    /// Added to every index of this mesh to reach [`Scene::vertices`].
    pub vertex_offset: u32,
    /// Number of vertices this mesh owns, starting at `vertex_offset`: the full mesh's, then its
    /// levels of detail's own copies ([`lod::LodChain::vertices`]).
    pub vertex_count: u32,
    /// Local-space axis-aligned bounds.
    pub bounds: Aabb,
    /// Local-space bounding sphere (contains `bounds`' vertices).
    pub sphere: Sphere,
    /// How the mesh deforms (skin influences, morph targets); `None` for a rigid mesh. Its
    /// `bounds` and `sphere` are those of the rest shape.
    pub deform: Option<std::sync::Arc<deform::MeshDeform>>,
    /// Simplified levels of detail, coarser and coarser ([`lod`]), their indices in the pool
    /// right after the full mesh's ([`Mesh::index_span`]); empty for a mesh that is always
    /// drawn whole (small, deformed, or [`MeshData::no_lod`]).
    pub lods: Vec<LodLevel>,
    /// Per level of detail (the full mesh first, then each of `lods`), its clusters
    /// ([`clusters`]), whose ranges cover the level's indices in order; empty (or shorter than
    /// the levels) where a level is drawn whole: small, deformed, or registered on a live world.
    pub clusters: Vec<Vec<clusters::Cluster>>,
}

impl Mesh {
    /// The indices the mesh holds in the pool: the full mesh's and then its levels of detail's,
    /// one range from `first_index`.
    pub fn index_span(&self) -> u32 {
        self.index_count + self.lods.iter().map(|l| l.index_count).sum::<u32>()
    }
}

/// Surface parameters of the shading model (glTF metallic-roughness): factors, each multiplied
/// by its texture where the material has one.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name for messages.
    pub name: String,
    /// Linear base color.
    pub albedo: Vec3,
    /// Base colour alpha (coverage where [`Material::alpha_mode`] uses it).
    pub alpha: f32,
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Emitted linear radiance.
    pub emissive: Vec3,
    /// Both sides are drawn (glTF `doubleSided`); otherwise back faces are culled, the winding
    /// that counts as front being flipped for mirrored instances as glTF specifies.
    pub double_sided: bool,
    /// How alpha is used.
    pub alpha_mode: AlphaMode,
    /// The textures, indexed by [`TextureSlot`] (`textures[slot as usize]`).
    pub textures: [Option<TextureRef>; 5],
    /// Scale of the normal texture's x and y.
    pub normal_scale: f32,
    /// How much the occlusion texture darkens (0: not at all, 1: fully).
    pub occlusion_strength: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            albedo: Vec3::splat(0.8),
            alpha: 1.0,
            roughness: 0.6,
            metallic: 0.0,
            emissive: Vec3::ZERO,
            double_sided: false,
            alpha_mode: AlphaMode::Opaque,
            textures: [None; 5],
            normal_scale: 1.0,
            occlusion_strength: 1.0,
        }
    }
}

impl Material {
    /// Whether the material emits light or darkens its ambient light: it has an emissive colour,
    /// or an occlusion texture with a strength above 0.
    pub fn has_emission_or_occlusion(&self) -> bool {
        self.emissive.max_element() > 0.0
            || (self.texture(TextureSlot::Occlusion).is_some() && self.occlusion_strength > 0.0)
    }

    /// Whether the material samples any texture (and so reads texture coordinates).
    pub fn samples_textures(&self) -> bool {
        self.textures.iter().any(Option::is_some)
    }

    /// The texture of `slot`, if any.
    pub fn texture(&self, slot: TextureSlot) -> Option<&TextureRef> {
        self.textures[slot as usize].as_ref()
    }
}

/// An affine transform with a double-precision translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Rotation and scale (may be mirrored or degenerate; validation decides).
    pub linear: Mat3,
    /// World-space translation.
    pub translation: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self { linear: Mat3::IDENTITY, translation: DVec3::ZERO }
    }
}

impl Transform {
    /// Transform of a point (in double precision).
    pub fn apply(&self, p: Vec3) -> DVec3 {
        self.linear.mul_vec3(p).as_dvec3() + self.translation
    }

    /// `self` after `child` (parent * child).
    pub fn then(&self, child: &Transform) -> Transform {
        Transform {
            linear: self.linear * child.linear,
            translation: self.linear.as_dmat3() * child.translation + self.translation,
        }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.linear.is_finite() && self.translation.is_finite()
    }

    /// World-space AABB (min, max) of the local box `bounds` under this transform.
    pub fn bounds_of(&self, bounds: &Aabb) -> (DVec3, DVec3) {
        let center = self.apply(bounds.center());
        // |M| * half-extent bounds the transformed box exactly for an affine map.
        let abs = Mat3::from_cols(self.linear.x_axis.abs(), self.linear.y_axis.abs(), self.linear.z_axis.abs());
        let half = abs.mul_vec3(bounds.half_extent()).as_dvec3();
        (center - half, center + half)
    }
}

/// One placed copy of a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Local-to-world transform.
    pub transform: Transform,
    /// Index into [`Scene::meshes`].
    pub mesh: u32,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// `FLAG_*` bits.
    pub flags: u32,
}

/// A point light with a finite range (its contribution is 0 beyond it), or a spot light when
/// it has a cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// World position.
    pub position: DVec3,
    /// Linear color times intensity.
    pub color: Vec3,
    /// Distance at which the light's contribution reaches zero.
    pub range: f32,
    /// The cone of a spot light (`None`: it shines every way).
    pub spot: Option<SpotCone>,
}

impl PointLight {
    /// A light shining every way.
    pub fn point(position: DVec3, color: Vec3, range: f32) -> Self {
        Self { position, color, range, spot: None }
    }
}

/// The cone of a spot light, as `KHR_lights_punctual` defines it: full intensity within
/// `inner_angle` of `direction`, falling smoothly to 0 at `outer_angle`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotCone {
    /// Direction the light travels (normalised).
    pub direction: Vec3,
    /// Radians from the axis where the falloff starts (0 to `outer_angle`).
    pub inner_angle: f32,
    /// Radians from the axis where the light ends (above 0, at most pi/2).
    pub outer_angle: f32,
}

/// What is wrong with a spot light's cone, if anything.
pub(crate) fn spot_cone_error(cone: &SpotCone) -> Option<String> {
    let d = cone.direction;
    if !d.is_finite() || (d.length() - 1.0).abs() > 1e-3 {
        return Some(format!("spot direction {d} must be finite and of length 1"));
    }
    let (inner, outer) = (cone.inner_angle, cone.outer_angle);
    let ok = inner.is_finite()
        && outer.is_finite()
        && inner >= 0.0
        && inner <= outer
        && outer > 0.0
        && outer <= std::f32::consts::FRAC_PI_2 + 1e-6;
    (!ok).then(|| format!("spot angles inner {inner}, outer {outer}: need 0 <= inner <= outer, 0 < outer <= pi/2"))
}

/// Where [`Scene::put_mesh`] writes a mesh: its first vertex and first index in the pools, and
/// its entry in the mesh table (`None`: a new one).
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshPlace {
    pub vertex: usize,
    pub index: usize,
    pub slot: Option<u32>,
}

/// A directional light (the sun).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Direction the light travels (normalised).
    pub direction: Vec3,
    /// Linear color times intensity.
    pub color: Vec3,
}

impl Default for DirectionalLight {
    fn default() -> Self {
        // Low enough that walls facing it are lit and those facing away fall to the sky ambient.
        Self { direction: Vec3::new(-0.55, -0.7, -0.45).normalize(), color: Vec3::new(2.0, 1.9, 1.75) }
    }
}

/// Everything that is drawn: geometry pool, mesh table, materials, instances, lights.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Name for stats (file name or `builtin:...`).
    pub name: String,
    /// Shared vertex pool.
    pub vertices: Vec<Vertex>,
    /// Shared index pool; indices are relative to their mesh's `vertex_offset`.
    pub indices: Vec<u32>,
    /// Mesh table (draw groups).
    pub meshes: Vec<Mesh>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Decoded textures, shared (a scene is cloned where it is laid out anew; its pixels need
    /// not be).
    pub textures: Vec<std::sync::Arc<Texture>>,
    /// Instances.
    pub instances: Vec<Instance>,
    /// Point lights.
    pub lights: Vec<PointLight>,
    /// The sun.
    pub sun: DirectionalLight,
    /// A camera the source suggests (glTF camera), if any.
    pub camera: Option<Camera>,
    /// What plays the scene's animations (glTF skins, morph weights, node animations): the
    /// instances they move and the clips; `None` for a static scene.
    pub animation: Option<std::sync::Arc<SceneAnimation>>,
}

impl Scene {
    /// Appends a mesh to the pools; validates indices and normals and computes bounds.
    ///
    /// `place` names the mesh in errors (e.g. `mesh 'wall' primitive 0 (accessor 3)`).
    ///
    /// The mesh gets its chain of levels of detail ([`lod`]) unless it is deformed or
    /// [`MeshData::no_lod`] says not to.
    pub fn add_mesh(&mut self, name: &str, data: &MeshData, place: &str) -> Result<u32, SceneError> {
        let at = MeshPlace { vertex: self.vertices.len(), index: self.indices.len(), slot: None };
        let (vertices, bounds, sphere, deform) = data.validate(place)?;
        let (vertices, levels) = lod::with_chain(data, vertices, deform.is_some());
        let deform = deform.map(std::sync::Arc::new);
        let mesh = self.put_mesh_vertices(name, &vertices, &data.indices, (bounds, sphere, deform), place, at)?;
        let start = self.indices.len();
        self.put_lod_chain(mesh, levels, start, place)?;
        self.add_clusters(mesh);
        Ok(mesh)
    }

    /// Splits each level of mesh `mesh` (the full mesh and its levels of detail) large enough
    /// into clusters, its indices rewritten in cluster order in place (none for a deformed
    /// mesh).
    pub(crate) fn add_clusters(&mut self, mesh: u32) {
        let m = &self.meshes[mesh as usize];
        if m.deform.is_some() {
            return;
        }
        let vertices = &self.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize];
        let ranges: Vec<(u32, u32)> = std::iter::once((m.first_index, m.index_count))
            .chain(m.lods.iter().map(|l| (l.first_index, l.index_count)))
            .collect();
        let mut levels = Vec::new();
        for (first, count) in ranges {
            let range = first as usize..(first + count) as usize;
            let Some((ordered, mut clusters)) = clusters::build(vertices, &self.indices[range.clone()]) else {
                break;
            };
            self.indices[range].copy_from_slice(&ordered);
            for c in &mut clusters {
                c.first_index += first;
            }
            levels.push(clusters);
        }
        self.meshes[mesh as usize].clusters = levels;
    }

    /// Writes `chain` as mesh `mesh`'s levels of detail, their indices one after the other from
    /// `start` in the index pool (growing it where they run past its end).
    pub(crate) fn put_lod_chain(
        &mut self,
        mesh: u32,
        chain: Vec<(Vec<u32>, f32)>,
        start: usize,
        place: &str,
    ) -> Result<(), SceneError> {
        let more: usize = chain.iter().map(|(i, _)| i.len()).sum();
        let end = start + more;
        u32::try_from(end).map_err(|_| SceneError::too_large(place, "index pool"))?;
        let grow = end.saturating_sub(self.indices.len());
        self.indices
            .try_reserve(grow)
            .map_err(|_| SceneError::invalid(place, format!("cannot allocate memory for {grow} more indices")))?;
        if self.indices.len() < end {
            self.indices.resize(end, 0);
        }
        let mut lods = Vec::with_capacity(chain.len());
        let mut at = start;
        for (indices, error) in chain {
            lods.push(LodLevel { first_index: at as u32, index_count: indices.len() as u32, error });
            self.indices[at..at + indices.len()].copy_from_slice(&indices);
            at += indices.len();
        }
        self.meshes[mesh as usize].lods = lods;
        Ok(())
    }

    /// Writes a mesh's vertices and indices, checked before, at `at` in the pools (growing them
    /// where it runs past their end) with its bounds and deformation, and its entry at `at.slot`
    /// of the mesh table (appended when `None`); returns its index. What a live world does to
    /// reuse the pool space of removed meshes.
    pub(crate) fn put_mesh_vertices(
        &mut self,
        name: &str,
        vertices: &[Vertex],
        indices: &[u32],
        (bounds, sphere, deform): (Aabb, Sphere, Option<std::sync::Arc<deform::MeshDeform>>),
        place: &str,
        at: MeshPlace,
    ) -> Result<u32, SceneError> {
        let mesh = Mesh {
            name: name.into(),
            first_index: u32::try_from(at.index).map_err(|_| SceneError::too_large(place, "index pool"))?,
            index_count: indices.len() as u32,
            vertex_offset: u32::try_from(at.vertex).map_err(|_| SceneError::too_large(place, "vertex pool"))?,
            vertex_count: vertices.len() as u32,
            bounds,
            sphere,
            deform,
            lods: Vec::new(),
            clusters: Vec::new(),
        };
        // Pools of millions of entries: a failed allocation is this mesh's error, not an abort.
        let no_memory =
            |what: &str, n: usize| SceneError::invalid(place, format!("cannot allocate memory for {n} more {what}"));
        let vertex_end = at.vertex + vertices.len();
        let index_end = at.index + indices.len();
        let more_vertices = vertex_end.saturating_sub(self.vertices.len());
        let more_indices = index_end.saturating_sub(self.indices.len());
        self.vertices.try_reserve(more_vertices).map_err(|_| no_memory("vertices", more_vertices))?;
        self.indices.try_reserve(more_indices).map_err(|_| no_memory("indices", more_indices))?;
        if self.vertices.len() < vertex_end {
            self.vertices.resize(vertex_end, Default::default());
        }
        if self.indices.len() < index_end {
            self.indices.resize(index_end, 0);
        }
        self.vertices[at.vertex..vertex_end].copy_from_slice(vertices);
        self.indices[at.index..index_end].copy_from_slice(indices);
        match at.slot {
            Some(slot) => {
                self.meshes[slot as usize] = mesh;
                Ok(slot)
            }
            None => {
                self.meshes.push(mesh);
                Ok(self.meshes.len() as u32 - 1)
            }
        }
    }

    /// Whether some material emits light or has an occlusion texture
    /// ([`Material::has_emission_or_occlusion`]).
    pub fn has_emission_or_occlusion(&self) -> bool {
        self.materials.iter().any(Material::has_emission_or_occlusion)
    }

    /// Whether some material is alpha-masked.
    pub fn has_alpha_masks(&self) -> bool {
        self.materials.iter().any(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. }))
    }

    /// Whether some material samples a texture ([`Material::samples_textures`]).
    pub fn samples_textures(&self) -> bool {
        self.materials.iter().any(Material::samples_textures)
    }

    /// Appends a material and returns its index.
    pub fn add_material(&mut self, material: Material) -> u32 {
        self.materials.push(material);
        self.materials.len() as u32 - 1
    }

    /// World-space AABB of one instance (the transformed corners of its mesh's local AABB).
    pub fn instance_bounds(&self, instance: &Instance) -> (DVec3, DVec3) {
        instance.transform.bounds_of(&self.meshes[instance.mesh as usize].bounds)
    }

    /// World-space bounds of all instances (`None` for an empty scene).
    pub fn world_bounds(&self) -> Option<(DVec3, DVec3)> {
        self.instances.iter().map(|i| self.instance_bounds(i)).reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }

    /// Moves every instance, light and the scene's own camera by `offset` (a large-world test:
    /// the image must not change when the camera moves with it).
    pub fn translate(&mut self, offset: DVec3) {
        for instance in &mut self.instances {
            instance.transform.translation += offset;
        }
        for light in &mut self.lights {
            light.position += offset;
        }
        if let Some(animation) = &mut self.animation {
            let animation = std::sync::Arc::make_mut(animation);
            let mut placement = animation.placement();
            placement.translation += offset;
            animation.set_placement(placement);
        }
        if let Some(camera) = &mut self.camera {
            camera.eye += offset;
            camera.target += offset;
        }
    }

    /// Total triangles over all instances.
    pub fn instanced_triangles(&self) -> u64 {
        self.instances.iter().map(|i| self.meshes[i.mesh as usize].index_count as u64 / 3).sum()
    }

    /// A camera that shows the whole scene: the source's own if it has one, else a framing view.
    pub fn default_camera(&self, aspect: f32) -> Camera {
        if let Some(c) = &self.camera {
            return c.clone();
        }
        match self.world_bounds() {
            Some((min, max)) => Camera::framing(min, max, aspect),
            None => Camera::default(),
        }
    }
}
