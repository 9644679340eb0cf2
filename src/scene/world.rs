//! A scene that changes while it is rendered: instances inserted, changed and removed through
//! persistent handles, meshes and materials registered at run time, point lights added, moved
//! and removed.
//!
//! An instance's handle is its index in the instance table plus a generation: a removed index
//! goes on a free list and is reused by a later insert with the next generation, so a handle kept
//! past its removal is refused ([`WorldError::Stale`]) rather than reaching the instance that
//! took its place. The GPU keeps an instance at its index, so that per-instance culling history
//! stays attached to it across frames.
//!
//! Every change is recorded in a journal with the world's version. A renderer remembers the
//! version it last applied and takes only the changes after it ([`World::changes_since`]); one
//! world can serve several renderers, each at its own version. The journal is trimmed with
//! [`World::trim_journal`] (to the oldest version a consumer still needs); a consumer whose
//! version was trimmed away reloads everything.
//!
//! Every method checks its input before changing anything: a bulk change is applied whole or
//! not at all.

use super::{DirectionalLight, Instance, Material, MeshData, PointLight, Scene, SceneError, Transform};
use std::fmt;

/// A persistent reference to one instance of a [`World`]; it belongs to that world, and any
/// other refuses it ([`WorldError::ForeignHandle`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct InstanceHandle {
    index: u32,
    generation: u32,
    world: u32,
}

impl InstanceHandle {
    /// The instance's index: where the GPU keeps it (its slot in the instance buffers).
    pub fn index(self) -> u32 {
        self.index
    }

    /// How many instances held this index before this one.
    pub fn generation(self) -> u32 {
        self.generation
    }

    /// The id of the world it belongs to ([`World::id`]).
    pub fn world(self) -> u32 {
        self.world
    }
}

impl fmt::Display for InstanceHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "instance #{} (generation {})", self.index, self.generation)
    }
}

/// A persistent reference to one point light of a [`World`]; it belongs to that world, like
/// an [`InstanceHandle`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LightHandle {
    index: u32,
    generation: u32,
    world: u32,
}

impl LightHandle {
    /// The light's index in the light table.
    pub fn index(self) -> u32 {
        self.index
    }

    /// The id of the world it belongs to ([`World::id`]).
    pub fn world(self) -> u32 {
        self.world
    }
}

impl fmt::Display for LightHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "light #{} (generation {})", self.index, self.generation)
    }
}

/// Why a change to a [`World`] was refused. Nothing was changed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WorldError {
    /// The handle's instance or light was removed.
    #[error("{handle}: stale handle (removed)")]
    Stale {
        /// The handle, as displayed.
        handle: String,
    },
    /// A renderer of one world was given another to sync with.
    #[error("sync: this renderer renders world {renders}; world {given} was given (a renderer renders the world it was made from)")]
    ForeignWorld {
        /// The world the renderer was made from.
        renders: u32,
        /// The world it was given.
        given: u32,
    },
    /// The handle belongs to another world.
    #[error("{handle}: a handle of world {owner} given to world {world}")]
    ForeignHandle {
        /// The handle, as displayed.
        handle: String,
        /// The world it belongs to.
        owner: u32,
        /// The world it was given to.
        world: u32,
    },
    /// A mesh index that names no registered mesh.
    #[error("{handle}: mesh {mesh} does not exist ({meshes} meshes are registered)")]
    UnknownMesh {
        /// What referred to it.
        handle: String,
        /// The index given.
        mesh: u32,
        /// Meshes there are.
        meshes: usize,
    },
    /// A material index that names no registered material.
    #[error("{handle}: material {material} does not exist ({materials} materials are registered)")]
    UnknownMaterial {
        /// What referred to it.
        handle: String,
        /// The index given.
        material: u32,
        /// Materials there are.
        materials: usize,
    },
    /// A value the GPU cannot use: not finite, a zero scale, beyond the world's range, flags
    /// beyond 6 bits.
    #[error("{handle}: {message}")]
    Invalid {
        /// What it was given to.
        handle: String,
        /// What is wrong.
        message: String,
    },
    /// A mesh or material that instances still use cannot be unregistered.
    #[error("{what} is used by {users} instance(s), the first {first}; remove or re-mesh them first")]
    InUse {
        /// The mesh or material.
        what: String,
        /// How many instances use it.
        users: usize,
        /// One of them.
        first: InstanceHandle,
    },
    /// Mesh data or a material the scene refuses.
    #[error(transparent)]
    Scene(#[from] SceneError),
}

/// One change, by what it touched: the renderer reloads that entry whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Change {
    /// The instance at this index was inserted, changed or removed.
    Instance(u32),
    /// The instance at this index moved: only its transform changed (the cheap path of a
    /// renderer's sync).
    Transform(u32),
    /// The point light at this index was added, moved or removed.
    Light(u32),
    /// This mesh was registered or unregistered.
    Mesh(u32),
    /// This material was registered, changed or unregistered.
    Material(u32),
    /// This texture was registered.
    Texture(u32),
    /// The sun changed.
    Sun,
    /// The user data of the instance at this index changed ([`World::set_user_data`]).
    UserData(u32),
    /// The pose of the instance at this index changed ([`World::set_pose`]).
    Pose(u32),
}

/// The most 32-bit words of user data an instance may carry ([`World::with_user_data`]).
pub const MAX_USER_WORDS: u32 = 16;

/// Slots of a table with generations and a free list.
#[derive(Clone, Debug, Default)]
struct Slots {
    generations: Vec<u32>,
    alive: Vec<bool>,
    /// Free indices, reused last-freed first.
    free: Vec<u32>,
    live: usize,
}

impl Slots {
    /// A table of `n` live entries.
    fn full(n: usize) -> Self {
        Self { generations: vec![0; n], alive: vec![true; n], free: Vec::new(), live: n }
    }

    fn check(&self, index: u32, generation: u32) -> bool {
        let i = index as usize;
        self.alive.get(i).copied().unwrap_or(false) && self.generations[i] == generation
    }

    /// Asks for the memory [`Slots::check`] of `index` reads ([`crate::parallel::prefetch`]).
    fn prefetch(&self, index: u32) {
        if let (Some(alive), Some(generation)) = (self.alive.get(index as usize), self.generations.get(index as usize))
        {
            crate::parallel::prefetch(alive);
            crate::parallel::prefetch(generation);
        }
    }

    /// The index the next insert takes, and its generation.
    fn next(&self) -> (u32, u32) {
        match self.free.last() {
            Some(&i) => (i, self.generations[i as usize]),
            None => (self.alive.len() as u32, 0),
        }
    }

    fn take(&mut self) -> (u32, u32) {
        let (index, generation) = self.next();
        if self.free.pop().is_none() {
            self.generations.push(0);
            self.alive.push(true);
        } else {
            self.alive[index as usize] = true;
        }
        self.live += 1;
        (index, generation)
    }

    fn release(&mut self, index: u32) {
        let i = index as usize;
        self.alive[i] = false;
        self.generations[i] = self.generations[i].wrapping_add(1);
        self.free.push(index);
        self.live -= 1;
    }
}

/// A world's id, unique in the process; a clone of it is a fresh id, so that a cloned
/// [`World`] is another world.
#[derive(Debug)]
struct Id(u32);

impl Id {
    fn fresh() -> Self {
        static NEXT_ID: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(1);
        // Relaxed: only uniqueness matters.
        Self(NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }
}

impl Clone for Id {
    fn clone(&self) -> Self {
        Self::fresh()
    }
}

/// A scene that changes between frames; see the module documentation.
///
/// A clone is another world, with an id of its own: the original's handles are refused by it
/// (its own come from [`World::handles`] and [`World::handle_at`]), and a renderer of the
/// original refuses to sync it. (With the same id, a clone that changed apart from the original
/// would pass a renderer's check while its journal and version mean other changes.)
#[derive(Clone, Debug)]
pub struct World {
    /// This world's id, unique in the process: what its handles carry.
    id: Id,
    /// Meshes, materials, the sun and the camera as in a [`Scene`]; `instances` and `lights`
    /// hold every index ever used, removed ones included (see [`World::is_live`]).
    scene: Scene,
    instances: Slots,
    lights: Slots,
    /// Whether each mesh is registered.
    meshes_live: Vec<bool>,
    /// Entries of the mesh table that unregistered meshes left, reused by later registrations.
    free_meshes: Vec<u32>,
    /// Free ranges of the vertex and index pools, given back by unregistered meshes.
    vertex_ranges: super::pool_ranges::PoolRanges,
    index_ranges: super::pool_ranges::PoolRanges,
    materials_live: Vec<bool>,
    /// Texture indices that removed textures left, reused by later registrations.
    free_textures: Vec<u32>,
    /// Changes in order; the first is the change that made version `journal_start + 1`.
    journal: Vec<Change>,
    journal_start: u64,
    /// Words of user data per instance, and every instance index's words.
    user_words: u32,
    user_data: Vec<u32>,
    /// The posed instances by index, and the joint boxes of each deformable mesh posed so far.
    poses: std::collections::BTreeMap<u32, super::posing::Pose>,
    joint_boxes: std::collections::HashMap<u32, std::sync::Arc<super::posing::JointBoxes>>,
}

impl World {
    /// A world holding `scene` (checked as at load), every instance live: the handle of instance
    /// `i` of the scene is `handles[i]`.
    pub fn new(scene: Scene) -> Result<(Self, Vec<InstanceHandle>), SceneError> {
        Self::with_user_data(scene, 0)
    }

    /// As [`World::new`], every instance carrying `words` 32-bit words of user data (at most
    /// [`MAX_USER_WORDS`]), zero until set ([`World::set_user_data`]). The GPU holds them per
    /// slot, beside the instance records: the renderer's `Renderer::user_data` buffer, which a
    /// graph reads as the imported buffer `user_data`.
    pub fn with_user_data(scene: Scene, words: u32) -> Result<(Self, Vec<InstanceHandle>), SceneError> {
        if words > MAX_USER_WORDS {
            return Err(SceneError::invalid(
                "the world's user data",
                format!("{words} words an instance; at most {MAX_USER_WORDS}"),
            ));
        }
        super::validate::validate_contents(&scene)?;
        let n = scene.instances.len();
        let id = Id::fresh();
        let world = Self {
            id,
            instances: Slots::full(n),
            lights: Slots::full(scene.lights.len()),
            meshes_live: vec![true; scene.meshes.len()],
            free_meshes: Vec::new(),
            vertex_ranges: super::pool_ranges::PoolRanges::new(scene.vertices.len() as u32),
            index_ranges: super::pool_ranges::PoolRanges::new(scene.indices.len() as u32),
            materials_live: vec![true; scene.materials.len()],
            free_textures: Vec::new(),
            user_words: words,
            user_data: vec![0; n * words as usize],
            poses: Default::default(),
            joint_boxes: Default::default(),
            scene,
            journal: Vec::new(),
            journal_start: 0,
        };
        let handles = (0..n as u32).map(|index| InstanceHandle { index, generation: 0, world: world.id.0 }).collect();
        Ok((world, handles))
    }

    /// The scene as the GPU mirrors it: every instance index ever used, removed ones included.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The world as a plain scene: its live instances (in index order) and live lights. The
    /// scene's animation is left out: its instance indices are the world's, which this
    /// compacts (a world plays an animation through handles, as `render --animate` does).
    pub fn live_scene(&self) -> Scene {
        let scene = &self.scene;
        Scene {
            animation: None,
            instances: (0..scene.instances.len() as u32)
                .filter(|&i| self.is_live(i))
                .map(|i| scene.instances[i as usize])
                .collect(),
            lights: (0..scene.lights.len() as u32)
                .filter(|&i| self.is_light_live(i))
                .map(|i| scene.lights[i as usize])
                .collect(),
            ..scene.clone()
        }
    }

    /// Whether the instance at `index` is live.
    pub fn is_live(&self, index: u32) -> bool {
        self.instances.alive.get(index as usize).copied().unwrap_or(false)
    }

    /// Live instances.
    pub fn live_instances(&self) -> usize {
        self.instances.live
    }

    /// Instance indices in use so far (live or removed): the size of the GPU's instance table.
    pub fn instance_slots(&self) -> usize {
        self.instances.alive.len()
    }

    /// The handles of every live instance, in index order.
    pub fn handles(&self) -> impl Iterator<Item = InstanceHandle> + '_ {
        (0..self.instances.alive.len() as u32).filter(|&i| self.is_live(i)).map(|index| InstanceHandle {
            index,
            generation: self.instances.generations[index as usize],
            world: self.id.0,
        })
    }

    /// The handle of the live instance at `index`.
    pub fn handle_at(&self, index: u32) -> Option<InstanceHandle> {
        self.is_live(index).then(|| InstanceHandle {
            index,
            generation: self.instances.generations[index as usize],
            world: self.id.0,
        })
    }

    /// The instance `handle` refers to.
    pub fn instance(&self, handle: InstanceHandle) -> Result<&Instance, WorldError> {
        self.check_instance(handle)?;
        Ok(&self.scene.instances[handle.index as usize])
    }

    /// The version: how many changes the world has had.
    pub fn version(&self) -> u64 {
        self.journal_start + self.journal.len() as u64
    }

    /// The changes after `version`, oldest first (one entry per change, so an instance changed
    /// twice appears twice); `None` when the journal no longer reaches back that far.
    pub fn changes_since(&self, version: u64) -> Option<&[Change]> {
        let from = version.checked_sub(self.journal_start)? as usize;
        self.journal.get(from..)
    }

    /// Records one change. The journal stays bounded even if nobody trims it: past
    /// [`World::journal_limit`] entries the older half is forgotten, and a consumer that had not
    /// caught up reloads everything (which is always correct, only slower).
    fn record(&mut self, change: Change) {
        self.journal.push(change);
        self.bound_journal();
    }

    /// Forgets the older half of the journal once it is past [`World::journal_limit`].
    fn bound_journal(&mut self) {
        let limit = self.journal_limit();
        if self.journal.len() > limit {
            self.trim_journal(self.version() - (limit / 2) as u64);
        }
    }

    /// The most changes the journal keeps: twice the instance and light tables, and at least
    /// 2^16 (a renderer that syncs every frame falls behind only in a frame that changes every
    /// instance more than once).
    pub fn journal_limit(&self) -> usize {
        (2 * (self.instances.alive.len() + self.lights.alive.len())).max(1 << 16)
    }

    /// Forgets the changes up to `version`: the oldest version a consumer still needs (for
    /// renderers, the least of their `Renderer::synced_version`).
    pub fn trim_journal(&mut self, version: u64) {
        let n = (version.saturating_sub(self.journal_start) as usize).min(self.journal.len());
        self.journal.drain(..n);
        self.journal_start += n as u64;
    }

    /// This world's id, unique in the process; its handles carry it.
    pub fn id(&self) -> u32 {
        self.id.0
    }

    fn check_instance(&self, handle: InstanceHandle) -> Result<(), WorldError> {
        check_instance_in(&self.instances, &self.id, handle)
    }

    fn check_light(&self, handle: LightHandle) -> Result<(), WorldError> {
        self.check_owner(handle.world, || handle.to_string())?;
        if self.lights.check(handle.index, handle.generation) {
            Ok(())
        } else {
            Err(WorldError::Stale { handle: handle.to_string() })
        }
    }

    fn check_owner(&self, owner: u32, handle: impl FnOnce() -> String) -> Result<(), WorldError> {
        check_owner_in(&self.id, owner, handle)
    }

    /// An error when `mesh` is not registered, naming `who` (formatted only then).
    fn unknown_mesh(&self, who: impl FnOnce() -> String, mesh: u32) -> Option<WorldError> {
        let live = |l: &&bool| **l;
        (!self.meshes_live.get(mesh as usize).copied().unwrap_or(false)).then(|| WorldError::UnknownMesh {
            handle: who(),
            mesh,
            meshes: self.meshes_live.iter().filter(live).count(),
        })
    }

    /// An error when `material` is not registered, naming `who` (formatted only then).
    fn unknown_material(&self, who: impl FnOnce() -> String, material: u32) -> Option<WorldError> {
        let live = |l: &&bool| **l;
        (!self.materials_live.get(material as usize).copied().unwrap_or(false)).then(|| WorldError::UnknownMaterial {
            handle: who(),
            material,
            materials: self.materials_live.iter().filter(live).count(),
        })
    }

    /// What is wrong with `instance` for the world, named as `who`.
    fn instance_error(&self, who: &dyn fmt::Display, instance: &Instance) -> Option<WorldError> {
        // Named only once something is wrong: formatting the handle for every change would
        // cost more than the checks.
        let handle = || who.to_string();
        if let Some(e) = self.unknown_mesh(handle, instance.mesh) {
            return Some(e);
        }
        if let Some(e) = self.unknown_material(handle, instance.material) {
            return Some(e);
        }
        transform_error(&instance.transform)
            .or_else(|| {
                (instance.flags >> super::validate::MAX_FLAG_BITS != 0).then(|| {
                    format!("flags {:#x} use more than {} bits", instance.flags, super::validate::MAX_FLAG_BITS)
                })
            })
            .map(|message| WorldError::Invalid { handle: handle(), message })
    }

    /// Adds an instance; its handle stays valid until it is removed.
    pub fn insert(&mut self, instance: Instance) -> Result<InstanceHandle, WorldError> {
        let (index, generation) = self.instances.next();
        let handle = InstanceHandle { index, generation, world: self.id.0 };
        if let Some(e) = self.instance_error(&handle, &instance) {
            return Err(e);
        }
        self.instances.take();
        put(&mut self.scene.instances, index, instance);
        let words = self.user_words as usize;
        let at = index as usize * words;
        if self.user_data.len() < at + words {
            self.user_data.resize(at + words, 0);
        }
        self.user_data[at..at + words].fill(0);
        self.record(Change::Instance(index));
        Ok(handle)
    }

    /// Poses instance `handle`, whose mesh deforms (glTF skin or morph targets,
    /// [`crate::scene::Mesh::deform`]): `joints` take the mesh's bind-space vertices into the
    /// instance's local space (at least the mesh's [`crate::scene::deform::MeshDeform::joint_count`],
    /// none for a mesh that is only morphed), `morph_weights` weigh its morph targets (missing
    /// ones 0). The first pose gives the instance its own copy of the mesh, which renderers
    /// deform on the GPU and cull with a bound of the pose; setting the instance another mesh
    /// ends the pose. Everything is checked first; an error names the handle.
    pub fn set_pose(
        &mut self,
        handle: InstanceHandle,
        joints: &[glam::Mat4],
        morph_weights: &[f32],
    ) -> Result<(), WorldError> {
        self.check_instance(handle)?;
        let index = handle.index;
        let source = self.poses.get(&index).map_or(self.scene.instances[index as usize].mesh, |p| p.source);
        let invalid = |message: String| WorldError::Invalid { handle: handle.to_string(), message };
        let mesh = &self.scene.meshes[source as usize];
        let Some(deform) = mesh.deform.clone() else {
            return Err(invalid(format!("mesh {source} '{}' has no skin and no morph targets to pose", mesh.name)));
        };
        if deform.is_skinned() && joints.len() < deform.joint_count as usize {
            return Err(invalid(format!(
                "{} joint matrices; mesh {source} '{}' needs {}",
                joints.len(),
                mesh.name,
                deform.joint_count
            )));
        }
        if morph_weights.len() > deform.morph_targets.len() {
            return Err(invalid(format!(
                "{} morph weights; mesh {source} '{}' has {} morph targets",
                morph_weights.len(),
                mesh.name,
                deform.morph_targets.len()
            )));
        }
        let finite_joints = joints.iter().all(|m| m.is_finite() && m.row(3) == glam::Vec4::W);
        if !finite_joints || !morph_weights.iter().all(|w| w.is_finite()) {
            return Err(invalid("joint matrices must be finite and affine, morph weights finite".into()));
        }
        let boxes = match self.joint_boxes.get(&source) {
            Some(boxes) => boxes.clone(),
            None => {
                let rest = &self.scene.vertices
                    [mesh.vertex_offset as usize..(mesh.vertex_offset + mesh.vertex_count) as usize];
                let boxes = std::sync::Arc::new(super::posing::JointBoxes::new(&deform, rest));
                self.joint_boxes.insert(source, boxes.clone());
                boxes
            }
        };
        let (bounds, sphere) = boxes.bound(joints, morph_weights);
        let own = match self.poses.get(&index) {
            Some(pose) => pose.mesh,
            None => {
                let own = self.copy_mesh(source, index)?;
                self.scene.instances[index as usize].mesh = own;
                self.record(Change::Instance(index));
                own
            }
        };
        let copy = &mut self.scene.meshes[own as usize];
        (copy.bounds, copy.sphere) = (bounds, sphere);
        let pose =
            super::posing::Pose { source, mesh: own, joints: joints.to_vec(), morph_weights: morph_weights.to_vec() };
        self.poses.insert(index, pose);
        self.record(Change::Pose(index));
        Ok(())
    }

    /// The pose of instance `handle` (`None`: not posed).
    pub fn pose(&self, handle: InstanceHandle) -> Result<Option<&super::posing::Pose>, WorldError> {
        self.check_instance(handle)?;
        Ok(self.poses.get(&handle.index))
    }

    /// Every posed instance index with its pose.
    pub fn posed(&self) -> impl Iterator<Item = (u32, &super::posing::Pose)> + '_ {
        self.poses.iter().map(|(&i, p)| (i, p))
    }

    /// The pose of instance index `index`, if it is posed.
    pub fn pose_at(&self, index: u32) -> Option<&super::posing::Pose> {
        self.poses.get(&index)
    }

    /// Registers a copy of mesh `source` for instance index `index` to deform (its vertices
    /// and indices; no deformation of its own).
    fn copy_mesh(&mut self, source: u32, index: u32) -> Result<u32, WorldError> {
        let m = self.scene.meshes[source as usize].clone();
        let vertices =
            self.scene.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize].to_vec();
        let indices = self.scene.indices[m.first_index as usize..(m.first_index + m.index_count) as usize].to_vec();
        let name = format!("{} (posed instance {index})", m.name);
        self.place_mesh(&name, vertices.len(), indices.len(), Vec::new(), |scene, place, at| {
            scene.put_mesh_vertices(&name, &vertices, &indices, (m.bounds, m.sphere, None), place, at)
        })
    }

    /// Ends the pose of instance index `index` (removed, or given another mesh): its copy of
    /// the mesh is unregistered.
    fn unpose(&mut self, index: u32) -> Option<super::posing::Pose> {
        let pose = self.poses.remove(&index)?;
        self.free_mesh(pose.mesh);
        Some(pose)
    }

    /// Words of user data each instance carries (0: none).
    pub fn user_words(&self) -> u32 {
        self.user_words
    }

    /// The user data of instance `handle` ([`World::user_words`] words).
    pub fn user_data(&self, handle: InstanceHandle) -> Result<&[u32], WorldError> {
        self.check_instance(handle)?;
        Ok(self.user_data_at(handle.index))
    }

    /// The user data of instance index `index` (live or not; zeros past the table).
    pub fn user_data_at(&self, index: u32) -> &[u32] {
        let words = self.user_words as usize;
        self.user_data.get(index as usize * words..(index as usize + 1) * words).unwrap_or(&[])
    }

    /// Sets instances' user data: `(handle, words)` each, every one checked first (live, of this
    /// world, exactly [`World::user_words`] words), then all applied. Renderers upload only
    /// these instances' words at their next sync.
    pub fn set_user_data(&mut self, changes: &[(InstanceHandle, &[u32])]) -> Result<(), WorldError> {
        for (handle, data) in changes {
            self.check_instance(*handle)?;
            if data.len() != self.user_words as usize {
                let message =
                    format!("user data of {} words; the world declares {} an instance", data.len(), self.user_words);
                return Err(WorldError::Invalid { handle: handle.to_string(), message });
            }
        }
        let words = self.user_words as usize;
        for (handle, data) in changes {
            let at = handle.index as usize * words;
            self.user_data[at..at + words].copy_from_slice(data);
            self.journal.push(Change::UserData(handle.index));
        }
        self.bound_journal();
        Ok(())
    }

    /// Removes an instance; its handle (and every copy of it) becomes stale.
    pub fn remove(&mut self, handle: InstanceHandle) -> Result<Instance, WorldError> {
        self.check_instance(handle)?;
        self.instances.release(handle.index);
        self.record(Change::Instance(handle.index));
        let mut instance = self.scene.instances[handle.index as usize];
        if let Some(pose) = self.unpose(handle.index) {
            instance.mesh = pose.source;
        }
        Ok(instance)
    }

    /// Replaces whole instances: each `(handle, instance)` is checked first, then all are applied.
    pub fn set_instances(&mut self, changes: &[(InstanceHandle, Instance)]) -> Result<(), WorldError> {
        for (handle, instance) in changes {
            self.check_instance(*handle)?;
            if let Some(e) = self.instance_error(handle, instance) {
                return Err(e);
            }
        }
        for (handle, instance) in changes {
            self.scene.instances[handle.index as usize] = *instance;
            self.record(Change::Instance(handle.index));
            // Another mesh than its posed copy ends the pose.
            if self.poses.get(&handle.index).is_some_and(|p| p.mesh != instance.mesh) {
                self.unpose(handle.index);
            }
        }
        Ok(())
    }

    /// Applies `edit` to the instances of `handles` (checked first, applied all or none).
    fn edit<T: Copy>(
        &mut self,
        changes: &[(InstanceHandle, T)],
        edit: impl Fn(&mut Instance, T),
    ) -> Result<(), WorldError> {
        let mut edited = Vec::with_capacity(changes.len());
        for &(handle, value) in changes {
            let mut instance = *self.instance(handle)?;
            edit(&mut instance, value);
            edited.push((handle, instance));
        }
        self.set_instances(&edited)
    }

    /// Moves instances: `(handle, transform)` each. (Only the transforms need checking: the
    /// rest of each instance was checked when it was set.) Checked all first, applied all or
    /// none; see [`World::set_transforms_by`].
    pub fn set_transforms(&mut self, changes: &[(InstanceHandle, Transform)]) -> Result<(), WorldError> {
        if crate::parallel::worth_routing(changes.len()) {
            return self.move_many(changes.len(), |i| changes[i].0, |i| changes[i].1);
        }
        for (handle, transform) in changes {
            self.check_instance(*handle)?;
            if let Some(message) = transform_error(transform) {
                return Err(WorldError::Invalid { handle: handle.to_string(), message });
            }
        }
        let instances = &mut self.scene.instances;
        self.journal.extend(changes.iter().map(|(handle, transform)| {
            instances[handle.index as usize].transform = *transform;
            Change::Transform(handle.index)
        }));
        self.bound_journal();
        Ok(())
    }

    /// Moves instances in bulk, reading each transform where the engine keeps it: `handles[i]`
    /// moves to `transform_of(i)` (called once or twice per item, from several threads). Every
    /// handle and transform is checked first, a long list on several threads; an error names
    /// the first bad handle in list order, and then nothing has moved. A handle listed twice
    /// takes its last transform.
    pub fn set_transforms_by(
        &mut self,
        handles: &[InstanceHandle],
        transform_of: impl Fn(usize) -> Transform + Sync,
    ) -> Result<(), WorldError> {
        if !crate::parallel::worth_routing(handles.len()) {
            let changes: Vec<_> = handles.iter().enumerate().map(|(i, &h)| (h, transform_of(i))).collect();
            return self.set_transforms(&changes);
        }
        self.move_many(handles.len(), |i| handles[i], transform_of)
    }

    /// Checks and applies `n` moves on several threads: item `i` moves `handle_of(i)` to
    /// `transform_of(i)`. The check also writes the journal's entries and routes each move to
    /// the thread that owns its instance's part of the table (`crate::parallel`), which then
    /// applies its moves in list order.
    fn move_many(
        &mut self,
        n: usize,
        handle_of: impl Fn(usize) -> InstanceHandle + Sync,
        transform_of: impl Fn(usize) -> Transform + Sync,
    ) -> Result<(), WorldError> {
        let base = self.journal.len();
        self.journal.reserve(n);
        let owners = crate::parallel::Owners::new(self.scene.instances.len(), n);
        let (slots, id) = (&self.instances, &self.id);
        let ahead = |i: usize| slots.prefetch(handle_of(i).index);
        // The entries are written straight into the journal's spare room, and count only once
        // every move passed.
        let room = &mut self.journal.spare_capacity_mut()[..n];
        let routed = crate::parallel::route(room, &owners, ahead, |i, entry| {
            let handle = handle_of(i);
            check_instance_in(slots, id, handle)?;
            if let Some(message) = transform_error(&transform_of(i)) {
                return Err(WorldError::Invalid { handle: handle.to_string(), message });
            }
            entry.write(Change::Transform(handle.index));
            Ok(Some(handle.index as usize))
        })?;
        // SAFETY: the room holds `n` entries, and `route` visited each of them once without a
        // refusal; every visit wrote its entry.
        unsafe { self.journal.set_len(base + n) };
        crate::parallel::apply_routed(&mut self.scene.instances, &owners, &routed, |instance, i| {
            instance.transform = transform_of(i);
            None::<()>
        });
        self.bound_journal();
        Ok(())
    }

    /// Moves one instance.
    pub fn set_transform(&mut self, handle: InstanceHandle, transform: Transform) -> Result<(), WorldError> {
        self.set_transforms(&[(handle, transform)])
    }

    /// Gives instances other meshes.
    pub fn set_meshes(&mut self, changes: &[(InstanceHandle, u32)]) -> Result<(), WorldError> {
        self.edit(changes, |i, m| i.mesh = m)
    }

    /// Gives instances other materials.
    pub fn set_materials(&mut self, changes: &[(InstanceHandle, u32)]) -> Result<(), WorldError> {
        self.edit(changes, |i, m| i.material = m)
    }

    /// Sets instances' `FLAG_*` bits.
    pub fn set_flags(&mut self, changes: &[(InstanceHandle, u32)]) -> Result<(), WorldError> {
        self.edit(changes, |i, f| i.flags = f)
    }

    /// Registers a mesh and returns its index: its vertices and indices take the smallest free
    /// ranges of the pools that hold them (space unregistered meshes gave back) before the pools
    /// grow, and it takes an unregistered mesh's index when there is one. It gets its chain of
    /// levels of detail and its clusters as a mesh of a loaded scene does ([`Scene::add_mesh`]).
    pub fn add_mesh(&mut self, name: &str, data: &MeshData) -> Result<u32, WorldError> {
        let (vertices, bounds, sphere, deform) = data.validate(&format!("mesh '{name}'"))?;
        let (vertices, chain) = super::lod::with_chain(data, vertices, deform.is_some());
        let deform = deform.map(std::sync::Arc::new);
        let mesh = self.place_mesh(name, vertices.len(), data.indices.len(), chain, |scene, place, at| {
            scene.put_mesh_vertices(name, &vertices, &data.indices, (bounds, sphere, deform), place, at)
        })?;
        self.scene.add_clusters(mesh);
        Ok(mesh)
    }

    /// Registers mesh `mesh` of `source` (checked when `source` was loaded), with its levels of
    /// detail and clusters, as [`World::add_mesh`] does.
    pub(crate) fn add_mesh_of(&mut self, source: &Scene, mesh: u32) -> Result<u32, WorldError> {
        let m = &source.meshes[mesh as usize];
        let vertices = &source.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize];
        let indices = &source.indices[m.first_index as usize..(m.first_index + m.index_count) as usize];
        let chain = m
            .lods
            .iter()
            .map(|l| {
                (source.indices[l.first_index as usize..(l.first_index + l.index_count) as usize].to_vec(), l.error)
            })
            .collect();
        let mesh = self.place_mesh(&m.name, vertices.len(), indices.len(), chain, |scene, place, at| {
            scene.put_mesh_vertices(&m.name, vertices, indices, (m.bounds, m.sphere, m.deform.clone()), place, at)
        })?;
        self.scene.add_clusters(mesh);
        Ok(mesh)
    }

    /// Finds room for a mesh of `vertices` and `indices` and its levels of detail `chain`, and
    /// registers it with `put`; the levels' indices follow the mesh's in the pool.
    fn place_mesh(
        &mut self,
        name: &str,
        vertices: usize,
        indices: usize,
        chain: Vec<(Vec<u32>, f32)>,
        put: impl FnOnce(&mut Scene, &str, super::MeshPlace) -> Result<u32, SceneError>,
    ) -> Result<u32, WorldError> {
        let place = format!("mesh '{name}'");
        let too_large = |pool| WorldError::from(SceneError::too_large(&place, pool));
        let span = indices + chain.iter().map(|(i, _)| i.len()).sum::<usize>();
        let vertices = u32::try_from(vertices).map_err(|_| too_large("vertex pool"))?;
        let span = u32::try_from(span).map_err(|_| too_large("index pool"))?;
        let (mut vertex_ranges, mut index_ranges) = (self.vertex_ranges.clone(), self.index_ranges.clone());
        let vertex = vertex_ranges.take(vertices).ok_or_else(|| too_large("vertex pool"))?;
        let index = index_ranges.take(span).ok_or_else(|| too_large("index pool"))?;
        let slot = self.free_meshes.last().copied();
        let at = super::MeshPlace { vertex: vertex as usize, index: index as usize, slot };
        let mesh = put(&mut self.scene, &place, at)?;
        if let Err(e) = self.scene.put_lod_chain(mesh, chain, at.index + indices, &place) {
            // A mesh appended is taken back; one put in a free entry leaves it free.
            if slot.is_none() {
                self.scene.meshes.pop();
            }
            return Err(e.into());
        }
        (self.vertex_ranges, self.index_ranges) = (vertex_ranges, index_ranges);
        if slot.is_some() {
            self.free_meshes.pop();
            self.meshes_live[mesh as usize] = true;
        } else {
            self.meshes_live.push(true);
        }
        self.record(Change::Mesh(mesh));
        Ok(mesh)
    }

    /// Unregisters a mesh no live instance uses: its vertices, indices and index go to later
    /// registrations.
    pub fn remove_mesh(&mut self, mesh: u32) -> Result<(), WorldError> {
        if let Some(e) = self.unknown_mesh(|| "remove_mesh".into(), mesh) {
            return Err(e);
        }
        let what = format!("mesh {mesh} '{}'", self.scene.meshes[mesh as usize].name);
        self.refuse_in_use(&what, |i| i.mesh == mesh)?;
        let posed: Vec<u32> = self.poses.iter().filter(|(_, p)| p.source == mesh).map(|(&i, _)| i).collect();
        if let Some(&first) = posed.first() {
            let first = self.handle_at(first).expect("posed instances are live");
            return Err(WorldError::InUse { what, users: posed.len(), first });
        }
        self.free_mesh(mesh);
        Ok(())
    }

    /// Unregisters `mesh`, which no instance uses.
    fn free_mesh(&mut self, mesh: u32) {
        self.joint_boxes.remove(&mesh);
        self.meshes_live[mesh as usize] = false;
        // Its pool ranges go to other meshes: no cluster may name them any more.
        self.scene.meshes[mesh as usize].clusters.clear();
        let m = &self.scene.meshes[mesh as usize];
        self.vertex_ranges.give_back(m.vertex_offset, m.vertex_count);
        self.index_ranges.give_back(m.first_index, m.index_span());
        self.free_meshes.push(mesh);
        self.record(Change::Mesh(mesh));
    }

    /// Entries of the vertex and index pools, in use or free (what the GPU holds).
    pub fn pool_sizes(&self) -> (usize, usize) {
        (self.scene.vertices.len(), self.scene.indices.len())
    }

    /// Registers a texture (decoded RGBA8) for materials to use and returns its index (a removed
    /// texture's index when there is one).
    pub fn add_texture(&mut self, texture: super::Texture) -> Result<u32, WorldError> {
        if let Some(message) = super::validate::texture_problem(&texture) {
            return Err(WorldError::Invalid { handle: format!("texture '{}'", texture.name), message });
        }
        let texture = std::sync::Arc::new(texture);
        let index = match self.free_textures.pop() {
            Some(free) => {
                self.scene.textures[free as usize] = texture;
                free
            }
            None => {
                self.scene.textures.push(texture);
                (self.scene.textures.len() - 1) as u32
            }
        };
        self.record(Change::Texture(index));
        Ok(index)
    }

    /// Removes a texture no registered material uses: its texels are freed (a 1x1 texel holds
    /// its place until a later registration takes its index).
    pub fn remove_texture(&mut self, index: u32) -> Result<(), WorldError> {
        let live = (index as usize) < self.scene.textures.len() && !self.free_textures.contains(&index);
        if !live {
            return Err(WorldError::Invalid {
                handle: format!("texture {index}"),
                message: format!(
                    "no such texture ({} are registered)",
                    self.scene.textures.len() - self.free_textures.len()
                ),
            });
        }
        let users: Vec<u32> = (0..self.scene.materials.len() as u32)
            .filter(|&m| self.materials_live[m as usize])
            .filter(|&m| self.scene.materials[m as usize].textures.iter().flatten().any(|t| t.texture == index))
            .collect();
        if let Some(&first) = users.first() {
            return Err(WorldError::Invalid {
                handle: format!("texture {index} '{}'", self.scene.textures[index as usize].name),
                message: format!(
                    "is used by {} material(s), the first {first}; change or remove them first",
                    users.len()
                ),
            });
        }
        let name = self.scene.textures[index as usize].name.clone();
        self.scene.textures[index as usize] =
            std::sync::Arc::new(super::Texture::solid(&format!("{name} (removed)"), [0; 4]));
        self.free_textures.push(index);
        self.record(Change::Texture(index));
        Ok(())
    }

    /// A problem of `material` beyond the scene's checks: a texture this world removed.
    fn removed_texture_of(&self, material: &Material) -> Option<String> {
        let removed = material.textures.iter().flatten().find(|t| self.free_textures.contains(&t.texture))?;
        Some(format!("texture {} was removed", removed.texture))
    }

    /// Registers a material and returns its index.
    pub fn add_material(&mut self, material: Material) -> Result<u32, WorldError> {
        if let Some(message) = self.removed_texture_of(&material) {
            return Err(WorldError::Invalid { handle: format!("material '{}'", material.name), message });
        }
        super::validate::material_problem(&material, self.scene.textures.len()).map_or(Ok(()), |message| {
            Err(WorldError::Invalid { handle: format!("material '{}'", material.name), message })
        })?;
        if !self.materials_live.contains(&false) && self.scene.materials.len() >= super::validate::MAX_MATERIALS {
            let message = format!("more than {} materials", super::validate::MAX_MATERIALS);
            return Err(WorldError::Invalid { handle: format!("material '{}'", material.name), message });
        }
        // An unregistered material's index is reused.
        let index = match self.materials_live.iter().position(|live| !live) {
            Some(free) => {
                self.scene.materials[free] = material;
                self.materials_live[free] = true;
                free as u32
            }
            None => {
                self.materials_live.push(true);
                self.scene.add_material(material)
            }
        };
        self.record(Change::Material(index));
        Ok(index)
    }

    /// Changes a registered material's parameters.
    pub fn set_material(&mut self, index: u32, material: Material) -> Result<(), WorldError> {
        if let Some(e) = self.unknown_material(|| "set_material".into(), index) {
            return Err(e);
        }
        if let Some(message) = super::validate::material_problem(&material, self.scene.textures.len())
            .or_else(|| self.removed_texture_of(&material))
        {
            return Err(WorldError::Invalid { handle: format!("material {index} '{}'", material.name), message });
        }
        self.scene.materials[index as usize] = material;
        self.record(Change::Material(index));
        Ok(())
    }

    /// Unregisters a material no live instance uses; a later registration takes its index.
    pub fn remove_material(&mut self, index: u32) -> Result<(), WorldError> {
        if let Some(e) = self.unknown_material(|| "remove_material".into(), index) {
            return Err(e);
        }
        let name = format!("material {index} '{}'", self.scene.materials[index as usize].name);
        self.refuse_in_use(&name, |i| i.material == index)?;
        self.materials_live[index as usize] = false;
        self.record(Change::Material(index));
        Ok(())
    }

    fn refuse_in_use(&self, what: &str, uses: impl Fn(&Instance) -> bool) -> Result<(), WorldError> {
        let users: Vec<InstanceHandle> =
            self.handles().filter(|h| uses(&self.scene.instances[h.index as usize])).collect();
        match users.first() {
            Some(&first) => Err(WorldError::InUse { what: what.to_string(), users: users.len(), first }),
            None => Ok(()),
        }
    }

    /// The sun.
    pub fn sun(&self) -> DirectionalLight {
        self.scene.sun
    }

    /// Sets the sun (direction it travels, colour times intensity); renderers take it at their
    /// next sync.
    pub fn set_sun(&mut self, sun: DirectionalLight) -> Result<(), WorldError> {
        let length = sun.direction.length();
        let message = if !sun.direction.is_finite() || (length - 1.0).abs() > 1e-3 {
            Some(format!("direction {} must be finite and of length 1", sun.direction))
        } else if !sun.color.is_finite() || sun.color.min_element() < 0.0 {
            Some(format!("color {} must be finite and non-negative", sun.color))
        } else {
            None
        };
        if let Some(message) = message {
            return Err(WorldError::Invalid { handle: "the sun".into(), message });
        }
        self.scene.sun = sun;
        self.record(Change::Sun);
        Ok(())
    }

    /// Whether light `index` is live.
    pub fn is_light_live(&self, index: u32) -> bool {
        self.lights.alive.get(index as usize).copied().unwrap_or(false)
    }

    /// Adds a point light.
    pub fn insert_light(&mut self, light: PointLight) -> Result<LightHandle, WorldError> {
        let (index, generation) = self.lights.next();
        let handle = LightHandle { index, generation, world: self.id.0 };
        if let Some(message) = light_error(&light) {
            return Err(WorldError::Invalid { handle: handle.to_string(), message });
        }
        self.lights.take();
        put(&mut self.scene.lights, index, light);
        self.record(Change::Light(index));
        Ok(handle)
    }

    /// Changes a point light (position, color, range).
    pub fn set_light(&mut self, handle: LightHandle, light: PointLight) -> Result<(), WorldError> {
        self.check_light(handle)?;
        if let Some(message) = light_error(&light) {
            return Err(WorldError::Invalid { handle: handle.to_string(), message });
        }
        self.scene.lights[handle.index as usize] = light;
        self.record(Change::Light(handle.index));
        Ok(())
    }

    /// Removes a point light.
    pub fn remove_light(&mut self, handle: LightHandle) -> Result<PointLight, WorldError> {
        self.check_light(handle)?;
        self.lights.release(handle.index);
        self.record(Change::Light(handle.index));
        Ok(self.scene.lights[handle.index as usize])
    }

    /// The handles of the lights the world started with (index order).
    pub fn light_handles(&self) -> impl Iterator<Item = LightHandle> + '_ {
        (0..self.lights.alive.len() as u32).filter(|&i| self.is_light_live(i)).map(|index| LightHandle {
            index,
            generation: self.lights.generations[index as usize],
            world: self.id.0,
        })
    }
}

/// Stores `value` at `index` of a table that an insert grows by one or refills at a freed index.
fn put<T>(items: &mut Vec<T>, index: u32, value: T) {
    match items.get_mut(index as usize) {
        Some(slot) => *slot = value,
        None => items.push(value),
    }
}

/// Why a transform is refused: not finite, or its translation beyond the world's range.
/// Why a handle of world `owner` (displayed by `handle`) is refused by the world `id`.
fn check_owner_in(id: &Id, owner: u32, handle: impl FnOnce() -> String) -> Result<(), WorldError> {
    if owner == id.0 {
        Ok(())
    } else {
        Err(WorldError::ForeignHandle { handle: handle(), owner, world: id.0 })
    }
}

/// Why `handle` names no live instance of the world `id` whose instance table is `slots`.
fn check_instance_in(slots: &Slots, id: &Id, handle: InstanceHandle) -> Result<(), WorldError> {
    check_owner_in(id, handle.world, || handle.to_string())?;
    if slots.check(handle.index, handle.generation) {
        Ok(())
    } else {
        Err(WorldError::Stale { handle: handle.to_string() })
    }
}

fn transform_error(t: &Transform) -> Option<String> {
    if !t.linear.is_finite() {
        return Some(format!("transform {:?} is not finite", t.linear));
    }
    // A zero scale along any axis (a singular matrix) flattens the instance to nothing: its
    // normals and bounds are undefined.
    let det = t.linear.determinant();
    let scale = t.linear.x_axis.length() * t.linear.y_axis.length() * t.linear.z_axis.length();
    if !det.is_finite() || !scale.is_finite() {
        return Some(format!("transform {:?} scales beyond what a float holds", t.linear));
    }
    if scale == 0.0 || det.abs() <= 1e-12 * scale {
        return Some(format!("transform {:?} has a zero scale (it is singular)", t.linear));
    }
    super::position_error("translation", t.translation)
}

fn light_error(l: &PointLight) -> Option<String> {
    if let Some(e) = super::position_error("position", l.position) {
        return Some(e);
    }
    if !l.color.is_finite() || l.color.min_element() < 0.0 {
        return Some(format!("color {} must be finite and non-negative", l.color));
    }
    if !(l.range.is_finite() && l.range > 0.0) {
        return Some(format!("range {} must be positive and finite", l.range));
    }
    l.spot.and_then(|cone| super::spot_cone_error(&cone))
}
