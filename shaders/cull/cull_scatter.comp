#version 460
// Instance cull, step 2 of 2: each workgroup places the survivors of its block. The test step
// left, per block, the survivors before it (exclusive prefix sum in the scratch) and the draw
// group of its first survivor (no search for it here: every step in a search is a round trip to
// memory), and per draw group the survivors before its first slot (group_base). Each survivor writes its
// instance id at (its group's first slot) + (survivors before it in the group), so every group's
// slice holds its survivors in instance order, every run.
#extension GL_GOOGLE_include_directive : require
#include "cull_common.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

layout(set = 0, binding = 0) readonly buffer DrawBits { uint draw_bits[]; };
layout(set = 0, binding = 1) readonly buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 5) readonly buffer GroupBase { uint group_base[]; };

layout(push_constant) uniform Push {
    uint slot_count;
    uint group_count;
} pc;

shared uint sh_words[CULL_WORDS_PER_BLOCK];
shared uint sh_group_count;                 // groups that meet the block
shared uint sh_group_first[THREADS];        // their first slots, in order
shared uint sh_group_base[THREADS];         // survivors before each of them

// Survivors among this block's bits below slot offset `k` (0..CULL_BLOCK).
uint local_before(uint k) {
    uint count = 0u;
    for (uint w = 0u; w < (k >> 5u); ++w) count += bitCount(sh_words[w]);
    uint bit = k & 31u;
    if (bit != 0u) count += bitCount(sh_words[k >> 5u] & ((1u << bit) - 1u));
    return count;
}

void main() {
    uint lane = gl_LocalInvocationIndex;
    uint block = gl_WorkGroupID.x;
    uint block_start = block * CULL_BLOCK;
    uint block_end = min(block_start + CULL_BLOCK, pc.slot_count);
    uint blocks = (pc.slot_count + CULL_BLOCK - 1u) / CULL_BLOCK;
    // One round of loads: the bits, the survivors before the block, its first survivor's group.
    if (lane < CULL_WORDS_PER_BLOCK) sh_words[lane] = draw_bits[block * CULL_WORDS_PER_BLOCK + lane];
    if (lane == 0u) sh_group_count = 0u;
    uint before = scratch[scratch_block(block)];
    uint g0 = scratch[scratch_block_group(blocks, block)];
    barrier();
    uint survivors = 0u;
    for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) survivors += bitCount(sh_words[w]);
    if (survivors == 0u) return;  // uniform: nothing to place

    // A second round: the groups that meet the block from its first survivor's on (groups are
    // sorted by slot), and the survivors' instance ids.
    uint slot = block_start + lane;
    bool drawn = slot < pc.slot_count && ((sh_words[lane >> 5u] >> (lane & 31u)) & 1u) != 0u;
    uint id = drawn ? slot_instances[slot] : 0u;
    uint g = g0 + lane;
    uint first_slot = g < pc.group_count ? groups[g].first_slot : 0xFFFFFFFFu;
    if (g < pc.group_count && (lane == 0u || first_slot < block_end)) {
        sh_group_first[lane] = first_slot;
        sh_group_base[lane] = group_base[g];
        atomicMax(sh_group_count, lane + 1u);
    }
    barrier();

    if (drawn) {
        // This slot's group among the block's groups: the last one starting at or before it.
        uint k = 0u;
        for (uint i = 1u; i < sh_group_count; ++i) {
            if (sh_group_first[i] <= slot) k = i;
        }
        uint position = sh_group_first[k] + (before + local_before(lane) - sh_group_base[k]);
        draw_ids[position] = id;
    }
}
