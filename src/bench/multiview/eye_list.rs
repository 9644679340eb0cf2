//! An instance list on the GPU, drawn as the geometry passes draw a culled list: grouped by
//! face cull and mesh in the scene's draw-list order, one `vkCmdDrawIndexedIndirectCount` per
//! face-cull region.

use crate::error::Result;
use crate::gpu::{Buffer, GpuContext, UploadBatch};
use crate::passes::shared::face_cull::{DrawRegions, FaceCull, FACE_CULL_REGIONS};
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::scene_buffers::DrawList;
use ash::vk;
use std::collections::BTreeSet;

/// The draws of a set of instances.
pub struct EyeList {
    /// Instance ids, group after group.
    pub instance_ids: Buffer,
    /// One command per non-empty group.
    pub commands: Buffer,
    /// Commands per face-cull region.
    pub count: Buffer,
    /// Where each region's commands are.
    pub regions: DrawRegions,
    /// Instances in the list.
    pub instances: u32,
    /// Triangles the list draws (transparent instances, which the geometry passes leave to the
    /// `transparent` pass, left out).
    pub triangles: u64,
}

/// The commands and ids of the instances of `all` (a scene's unculled list) that `keep` holds,
/// in `all`'s order: the same groups, each keeping the instances of `keep`.
pub fn subset(all: &DrawList, keep: &BTreeSet<u32>) -> (Vec<DrawIndexedIndirect>, Vec<u32>, DrawRegions) {
    let mut commands = Vec::new();
    let mut ids = Vec::new();
    let mut len = [0u32; FACE_CULL_REGIONS];
    for (r, region_len) in len.iter_mut().enumerate() {
        let first = all.regions.first[r] as usize;
        for command in all.commands.iter().skip(first).take(all.regions.len[r] as usize) {
            let start = command.first_instance as usize;
            let slice = &all.instance_ids[start..start + command.instance_count as usize];
            let first_instance = ids.len() as u32;
            ids.extend(slice.iter().copied().filter(|id| keep.contains(id)));
            let instance_count = ids.len() as u32 - first_instance;
            if instance_count > 0 {
                commands.push(DrawIndexedIndirect { instance_count, first_instance, ..*command });
                *region_len += 1;
            }
        }
    }
    (commands, ids, DrawRegions::from_lengths(len))
}

impl EyeList {
    /// Uploads the instances of `keep` grouped as `all` groups them.
    pub fn upload(ctx: &GpuContext, name: &str, all: &DrawList, keep: &BTreeSet<u32>) -> Result<Self> {
        let (commands, ids, regions) = subset(all, keep);
        let opaque = regions.drawn(&commands, &regions.len);
        let triangles = opaque.map(|c| c.index_count as u64 / 3 * c.instance_count as u64).sum();
        let mut batch = UploadBatch::default();
        let indirect = vk::BufferUsageFlags::INDIRECT_BUFFER;
        let list = Self {
            instance_ids: batch.buffer(
                ctx,
                &format!("{name} ids"),
                vk::BufferUsageFlags::STORAGE_BUFFER,
                bytemuck::cast_slice(&ids),
            )?,
            commands: batch.buffer(ctx, &format!("{name} commands"), indirect, bytemuck::cast_slice(&commands))?,
            count: batch.buffer(ctx, &format!("{name} count"), indirect, bytemuck::cast_slice(&regions.len))?,
            regions,
            instances: ids.len() as u32,
            triangles,
        };
        batch.submit_and_wait(ctx)?;
        Ok(list)
    }

    /// Records the list's draws (inside rendering, with a pipeline whose bindings are pushed).
    pub fn record(&self, device: &ash::Device, cmd: vk::CommandBuffer) {
        self.regions.record(device, cmd, &self.commands, &self.count, &FaceCull::DRAWN);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::shared::face_cull::DrawRegions;

    #[test]
    fn a_subset_keeps_the_groups_and_their_order() {
        let command = |first_instance, instance_count, first_index| DrawIndexedIndirect {
            index_count: 6,
            instance_count,
            first_index,
            vertex_offset: 0,
            first_instance,
        };
        // Back: mesh 0 [5, 1, 3], mesh 1 [0]; Front: mesh 0 [4]; None: none; Blended: [2].
        let all = DrawList {
            instance_ids: vec![5, 1, 3, 0, 4, 2],
            commands: vec![command(0, 3, 0), command(3, 1, 6), command(4, 1, 0), command(5, 1, 12)],
            regions: DrawRegions::from_lengths([2, 1, 0, 0, 0, 0, 1]),
        };
        let keep: BTreeSet<u32> = [3, 5, 4, 2].into();
        let (commands, ids, regions) = subset(&all, &keep);
        assert_eq!(ids, [5, 3, 4, 2]);
        assert_eq!(commands, [command(0, 2, 0), command(2, 1, 0), command(3, 1, 12)]);
        assert_eq!(regions, DrawRegions::from_lengths([1, 1, 0, 0, 0, 0, 1]));
        let (commands, ids, regions) = subset(&all, &BTreeSet::new());
        assert!(commands.is_empty() && ids.is_empty() && regions.groups() == 0);
    }
}
