//! Where each instance of a changing world sits on the GPU.
//!
//! Everything the GPU keeps per instance (its record, its cull bound, its mesh's base) is kept
//! per *slot*, and a slot's id is what draw lists and culling history hold. The slots of one
//! draw group (face cull, mesh) are a contiguous range with room to spare, so that instances can
//! come, go and change in place while every other slot keeps its place and its history: a moved
//! instance rewrites its slot, a new one takes a free slot of its group, a removed one leaves
//! its slot empty ([`FLAG_EMPTY_SLOT`]: drawn as nothing, never culled in).
//!
//! A freed slot is reused only after one frame has been recorded with it empty. That frame's
//! late cull clears its visibility bit and leaves it out of the next early draw list, so the
//! instance that takes it next inherits nothing: it is tested in the late phase, which draws it
//! if it is visible. (Reused at once, it would find the bit of the instance before it set, and
//! the late phase would take it for drawn by the early one.) An instance that changes group
//! moves to a new slot for the same reason: the early list would otherwise draw its old mesh.
//!
//! When a group has no free slot, or an instance needs a group the layout lacks, the world is
//! laid out anew ([`SlotLayout::new`]), with the culling history cleared.

use super::face_cull::{FaceCull, FACE_CULL_REGIONS};
use super::scene_buffers::{spatial_keys, DrawList};
use crate::passes::shared::face_cull::DrawRegions;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::scene::{Instance, Scene, Transform, FLAG_EMPTY_SLOT};
use std::collections::HashMap;

/// The draw group of an instance: face-cull region major, then mesh (the command-list order).
pub fn group_key(scene: &Scene, instance: &Instance) -> (usize, u32) {
    (FaceCull::of(scene, instance) as usize, instance.mesh)
}

/// One draw group's range of slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroupRange {
    /// Face-cull region and mesh.
    pub key: (usize, u32),
    /// First slot.
    pub first_slot: u32,
    /// Slots of the range, used or not.
    pub capacity: u32,
}

/// Slots of a group with `count` instances: room for a quarter more, and at least 4 spare.
fn capacity_for(count: usize) -> u32 {
    (count + count / 4 + 4) as u32
}

/// The slot layout of one renderer's copy of a world.
#[derive(Clone, Debug)]
pub struct SlotLayout {
    /// The groups in command-list order.
    pub groups: Vec<GroupRange>,
    group_of_key: HashMap<(usize, u32), usize>,
    /// The world instance index each slot holds.
    slot_instance: Vec<Option<u32>>,
    /// The slot of each world instance index.
    instance_slot: Vec<Option<u32>>,
    /// Per group, its free slots ready for reuse.
    free: Vec<Vec<u32>>,
    /// Freed slots with the frame from which they may be reused.
    quarantine: Vec<(u64, u32)>,
    /// Slots that hold an instance.
    occupied: u32,
}

impl SlotLayout {
    /// Lays out the instances of `scene` for which `live` holds: each group's slots in spatial
    /// order, with room to spare.
    pub fn new(scene: &Scene, live: impl Fn(u32) -> bool) -> Self {
        let mut members: HashMap<(usize, u32), Vec<u32>> = HashMap::new();
        for (i, inst) in scene.instances.iter().enumerate().filter(|(i, _)| live(*i as u32)) {
            members.entry(group_key(scene, inst)).or_default().push(i as u32);
        }
        let keys = spatial_keys(scene);
        let mut ordered: Vec<((usize, u32), Vec<u32>)> = members.into_iter().collect();
        ordered.sort_by_key(|(k, _)| *k);
        let mut layout = Self {
            groups: Vec::new(),
            group_of_key: HashMap::new(),
            slot_instance: Vec::new(),
            instance_slot: vec![None; scene.instances.len()],
            free: Vec::new(),
            quarantine: Vec::new(),
            occupied: 0,
        };
        for (key, mut ids) in ordered {
            ids.sort_unstable_by_key(|&id| (keys[id as usize], id));
            let first_slot = layout.slot_instance.len() as u32;
            let capacity = capacity_for(ids.len());
            for &id in &ids {
                layout.instance_slot[id as usize] = Some(layout.slot_instance.len() as u32);
                layout.slot_instance.push(Some(id));
            }
            layout.occupied += ids.len() as u32;
            let spare = first_slot + ids.len() as u32..first_slot + capacity;
            layout.slot_instance.extend(spare.clone().map(|_| None));
            // Lowest slots first.
            layout.free.push(spare.rev().collect());
            layout.group_of_key.insert(key, layout.groups.len());
            layout.groups.push(GroupRange { key, first_slot, capacity });
        }
        layout
    }

    /// Slots in all.
    pub fn slots(&self) -> u32 {
        self.slot_instance.len() as u32
    }

    /// Slots that hold an instance.
    pub fn occupied(&self) -> u32 {
        self.occupied
    }

    /// The slot of world instance `instance`, if it has one.
    pub fn slot_of(&self, instance: u32) -> Option<u32> {
        self.instance_slot.get(instance as usize).copied().flatten()
    }

    /// The world instance in `slot`, if any.
    pub fn instance_in(&self, slot: u32) -> Option<u32> {
        self.slot_instance.get(slot as usize).copied().flatten()
    }

    /// The group `slot` belongs to (its index in [`SlotLayout::groups`], the command order).
    pub fn group_of_slot(&self, slot: u32) -> usize {
        self.groups.partition_point(|g| g.first_slot + g.capacity <= slot)
    }

    /// Makes the slots freed before `frame` reusable.
    pub fn release_quarantine(&mut self, frame: u64) {
        let mut quarantine = std::mem::take(&mut self.quarantine);
        quarantine.retain(|&(from, slot)| {
            let ready = from <= frame;
            if ready {
                let g = self.group_of_slot(slot);
                self.free[g].push(slot);
            }
            !ready
        });
        self.quarantine = quarantine;
    }

    /// Empties the slot of world instance `instance` (if it has one), reusable from frame
    /// `next_frame + 1`; returns it.
    pub fn vacate(&mut self, instance: u32, next_frame: u64) -> Option<u32> {
        let slot = self.instance_slot.get_mut(instance as usize)?.take()?;
        self.slot_instance[slot as usize] = None;
        self.quarantine.push((next_frame + 1, slot));
        self.occupied -= 1;
        Some(slot)
    }

    /// Puts world instance `instance` into a free slot of group `key`; `None` when the layout
    /// has no such group or no free slot in it (lay the world out anew).
    pub fn place(&mut self, instance: u32, key: (usize, u32)) -> Option<u32> {
        let g = *self.group_of_key.get(&key)?;
        let slot = self.free[g].pop()?;
        if self.instance_slot.len() <= instance as usize {
            self.instance_slot.resize(instance as usize + 1, None);
        }
        self.instance_slot[instance as usize] = Some(slot);
        self.slot_instance[slot as usize] = Some(instance);
        self.occupied += 1;
        Some(slot)
    }

    /// The group key of the instance in `slot`'s group.
    pub fn key_of_slot(&self, slot: u32) -> (usize, u32) {
        self.groups[self.group_of_slot(slot)].key
    }

    /// What slot `slot` holds, as the GPU takes it: the world's instance, or an empty slot of
    /// its group's mesh ([`FLAG_EMPTY_SLOT`]).
    pub fn slot_contents(&self, slot: u32, scene: &Scene) -> Instance {
        match self.instance_in(slot) {
            Some(i) => scene.instances[i as usize],
            None => Instance {
                transform: Transform::default(),
                mesh: self.key_of_slot(slot).1,
                material: 0,
                flags: FLAG_EMPTY_SLOT,
            },
        }
    }

    /// The world's instances in slot order (empty slots included): what the GPU scene is built
    /// from.
    pub fn slot_scene(&self, scene: &Scene) -> Scene {
        let instances = (0..self.slots()).map(|s| self.slot_contents(s, scene)).collect();
        Scene { instances, ..scene.clone() }
    }

    /// The unculled draw list: every slot of every group (empty ones draw nothing), slot `s`
    /// drawing instance record `s`.
    pub fn draw_list(&self, scene: &Scene) -> DrawList {
        let mut region_len = [0u32; FACE_CULL_REGIONS];
        let commands = self
            .groups
            .iter()
            .map(|g| {
                region_len[g.key.0] += 1;
                let mesh = &scene.meshes[g.key.1 as usize];
                DrawIndexedIndirect {
                    index_count: mesh.index_count,
                    instance_count: g.capacity,
                    first_index: mesh.first_index,
                    vertex_offset: mesh.vertex_offset as i32,
                    first_instance: g.first_slot,
                }
            })
            .collect();
        DrawList { instance_ids: (0..self.slots()).collect(), commands, regions: DrawRegions::from_lengths(region_len) }
    }
}
