//! Adding another scene to a live world: a glTF level loaded into a running game, whole
//! ([`World::load_gltf`]) or in pieces over several frames ([`SceneMerge::add`], streaming).
//! Each piece registers only the meshes, materials and textures its instances use that earlier
//! pieces did not, so a level streamed in pieces registers each of them once.

use super::world::{InstanceHandle, LightHandle, World, WorldError};
use super::{Instance, PointLight, Scene, SpotCone, Transform};
use std::path::Path;

/// The world's index of each of a source's meshes, materials and textures registered so far.
type Registered = (Vec<Option<u32>>, Vec<Option<u32>>, Vec<Option<u32>>);

/// A scene being added to a world, piece by piece: what of it the world already holds.
pub struct SceneMerge {
    source: Scene,
    placement: Transform,
    /// The world's index of each of the source's meshes, materials and textures registered.
    meshes: Vec<Option<u32>>,
    materials: Vec<Option<u32>>,
    textures: Vec<Option<u32>>,
    /// Whether the source's lights were added (with the first piece).
    lights_added: bool,
}

/// What one [`SceneMerge::add`] added to the world.
#[derive(Clone, Debug, Default)]
pub struct Added {
    /// The new instances, in the order asked for.
    pub instances: Vec<InstanceHandle>,
    /// The source's lights (with the first piece only).
    pub lights: Vec<LightHandle>,
    /// Meshes registered.
    pub meshes: usize,
    /// Materials registered.
    pub materials: usize,
    /// Textures registered.
    pub textures: usize,
    /// The source's animation, placed where its instances were, when the whole source was
    /// added at once ([`World::load_gltf`]): its instance `i` is `instances[i]` (play it with
    /// [`super::animation::SceneAnimation::pose`], then [`World::set_transforms`] and
    /// [`World::set_pose`]).
    pub animation: Option<std::sync::Arc<super::animation::SceneAnimation>>,
}

impl SceneMerge {
    /// Prepares adding `source` (a loaded scene, so already checked) with every instance and
    /// light moved by `placement`; the world's sun stays.
    pub fn new(source: Scene, placement: Transform) -> Result<Self, WorldError> {
        let det = placement.linear.determinant();
        if !placement.is_finite() || !det.is_finite() || det.abs() < 1e-12 {
            return Err(WorldError::Invalid {
                handle: format!("scene '{}'", source.name),
                message: "its placement must be finite and invertible".into(),
            });
        }
        Ok(Self {
            meshes: vec![None; source.meshes.len()],
            materials: vec![None; source.materials.len()],
            textures: vec![None; source.textures.len()],
            lights_added: false,
            source,
            placement,
        })
    }

    /// The scene being added.
    pub fn source(&self) -> &Scene {
        &self.source
    }

    /// The source's instances in `n` pieces of about equal count, each a slab along the axis
    /// on which the instances spread most (the order a level streams in as a player walks
    /// along it).
    pub fn pieces(&self, n: usize) -> Vec<Vec<usize>> {
        let n = n.max(1);
        let centers: Vec<glam::DVec3> = self.source.instances.iter().map(|i| i.transform.translation).collect();
        let (lo, hi) = centers
            .iter()
            .fold((glam::DVec3::splat(f64::MAX), glam::DVec3::splat(f64::MIN)), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mut order: Vec<usize> = (0..centers.len()).collect();
        order.sort_by(|&a, &b| centers[a][axis].total_cmp(&centers[b][axis]).then(a.cmp(&b)));
        let per = order.len().div_ceil(n).max(1);
        order.chunks(per).map(<[usize]>::to_vec).collect()
    }

    /// Adds the source's `instances` (indices into its instance list) to `world`, registering
    /// what they use that the world does not hold yet, and with the first piece the source's
    /// lights. On error the world is as it was.
    pub fn add(&mut self, world: &mut World, instances: &[usize]) -> Result<Added, WorldError> {
        let before: Registered = (self.meshes.clone(), self.materials.clone(), self.textures.clone());
        let mut added = Added::default();
        let result = self.add_inner(world, instances, &mut added);
        if result.is_err() {
            self.undo(world, &added, &before);
            (self.meshes, self.materials, self.textures) = before;
        }
        result.map(|()| added)
    }

    /// Adds every instance of the source (for a scene added whole, in one call).
    pub fn add_all(&mut self, world: &mut World) -> Result<Added, WorldError> {
        let all: Vec<usize> = (0..self.source.instances.len()).collect();
        self.add(world, &all)
    }

    fn add_inner(&mut self, world: &mut World, instances: &[usize], added: &mut Added) -> Result<(), WorldError> {
        let count = self.source.instances.len();
        if let Some(&bad) = instances.iter().find(|&&i| i >= count) {
            return Err(WorldError::Invalid {
                handle: format!("scene '{}'", self.source.name),
                message: format!("instance {bad} does not exist ({count} instances)"),
            });
        }
        for &i in instances {
            let source = self.source.instances[i];
            let mesh = self.mesh(world, source.mesh, added)?;
            let material = self.material(world, source.material, added)?;
            let transform = self.placement.then(&source.transform);
            added.instances.push(world.insert(Instance { transform, mesh, material, flags: source.flags })?);
        }
        if !self.lights_added {
            for light in &self.source.lights {
                let spot = light
                    .spot
                    .map(|c| SpotCone { direction: (self.placement.linear * c.direction).normalize_or_zero(), ..c });
                let position = self.placement.linear.as_dmat3() * light.position + self.placement.translation;
                added.lights.push(world.insert_light(PointLight { position, spot, ..*light })?);
            }
            self.lights_added = true;
        }
        Ok(())
    }

    fn mesh(&mut self, world: &mut World, mesh: u32, added: &mut Added) -> Result<u32, WorldError> {
        if let Some(m) = self.meshes[mesh as usize] {
            return Ok(m);
        }
        let m = world.add_mesh_of(&self.source, mesh)?;
        self.meshes[mesh as usize] = Some(m);
        added.meshes += 1;
        Ok(m)
    }

    fn material(&mut self, world: &mut World, material: u32, added: &mut Added) -> Result<u32, WorldError> {
        if let Some(m) = self.materials[material as usize] {
            return Ok(m);
        }
        let mut copy = self.source.materials[material as usize].clone();
        for texture in copy.textures.iter_mut().flatten() {
            texture.texture = match self.textures[texture.texture as usize] {
                Some(t) => t,
                None => {
                    let source = (*self.source.textures[texture.texture as usize]).clone();
                    let t = world.add_texture(source)?;
                    self.textures[texture.texture as usize] = Some(t);
                    added.textures += 1;
                    t
                }
            };
        }
        let m = world.add_material(copy)?;
        self.materials[material as usize] = Some(m);
        added.materials += 1;
        Ok(m)
    }

    /// Takes back what a failed [`SceneMerge::add`] added (removals of what was just added
    /// cannot fail: nothing else uses it).
    fn undo(&self, world: &mut World, added: &Added, before: &Registered) {
        for &h in added.instances.iter().rev() {
            let _ = world.remove(h);
        }
        for &h in added.lights.iter().rev() {
            let _ = world.remove_light(h);
        }
        let new = |now: &[Option<u32>], was: &[Option<u32>]| -> Vec<u32> {
            now.iter().zip(was).filter_map(|(n, w)| if w.is_none() { *n } else { None }).collect()
        };
        for m in new(&self.materials, &before.1) {
            let _ = world.remove_material(m);
        }
        for m in new(&self.meshes, &before.0) {
            let _ = world.remove_mesh(m);
        }
        for t in new(&self.textures, &before.2) {
            let _ = world.remove_texture(t);
        }
    }
}

impl World {
    /// Loads the glTF file at `path` into this world, every instance and light moved by
    /// `placement` (the world's sun stays); returns what was added and what the import left
    /// out. The file's lights are added; none are placed for a file without lights. On error the
    /// world is as it was.
    pub fn load_gltf(
        &mut self,
        path: &Path,
        placement: Transform,
        options: &super::source::LoadOptions,
    ) -> Result<(Added, super::gltf_import::ImportReport), WorldError> {
        let options = super::source::LoadOptions { lights: Some(0), ..options.clone() };
        let (scene, report) = super::gltf_import::load_with_report(path, &options)?;
        let animation = scene.animation.as_deref().map(|a| {
            let mut placed = a.clone();
            placed.set_placement(placement.then(&a.placement()));
            std::sync::Arc::new(placed)
        });
        let mut merge = SceneMerge::new(scene, placement)?;
        let mut added = merge.add_all(self)?;
        added.animation = animation;
        Ok((added, report))
    }
}
