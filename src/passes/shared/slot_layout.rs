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
//! When a group has no free slot, or an instance needs a group the layout lacks, the layout
//! grows at its end ([`SlotLayout::grow`]): a new slot range, as large as the key's slots so
//! far, becomes a new draw group with the same key. Every slot and every group keeps its index,
//! so the culling history stays valid. The new group takes one of the empty groups that each
//! face-cull region keeps in reserve after its own (the regions' commands stay contiguous); a
//! region that has used them all is laid out anew ([`SlotLayout::new`]), with the culling
//! history cleared.

use super::face_cull::{self, FaceCull, FACE_CULL_REGIONS};
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
    /// Slots of the range, used or not; 0 for a group held in reserve ([`GroupRange::spare`]).
    pub capacity: u32,
}

impl GroupRange {
    /// A group its region holds in reserve for growth: no slots, no mesh.
    fn reserve(region: usize) -> Self {
        Self { key: (region, u32::MAX), first_slot: 0, capacity: 0 }
    }

    /// Whether the group is held in reserve (draws nothing).
    pub fn spare(&self) -> bool {
        self.capacity == 0
    }
}

/// Groups a region holds in reserve beyond its `groups`: three for each, and 8 more. Each
/// growth of a group doubles its slots, so every group can double three times (a world
/// streamed in, growing eightfold) before the world is laid out anew. A reserved group costs
/// its few bytes of group records and nothing in the draws: culled draw lists hold only the
/// groups with instances to draw.
fn reserve_for(groups: usize) -> usize {
    groups * 3 + 8
}

/// Slots of a group with `count` instances: room for a quarter more, and at least 4 spare.
fn capacity_for(count: usize) -> u32 {
    (count + count / 4 + 4) as u32
}

/// Where a world instance is: its slot and the slot's group (`Placement::NONE`: nowhere).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Placement {
    /// The slot.
    pub slot: u32,
    /// The group the slot belongs to (its index in [`SlotLayout::groups`]).
    pub group: u32,
}

impl Placement {
    /// An instance without a slot.
    const NONE: Placement = Placement { slot: u32::MAX, group: u32::MAX };

    fn get(self) -> Option<Placement> {
        (self.slot != u32::MAX).then_some(self)
    }
}

/// The slot layout of one renderer's copy of a world.
#[derive(Clone, Debug, Default)]
pub struct SlotLayout {
    /// The groups in command-list order (each face-cull region's, then its reserve).
    pub groups: Vec<GroupRange>,
    /// The groups of each key, oldest first.
    groups_of_key: HashMap<(usize, u32), Vec<usize>>,
    /// The group of each slot: a slot's group never changes, and a change of a slot asks for
    /// it (a search over the groups cost more than the rest of an insert or a remove).
    slot_group: Vec<u32>,
    /// Per face-cull region, its groups held in reserve, last to be used first.
    reserve: [Vec<usize>; FACE_CULL_REGIONS],
    /// The world instance index each slot holds.
    slot_instance: Vec<Option<u32>>,
    /// The slot of each world instance index, with its group: a move's scatter takes both,
    /// and one 8-byte entry is one memory access per move.
    instance_slot: Vec<Placement>,
    /// Per group, its free slots ready for reuse.
    free: Vec<Vec<u32>>,
    /// Freed slots with the frame from which they may be reused.
    quarantine: Vec<(u64, u32)>,
    /// Slots that hold an instance.
    occupied: u32,
}

impl SlotLayout {
    /// Slots of the transparent region's groups ([`FaceCull::Blended`]), used or not.
    pub fn blended_slots(&self) -> u32 {
        self.groups.iter().filter(|g| g.key.0 == FaceCull::Blended as usize).map(|g| g.capacity).sum()
    }

    /// Lays out the instances of `scene` for which `live` holds: each group's slots in spatial
    /// order, with room to spare, and each face-cull region's groups followed by its reserve.
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
            groups_of_key: HashMap::new(),
            slot_group: Vec::new(),
            reserve: Default::default(),
            slot_instance: Vec::new(),
            instance_slot: vec![Placement::NONE; scene.instances.len()],
            free: Vec::new(),
            quarantine: Vec::new(),
            occupied: 0,
        };
        let mut ordered = ordered.into_iter().peekable();
        for region in 0..FACE_CULL_REGIONS {
            let mut groups = 0;
            while let Some((key, mut ids)) = ordered.next_if(|(key, _)| key.0 == region) {
                ids.sort_unstable_by_key(|&id| (keys[id as usize], id));
                let capacity = capacity_for(ids.len());
                let g = layout.add_range(key, capacity);
                let first_slot = layout.groups[g].first_slot;
                for (slot, &id) in (first_slot..).zip(&ids) {
                    layout.instance_slot[id as usize] = Placement { slot, group: g as u32 };
                    layout.slot_instance[slot as usize] = Some(id);
                    layout.free[g].pop();
                }
                layout.occupied += ids.len() as u32;
                groups += 1;
            }
            let reserve = reserve_for(groups);
            for _ in 0..reserve {
                layout.reserve[region].push(layout.groups.len());
                layout.groups.push(GroupRange::reserve(region));
                layout.free.push(Vec::new());
            }
            layout.reserve[region].reverse();
            // Room for a command per level of detail of each group: empty groups that no mesh
            // takes, enough for the groups laid out and for reserved ones of the scene's
            // most detailed chain.
            let most = scene.meshes.iter().map(|m| face_cull::lod_commands(m, region) - 1).max().unwrap_or(0);
            let levels = layout.level_commands(scene, region) - layout.used_groups(region);
            for _ in 0..levels + reserve as u32 * most {
                layout.groups.push(GroupRange::reserve(region));
                layout.free.push(Vec::new());
            }
        }
        layout
    }

    /// Groups of face-cull region `region` that hold slots.
    fn used_groups(&self, region: usize) -> u32 {
        self.groups.iter().filter(|g| g.key.0 == region && !g.spare()).count() as u32
    }

    /// The most commands a culled list may hold in face-cull region `region`: one per level of
    /// detail of each group with slots ([`face_cull::lod_commands`]).
    fn level_commands(&self, scene: &Scene, region: usize) -> u32 {
        let groups = self.groups.iter().filter(|g| g.key.0 == region && !g.spare());
        groups.map(|g| scene.meshes.get(g.key.1 as usize).map_or(1, |m| face_cull::lod_commands(m, region))).sum()
    }

    /// Whether every face-cull region has a command for each level of detail of each of its
    /// groups with `scene`'s meshes (a region outgrown by new groups or by meshes registered
    /// with longer chains must be laid out anew).
    pub fn has_level_room(&self, scene: &Scene) -> bool {
        let mut len = [0u32; FACE_CULL_REGIONS];
        for g in &self.groups {
            len[g.key.0] += 1;
        }
        (0..FACE_CULL_REGIONS).all(|r| self.level_commands(scene, r) <= len[r])
    }

    /// Appends a range of `capacity` empty slots as a new group of `key`; returns the group.
    fn add_range(&mut self, key: (usize, u32), capacity: u32) -> usize {
        let g = self.groups.len();
        self.groups.push(GroupRange::reserve(key.0));
        self.free.push(Vec::new());
        self.open_range(g, key, capacity);
        g
    }

    /// Makes group `g` (new or reserved) a range of `capacity` empty slots of `key` at the end.
    fn open_range(&mut self, g: usize, key: (usize, u32), capacity: u32) {
        let first_slot = self.slots();
        self.slot_instance.extend((0..capacity).map(|_| None));
        self.groups[g] = GroupRange { key, first_slot, capacity };
        // Lowest slots first.
        self.free[g] = (first_slot..first_slot + capacity).rev().collect();
        self.groups_of_key.entry(key).or_default().push(g);
        self.slot_group.extend(std::iter::repeat_n(g as u32, capacity as usize));
    }

    /// Makes room for more instances of `key`: a new range at the end of the slots, as large as
    /// the key's slots so far (at least 4), in one of its face-cull region's reserved groups.
    /// Every slot and group keeps its index. `false` when the region has no reserve left (lay
    /// the world out anew).
    pub fn grow(&mut self, key: (usize, u32)) -> bool {
        let Some(g) = self.reserve[key.0].pop() else { return false };
        let so_far: u32 =
            self.groups_of_key.get(&key).map_or(0, |gs| gs.iter().map(|&g| self.groups[g].capacity).sum());
        self.open_range(g, key, so_far.max(capacity_for(0)));
        true
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
        self.placement_of(instance).map(|p| p.slot)
    }

    /// The slot of world instance `instance` and its group, if it has one.
    pub fn placement_of(&self, instance: u32) -> Option<Placement> {
        self.instance_slot.get(instance as usize).and_then(|p| p.get())
    }

    /// Asks for the memory [`SlotLayout::placement_of`] of `instance` reads
    /// ([`crate::parallel::prefetch`]).
    pub(crate) fn prefetch(&self, instance: u32) {
        if let Some(entry) = self.instance_slot.get(instance as usize) {
            crate::parallel::prefetch(entry);
        }
    }

    /// The world instance in `slot`, if any.
    pub fn instance_in(&self, slot: u32) -> Option<u32> {
        self.slot_instance.get(slot as usize).copied().flatten()
    }

    /// The group `slot` belongs to (its index in [`SlotLayout::groups`], the command order).
    pub fn group_of_slot(&self, slot: u32) -> usize {
        self.slot_group[slot as usize] as usize
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
        let entry = self.instance_slot.get_mut(instance as usize)?;
        let slot = entry.get()?.slot;
        *entry = Placement::NONE;
        self.slot_instance[slot as usize] = None;
        self.quarantine.push((next_frame + 1, slot));
        self.occupied -= 1;
        Some(slot)
    }

    /// Puts world instance `instance` into a free slot of group `key`; `None` when the layout
    /// has no such group or no free slot in it (lay the world out anew).
    pub fn place(&mut self, instance: u32, key: (usize, u32)) -> Option<u32> {
        let groups = self.groups_of_key.get(&key)?;
        // The newest range first: the older ones are full more often.
        let (slot, group) = groups.iter().rev().find_map(|&g| Some((self.free[g].pop()?, g as u32)))?;
        if self.instance_slot.len() <= instance as usize {
            self.instance_slot.resize(instance as usize + 1, Placement::NONE);
        }
        self.instance_slot[instance as usize] = Placement { slot, group };
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

    /// Group `g`'s unculled draw command: every slot of it (none for a group in reserve).
    pub fn command(&self, g: usize, scene: &Scene) -> DrawIndexedIndirect {
        let group = &self.groups[g];
        if group.spare() {
            return DrawIndexedIndirect::default();
        }
        let mesh = &scene.meshes[group.key.1 as usize];
        DrawIndexedIndirect {
            index_count: mesh.index_count,
            instance_count: group.capacity,
            first_index: mesh.first_index,
            vertex_offset: mesh.vertex_offset as i32,
            first_instance: group.first_slot,
        }
    }

    /// The unculled draw list: every slot of every group (empty ones draw nothing), slot `s`
    /// drawing instance record `s`.
    pub fn draw_list(&self, scene: &Scene) -> DrawList {
        let mut region_len = [0u32; FACE_CULL_REGIONS];
        let commands = (0..self.groups.len())
            .map(|g| {
                region_len[self.groups[g].key.0] += 1;
                self.command(g, scene)
            })
            .collect();
        DrawList { instance_ids: (0..self.slots()).collect(), commands, regions: DrawRegions::from_lengths(region_len) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Mat3};

    /// Every placed instance's group is the group its slot lies in.
    fn assert_placements_agree(layout: &SlotLayout, instances: u32) {
        for i in 0..instances {
            if let Some(p) = layout.placement_of(i) {
                assert_eq!(p.group as usize, layout.group_of_slot(p.slot), "instance {i} in slot {}", p.slot);
                assert_eq!(layout.instance_in(p.slot), Some(i));
            }
        }
    }

    #[test]
    fn placements_name_the_group_of_their_slot_as_the_layout_grows() {
        let (mut scene, meshes) = crate::passes::shared::scene_buffers::tests::triangle_meshes(2);
        for i in 0..40u32 {
            let transform = Transform { linear: Mat3::IDENTITY, translation: DVec3::new(i as f64, 0.0, 0.0) };
            scene.instances.push(Instance { transform, mesh: meshes[(i % 3 == 0) as usize], material: 0, flags: 0 });
        }
        let mut layout = SlotLayout::new(&scene, |i| i % 5 != 0);
        assert_placements_agree(&layout, 60);
        assert_eq!(layout.placement_of(5), None);
        // Placed until the groups of mesh b are full, then grown into a range of a reserved group.
        let key = group_key(&scene, &scene.instances[0]);
        let mut next = 40;
        while layout.place(next, key).is_some() {
            next += 1;
        }
        assert!(layout.grow(key));
        let placed = layout.place(next, key).expect("room after growing");
        let grown = layout.placement_of(next).unwrap();
        assert_eq!(grown.slot, placed);
        assert_ne!(grown.group as usize, layout.group_of_slot(layout.slot_of(3).unwrap()), "a new group");
        assert_placements_agree(&layout, next + 1);
        let slot = layout.slot_of(3).unwrap();
        assert_eq!(layout.vacate(3, 0), Some(slot));
        assert_eq!((layout.placement_of(3), layout.instance_in(slot)), (None, None));
    }
}
