#version 460
// Instance cull, step 3 of 3: every surviving slot writes its instance id into its group's
// slice of the draw list, at (group's first slot) + (survivors before it in the group). The
// order within each slice is slot order, i.e. instance order.
#extension GL_GOOGLE_include_directive : require
#include "cull_common.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0) readonly buffer Flags { uint draw_bits[]; };
layout(set = 0, binding = 1) readonly buffer BlockPrefix { uint block_prefix[]; };
layout(set = 0, binding = 2) readonly buffer SlotGroups { uint slot_groups[]; };
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 5) readonly buffer GroupBase { uint group_base[]; };
layout(set = 0, binding = 6) writeonly buffer DrawIds { uint draw_ids[]; };

layout(push_constant) uniform Push { uint slot_count; } pc;

void main() {
    uint slot = gl_GlobalInvocationID.x;
    if (slot >= pc.slot_count) return;
    uint word = draw_bits[slot >> 5u];
    uint bit = slot & 31u;
    if (((word >> bit) & 1u) == 0u) return;
    // Survivors before this slot: the block's prefix plus the bits before it in its block.
    uint block = slot / CULL_BLOCK;
    uint count = block_prefix[block];
    for (uint w = block * CULL_WORDS_PER_BLOCK; w < (slot >> 5u); ++w) count += bitCount(draw_bits[w]);
    if (bit != 0u) count += bitCount(word & ((1u << bit) - 1u));
    uint g = slot_groups[slot];
    draw_ids[groups[g].first_slot + (count - group_base[g])] = slot_instances[slot];
}
