//! `transparent_sort`: the transparent (alphaMode BLEND) instances a culled list kept, in
//! back-to-front order, as one draw command per instance for the `transparent` pass.
//!
//! Blended instances have their own face-cull region ([`FaceCull::Blended`]) in every draw list:
//! the culling tests them like any instance (frustum and Hi-Z), but the geometry passes skip the
//! region, so they are never drawn into the depth, never occlude and never build the Hi-Z. This
//! pass reads the region of the list that holds every instance visible this frame (two-phase
//! culling's `list_*` output, a one-phase cull's draw list, or every instance when none is
//! bound; or two lists that hold them together, such as an occluder pass's and the rest's), and
//! sorts by distance from the eye to each instance's origin in one workgroup
//! (`shaders/transparent_sort/transparent_sort.comp`). Sorting per instance, as Bevy and
//! Granite do, leaves the triangles of one instance in mesh order.

use super::slots::{list_slots, slot, DRAW_COMMANDS, DRAW_COUNTS, INSTANCE_IDS};
use crate::gpu::{Bind, Buffer, Pipeline};
use crate::graph::executor::PassContext;
use crate::graph::{
    Creates, FormatRule, Growth, NodeSetup, PassKind, PassKindInfo, PassNode, Quantity, SlotDecl, Stages, Usage,
};
use crate::passes::gbuffer::{DrawSource, LIST_SLOTS};
use crate::passes::shared::face_cull::FaceCull;
use crate::passes::shared::gpu_types::DrawIndexedIndirect;
use crate::passes::shared::SceneCounts;
use crate::passes::shared::SceneInputs;
use ash::vk;

/// The slots of the list this pass reads.
const SOURCE_SLOTS: [&str; 3] = ["list_commands", "list_count", "list_instance_ids"];
/// The slots of an optional second list (the visible instances may come in two lists).
const SECOND_SLOTS: [&str; 3] = ["second_list_commands", "second_list_count", "second_list_instance_ids"];
/// Bytes of one sorted command.
const COMMAND_BYTES: u64 = std::mem::size_of::<DrawIndexedIndirect>() as u64;
/// Scratch bytes per transparent instance: a sort key (8 bytes) in a power of two of at most
/// twice the instances, and the instance's entry (8 bytes).
pub(crate) const SCRATCH_BYTES_PER_INSTANCE: u64 = 24;

/// The kind's name in RON.
pub(crate) const KIND: &str = "transparent_sort";

/// One sorted command per transparent instance (it may be 0, so at least one).
pub(crate) const SORTED_COMMANDS_BYTES: &str = "max(1, blended) * 20";
/// One instance id per transparent instance.
pub(crate) const SORTED_IDS_BYTES: &str = "max(1, blended) * 4";

const _: () = assert!(COMMAND_BYTES == 20 && SCRATCH_BYTES_PER_INSTANCE == 24);

/// The quantity `blended`: the transparent (alphaMode BLEND) instances, the ones sorted and
/// drawn after the lighting; for a world, the slots of its transparent draw groups.
pub const BLENDED: Quantity = Quantity {
    name: "blended",
    doc:
        "transparent (alphaMode BLEND) instances, drawn sorted after the lighting (may be 0: sizes use max(1, blended))",
    count: |s| {
        let c = SceneCounts::downcast(s)?;
        Some(
            c.layout.map_or(crate::passes::shared::face_cull::blended_instances(c.scene) as u64, |l| {
                l.blended_slots() as u64
            }),
        )
    },
    growth: Growth::Grows,
};

/// Push constants of `transparent_sort.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SortPush {
    first_command: u32,
    region_commands: u32,
    capacity: u32,
    keys: u32,
    count_index: u32,
    lists: u32,
}

/// The sorted list's capacity in instances, given its buffers, and the scratch's sort keys
/// for it (a power of two): the most instances `n` every buffer holds, the scratch holding
/// `next_power_of_two(n)` keys and `n` entries of 8 bytes.
fn capacity(commands: u64, ids: u64, scratch: u64) -> (u32, u32) {
    let limit = (commands / COMMAND_BYTES).min(ids / 4).min(u32::MAX as u64 / 2);
    let words = scratch / 8;
    // For each power of two `keys`, at most `keys` instances fit its keys and `words - keys`
    // its entries.
    let best = (0..32).map(|k| 1u64 << k).map(|keys| keys.min(words.saturating_sub(keys)).min(limit)).max();
    let n = best.unwrap_or(0);
    (n as u32, n.next_power_of_two().max(1) as u32)
}

/// The `transparent_sort` pass.
pub(crate) struct TransparentSortPass {
    pipeline: Pipeline,
}

impl PassNode for TransparentSortPass {
    /// Its commands follow from its settings, slots and the scene alone.
    fn replay_state(&self) -> Option<u64> {
        Some(0)
    }

    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let inputs = SceneInputs::of(rec)?;
        let scene = &inputs.scene;
        let region = FaceCull::Blended as usize;
        if scene.regions.len[region] == 0 {
            // Nothing transparent in the scene: no dispatch, and the `transparent` pass draws
            // nothing either (it does not read the list then).
            return Ok(());
        }
        let slots = &rec.slots;
        let source = DrawSource::bound(slots, SOURCE_SLOTS)?.unwrap_or_else(|| DrawSource::unculled(scene));
        let second = DrawSource::bound(slots, SECOND_SLOTS)?;
        let commands: &Buffer = slots.required_buffer(LIST_SLOTS[0])?;
        let count = slots.required_buffer(LIST_SLOTS[1])?;
        let ids = slots.required_buffer(LIST_SLOTS[2])?;
        let scratch = slots.required_buffer("scratch")?;
        let (capacity, keys) = capacity(commands.size(), ids.size(), scratch.size());

        let push = SortPush {
            first_command: scene.regions.first[region],
            region_commands: scene.regions.len[region],
            capacity,
            keys,
            count_index: region as u32,
            lists: if second.is_some() { 2 } else { 1 },
        };
        let second = second.as_ref().unwrap_or(&source);
        let mut binds = vec![
            Bind::Buffer(0, inputs.constants().handle()),
            Bind::Buffer(2, source.commands.handle()),
            Bind::Buffer(3, source.count.handle()),
            Bind::Buffer(4, source.instance_ids.handle()),
            Bind::Buffer(5, scratch.handle()),
            Bind::Buffer(6, commands.handle()),
            Bind::Buffer(7, count.handle()),
            Bind::Buffer(8, ids.handle()),
            Bind::Buffer(9, second.commands.handle()),
            Bind::Buffer(10, second.count.handle()),
            Bind::Buffer(11, second.instance_ids.handle()),
        ];
        binds.extend(scene.instance_binds(1));
        // One workgroup: the sort synchronizes its steps with workgroup barriers.
        self.pipeline.dispatch_over(rec.cmd, &binds, bytemuck::bytes_of(&push), vk::Extent2D { width: 1, height: 1 });
        Ok(())
    }
}

/// The `transparent_sort` pass kind.
pub struct TransparentSortKind;

impl PassKind for TransparentSortKind {
    fn info(&self) -> PassKindInfo {
        let read = |s: SlotDecl| SlotDecl { usage: Usage::StorageBufferRead(Stages::Compute), ..s };
        let source = list_slots(
            SOURCE_SLOTS,
            [
                "the culled list whose blended region holds every instance visible this frame (default: every instance)",
                "its counts",
                "its instance ids",
            ],
            false,
        )
        .map(read);
        let second = list_slots(
            SECOND_SLOTS,
            [
                "a second list whose blended region holds the rest of this frame's visible instances (an occluder pass's list)",
                "its counts",
                "its instance ids",
            ],
            false,
        )
        .map(read);
        let write = |name, bytes, doc| {
            slot(name, Usage::StorageBufferWrite(Stages::Compute), false, FormatRule::Any, doc)
                .at_least(bytes)
                .creates(Creates::buffer())
        };
        PassKindInfo {
            name: KIND,
            doc: "the transparent (alphaMode BLEND) instances a culled list kept, sorted back to front, as one draw command each (a scene with nothing transparent costs no dispatch; its list is then left unwritten, and the transparent pass draws nothing)",
            reads: source.into_iter().chain(second).collect(),
            writes: vec![
                write("draw_commands", SORTED_COMMANDS_BYTES, "one VkDrawIndexedIndirectCommand per transparent instance, farthest first").required().content(DRAW_COMMANDS),
                write("draw_count", "4", "their number").required().content(DRAW_COUNTS),
                write("draw_instance_ids", SORTED_IDS_BYTES, "their instance ids").required().content(INSTANCE_IDS),
                write("scratch", "max(1, blended) * 24", "the sort's keys and entries (created when unbound)").creates(Creates::buffer().always()),
            ],
            settings: vec![],
            slots_from_shader: false,
        }
    }

    fn quantities(&self) -> Vec<Quantity> {
        vec![BLENDED]
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        let spirv = s.shaders.compile("transparent_sort/transparent_sort.comp", &[])?;
        Ok(Box::new(TransparentSortPass { pipeline: Pipeline::compute(s.ctx, &s.pass.name, &spirv)? }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_capacity_is_what_every_buffer_holds() {
        // 10 commands, 10 ids, and scratch for 16 keys and 10 entries.
        assert_eq!(capacity(10 * COMMAND_BYTES, 40, 26 * 8), (10, 16));
        // A scratch one entry short holds 9 instances (16 keys + 9 entries).
        assert_eq!(capacity(10 * COMMAND_BYTES, 40, 25 * 8), (9, 16));
        // One of 8 keys + 8 entries holds 8.
        assert_eq!(capacity(10 * COMMAND_BYTES, 40, 16 * 8), (8, 8));
        assert_eq!(capacity(0, 40, 1000), (0, 1));
    }
}
