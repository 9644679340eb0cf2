//! Back-face culling and alpha masks for indirect draws, and the region of transparent instances.
//!
//! glTF culls the back faces of one-sided materials, and a mirroring transform (negative
//! determinant) flips which winding is the front. The rasterizer's cull mode is fixed for one
//! `vkCmdDrawIndexedIndirectCount`, and so is the pipeline: an alpha-masked material needs a
//! fragment shader that discards, and a `discard` anywhere in a pipeline makes the depth test
//! wait for the shader in every draw of that pipeline. So a draw group is a (region, mesh) pair,
//! a region being a face cull for opaque or for masked materials, and the groups are sorted by
//! region first. Every command list then holds one *region* per [`FaceCull`], at the same place
//! in every list (the region's first group), each compacted from its start with its own count;
//! a draw pass issues one indirect draw per non-empty region, with the cull mode set as dynamic
//! state, the opaque regions with pipelines that never discard and the masked ones after them
//! with the alpha-tested pipelines.
//!
//! Transparent (alphaMode BLEND) instances form the last region, [`FaceCull::Blended`], in
//! every list: culled like the others, but skipped by the geometry passes (they must not write
//! depth nor occlude) and drawn sorted by the `transparent` pass, which culls their back faces
//! in its shader.

use crate::gpu::Buffer;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::scene::{AlphaMode, Instance, Scene};
use ash::vk;

/// The region of a command list an instance is drawn from: which faces of its triangles the
/// rasterizer drops, and whether its material is alpha-masked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceCull {
    /// One-sided opaque material: counter-clockwise is the front, back faces are dropped.
    Back = 0,
    /// One-sided opaque material on a mirrored instance: clockwise is the front (glTF), so the
    /// counter-clockwise faces are dropped.
    Front = 1,
    /// Double-sided opaque material: nothing is dropped.
    None = 2,
    /// [`FaceCull::Back`] for an alpha-masked material.
    MaskedBack = 3,
    /// [`FaceCull::Front`] for an alpha-masked material.
    MaskedFront = 4,
    /// [`FaceCull::None`] for an alpha-masked material.
    MaskedNone = 5,
    /// Transparent material (alphaMode BLEND): not drawn by the geometry passes.
    Blended = 6,
}

/// Number of regions in a command list.
pub const FACE_CULL_REGIONS: usize = 7;

/// Bytes of a draw count buffer: one `u32` per region, in [`FaceCull`] order.
pub const DRAW_COUNT_BYTES: u64 = 4 * FACE_CULL_REGIONS as u64;

impl FaceCull {
    /// The regions in command-list order.
    pub const ALL: [FaceCull; FACE_CULL_REGIONS] = [
        FaceCull::Back,
        FaceCull::Front,
        FaceCull::None,
        FaceCull::MaskedBack,
        FaceCull::MaskedFront,
        FaceCull::MaskedNone,
        FaceCull::Blended,
    ];

    /// The regions the geometry passes draw: every one but [`FaceCull::Blended`].
    pub const DRAWN: [FaceCull; 6] = [
        FaceCull::Back,
        FaceCull::Front,
        FaceCull::None,
        FaceCull::MaskedBack,
        FaceCull::MaskedFront,
        FaceCull::MaskedNone,
    ];

    /// The regions of opaque materials: drawn with pipelines that never discard.
    pub const OPAQUE: [FaceCull; 3] = [FaceCull::Back, FaceCull::Front, FaceCull::None];

    /// The regions of alpha-masked materials: drawn with the alpha-tested pipelines.
    pub const MASKED: [FaceCull; 3] = [FaceCull::MaskedBack, FaceCull::MaskedFront, FaceCull::MaskedNone];

    /// The region of `instance` (an unknown material counts as opaque and one-sided).
    pub fn of(scene: &Scene, instance: &Instance) -> Self {
        let material = scene.materials.get(instance.material as usize);
        let alpha = material.map_or(AlphaMode::Opaque, |m| m.alpha_mode);
        let sides = if alpha == AlphaMode::Blend {
            return FaceCull::Blended;
        } else if material.is_some_and(|m| m.double_sided) {
            FaceCull::None
        } else if instance.transform.linear.determinant() < 0.0 {
            // The same sign test as `instance_is_mirrored` in `shaders/common/scene.glsl`.
            FaceCull::Front
        } else {
            FaceCull::Back
        };
        if matches!(alpha, AlphaMode::Mask { .. }) {
            sides.masked()
        } else {
            sides
        }
    }

    /// The masked region with this region's face cull.
    fn masked(self) -> Self {
        match self {
            FaceCull::Back => FaceCull::MaskedBack,
            FaceCull::Front => FaceCull::MaskedFront,
            FaceCull::None => FaceCull::MaskedNone,
            other => other,
        }
    }

    /// Whether the region's materials are alpha-masked.
    pub fn is_masked(self) -> bool {
        Self::MASKED.contains(&self)
    }

    /// The opaque region with the same face cull (itself for opaque and blended regions).
    pub fn sides(self) -> Self {
        match self {
            FaceCull::MaskedBack => FaceCull::Back,
            FaceCull::MaskedFront => FaceCull::Front,
            FaceCull::MaskedNone => FaceCull::None,
            other => other,
        }
    }

    /// The rasterizer's cull mode (pipelines take counter-clockwise as the front).
    pub fn mode(self) -> vk::CullModeFlags {
        match self.sides() {
            FaceCull::Back => vk::CullModeFlags::BACK,
            FaceCull::Front => vk::CullModeFlags::FRONT,
            _ => vk::CullModeFlags::NONE,
        }
    }
}

/// The graphs' `meshes` variable: every mesh once, and once more for each further face cull its
/// instances need, each times its levels of detail ([`lod_commands`]), so that `meshes * 20`
/// bytes hold any command list of `scene` (at least one command per mesh, as before face culls
/// were grouped).
pub fn command_capacity(scene: &Scene) -> usize {
    let meshes = scene.meshes.len();
    let mut used = vec![[false; FACE_CULL_REGIONS]; meshes];
    for instance in &scene.instances {
        if let Some(u) = used.get_mut(instance.mesh as usize) {
            u[FaceCull::of(scene, instance) as usize] = true;
        }
    }
    let commands = |m: usize, u: &[bool; FACE_CULL_REGIONS]| {
        let used = (0..FACE_CULL_REGIONS).filter(|&r| u[r]).map(|r| lod_commands(&scene.meshes[m], r) as usize);
        used.sum::<usize>().max(1)
    };
    used.iter().enumerate().map(|(m, u)| commands(m, u)).sum()
}

/// The commands a draw group of `mesh` in face-cull region `region` may need: one per level of
/// detail (transparent instances are always drawn whole, so that their sort sees one command
/// per group).
pub fn lod_commands(mesh: &crate::scene::Mesh, region: usize) -> u32 {
    if region == FaceCull::Blended as usize {
        1
    } else {
        1 + mesh.lods.len() as u32
    }
}

/// The graphs' `blended` variable: the instances of `scene` that are transparent.
pub fn blended_instances(scene: &Scene) -> usize {
    scene.instances.iter().filter(|i| FaceCull::of(scene, i) == FaceCull::Blended).count()
}

/// Where each face cull's commands live in a command list, in groups (= commands).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DrawRegions {
    /// First group of each region, in [`FaceCull`] order.
    pub first: [u32; FACE_CULL_REGIONS],
    /// Groups in each region (the most commands its count may say).
    pub len: [u32; FACE_CULL_REGIONS],
}

impl DrawRegions {
    /// Regions of `len[r]` groups each, one after the other.
    pub fn from_lengths(len: [u32; FACE_CULL_REGIONS]) -> Self {
        let mut first = [0; FACE_CULL_REGIONS];
        for r in 1..FACE_CULL_REGIONS {
            first[r] = first[r - 1] + len[r - 1];
        }
        Self { first, len }
    }

    /// The face-cull region that draw group `group` belongs to.
    pub fn region_of(&self, group: u32) -> usize {
        (1..FACE_CULL_REGIONS).filter(|&r| group >= self.first[r]).count()
    }

    /// Groups over all regions.
    pub fn groups(&self) -> u32 {
        self.len.iter().sum()
    }

    /// The commands a geometry pass drew from a list, given its commands and its per-region
    /// counts (host copies): those of the drawn regions ([`FaceCull::DRAWN`]).
    pub fn drawn<'a>(
        &self,
        commands: &'a [DrawIndexedIndirect],
        counts: &'a [u32],
    ) -> impl Iterator<Item = &'a DrawIndexedIndirect> + 'a {
        let regions = *self;
        FaceCull::DRAWN.into_iter().map(|f| f as usize).flat_map(move |r| {
            let first = (regions.first[r] as usize).min(commands.len());
            let count = counts.get(r).copied().unwrap_or(0).min(regions.len[r]) as usize;
            commands[first..(first + count).min(commands.len())].iter()
        })
    }

    /// Whether any of `regions` has groups: a pass skips binding a pipeline for none.
    pub fn any(&self, regions: &[FaceCull]) -> bool {
        regions.iter().any(|&r| self.len[r as usize] != 0)
    }

    /// Records one `vkCmdDrawIndexedIndirectCount` per non-empty region of `regions` in
    /// `commands` (counts in `count`, one `u32` per region: [`DRAW_COUNT_BYTES`], which callers
    /// check), each with its region's cull mode. The transparent region is the `transparent`
    /// pass's; the masked regions need a pipeline that alpha-tests. The pipeline bound must
    /// have the cull mode as dynamic state; a commands buffer shorter than the regions clamps
    /// them.
    pub fn record(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        commands: &Buffer,
        count: &Buffer,
        regions: &[FaceCull],
    ) {
        let stride = std::mem::size_of::<DrawIndexedIndirect>() as u32;
        let capacity = (commands.size() / stride as u64).min(u32::MAX as u64) as u32;
        for &face_cull in regions {
            let r = face_cull as usize;
            let max = self.len[r].min(capacity.saturating_sub(self.first[r]));
            // Never reads a count past the buffer (callers refuse short ones with a message).
            if max == 0 || count.size() < (r as u64 + 1) * 4 {
                continue;
            }
            // SAFETY: cmd is recording inside a rendering scope with a graphics pipeline bound;
            // the buffers outlive the command buffer's execution.
            unsafe {
                device.cmd_set_cull_mode(cmd, face_cull.mode());
                device.cmd_draw_indexed_indirect_count(
                    cmd,
                    commands.handle(),
                    self.first[r] as u64 * stride as u64,
                    count.handle(),
                    r as u64 * 4,
                    max,
                    stride,
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cmd(first_instance: u32) -> DrawIndexedIndirect {
        DrawIndexedIndirect { index_count: 3, instance_count: 1, first_index: 0, vertex_offset: 0, first_instance }
    }

    #[test]
    fn drawn_takes_each_region_up_to_its_count() {
        let regions = DrawRegions::from_lengths([3, 1, 2, 0, 0, 0, 0]);
        assert_eq!(regions.first, [0, 3, 4, 6, 6, 6, 6]);
        let commands: Vec<_> = (0..6).map(cmd).collect();
        let firsts = |counts: &[u32]| regions.drawn(&commands, counts).map(|c| c.first_instance).collect::<Vec<_>>();
        assert_eq!(firsts(&[2, 0, 1]), [0, 1, 4]);
        // A count past its region is clamped to it, and a missing count is zero.
        assert_eq!(firsts(&[9, 1]), [0, 1, 2, 3]);
        // The transparent region is not the geometry passes'.
        let regions = DrawRegions::from_lengths([1, 1, 1, 0, 0, 0, 3]);
        let opaque: Vec<u32> = regions.drawn(&commands, &[1, 1, 1, 0, 0, 0, 3]).map(|c| c.first_instance).collect();
        assert_eq!(opaque, [0, 1, 2]);
        // The masked regions are drawn, after the opaque ones.
        let regions = DrawRegions::from_lengths([1, 0, 0, 2, 0, 1, 2]);
        let drawn: Vec<u32> = regions.drawn(&commands, &[1, 0, 0, 2, 0, 1, 2]).map(|c| c.first_instance).collect();
        assert_eq!(drawn, [0, 1, 2, 3]);
    }

    #[test]
    fn draw_lists_group_by_face_cull_then_mesh() {
        use crate::passes::shared::scene_buffers::DrawList;
        use crate::scene::{Instance, Material, MeshData, Transform};
        use glam::{DVec3, Mat3, Vec3};
        let mut scene = Scene::default();
        let tri = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        let a = scene.add_mesh("a", &tri, "a").unwrap();
        let b = scene.add_mesh("b", &tri, "b").unwrap();
        let _unused = scene.add_mesh("c", &tri, "c").unwrap();
        let one = scene.add_material(Material::default());
        let two = scene.add_material(Material { double_sided: true, ..Default::default() });
        let mask = crate::scene::AlphaMode::Mask { cutoff: 0.5 };
        let three = scene.add_material(Material { alpha_mode: mask, ..Default::default() });
        let four = scene.add_material(Material { alpha_mode: mask, double_sided: true, ..Default::default() });
        let mirrored = Mat3::from_diagonal(Vec3::new(1.0, -2.0, 1.0));
        for (mesh, material, linear) in [
            (a, one, Mat3::IDENTITY),
            (a, one, mirrored),
            (b, two, mirrored),
            (b, one, Mat3::IDENTITY),
            (a, one, Mat3::IDENTITY),
            (a, three, mirrored),
            (b, four, Mat3::IDENTITY),
        ] {
            let transform = Transform { linear, translation: DVec3::ZERO };
            scene.instances.push(Instance { transform, mesh, material, flags: 0 });
        }
        let faces: Vec<_> = scene.instances.iter().map(|i| FaceCull::of(&scene, i)).collect();
        let (back, front, none) = (FaceCull::Back, FaceCull::Front, FaceCull::None);
        assert_eq!(faces, [back, front, none, back, back, FaceCull::MaskedFront, FaceCull::MaskedNone]);
        let draws = DrawList::all_instances(&scene);
        // Back: a [0, 4], b [3]; Front: a [1]; None: b [2]; masked Front: a [5]; masked None: b [6].
        assert_eq!(draws.instance_ids, [0, 4, 3, 1, 2, 5, 6]);
        assert_eq!(
            draws.commands.iter().map(|c| (c.first_instance, c.instance_count)).collect::<Vec<_>>(),
            [(0, 2), (2, 1), (3, 1), (4, 1), (5, 1), (6, 1)]
        );
        assert_eq!(draws.regions, DrawRegions::from_lengths([2, 1, 1, 0, 1, 1, 0]));
        // a three times, b three times, c (unused) once.
        assert_eq!(command_capacity(&scene), 7);
        // Masked regions keep their face cull.
        assert_eq!(FaceCull::MaskedFront.mode(), ash::vk::CullModeFlags::FRONT);
        assert!(FaceCull::MaskedNone.is_masked() && !none.is_masked());
    }
}
