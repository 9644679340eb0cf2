#version 460
// Instance cull, step 2 of 3: each workgroup places the survivors of its block. Survivors
// before the block = superblock counts before its superblock + block counts before it in its
// superblock (all final: the test step finished). Each survivor writes its instance id at
// (its group's first slot) + (survivors before it in the group), so every group's slice holds
// its survivors in instance order, every run. Groups that start in the block get their base
// (survivors before their first slot) written for the commands step.
#extension GL_GOOGLE_include_directive : require
#include "cull_common.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

layout(set = 0, binding = 0) readonly buffer DrawBits { uint draw_bits[]; };
layout(set = 0, binding = 1) readonly buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 5) writeonly buffer GroupBase { uint group_base[]; };

layout(push_constant) uniform Push {
    uint slot_count;
    uint group_count;
    uint superblocks;
} pc;

shared uint sh_words[CULL_WORDS_PER_BLOCK];
shared uint sh_sum[THREADS];
shared uint sh_first_group;
shared uint sh_group_count;                 // groups that meet the block
shared uint sh_group_first[THREADS];        // their first slots, in order
shared uint sh_group_base[THREADS];         // survivors before each of them

// Survivors before block `b` (all threads must call it together).
uint survivors_before_block(uint b) {
    uint lane = gl_LocalInvocationIndex;
    uint super_index = b / CULL_SUPERBLOCK;
    uint sum = 0u;
    for (uint s = lane; s < super_index; s += THREADS) sum += scratch[scratch_superblock(s)];
    uint first = super_index * CULL_SUPERBLOCK;
    for (uint k = first + lane; k < b; k += THREADS) sum += scratch[scratch_block(pc.superblocks, k)];
    sh_sum[lane] = sum;
    barrier();
    for (uint offset = THREADS / 2u; offset > 0u; offset >>= 1u) {
        if (lane < offset) sh_sum[lane] += sh_sum[lane + offset];
        barrier();
    }
    uint total = sh_sum[0];
    barrier();
    return total;
}

// Survivors among the bits of block `b` below slot offset `k` (0..CULL_BLOCK).
uint bits_before(uint b, uint k) {
    uint count = 0u;
    for (uint w = 0u; w < (k >> 5u); ++w) count += bitCount(draw_bits[b * CULL_WORDS_PER_BLOCK + w]);
    uint bit = k & 31u;
    if (bit != 0u) count += bitCount(draw_bits[b * CULL_WORDS_PER_BLOCK + (k >> 5u)] & ((1u << bit) - 1u));
    return count;
}

// Same, from this block's words in shared memory.
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
    if (lane < CULL_WORDS_PER_BLOCK) sh_words[lane] = draw_bits[block * CULL_WORDS_PER_BLOCK + lane];
    if (lane == 0u) {
        // The group holding the block's first slot (groups are sorted by first slot).
        uint lo = 0u;
        uint hi = pc.group_count;
        while (hi - lo > 1u) {
            uint mid = (lo + hi) >> 1u;
            if (groups[mid].first_slot <= block_start) lo = mid; else hi = mid;
        }
        sh_first_group = lo;
        sh_group_count = 0u;
    }
    barrier();
    uint first_group = sh_first_group;
    uint g = first_group + lane;
    uint first_slot = g < pc.group_count ? groups[g].first_slot : 0xFFFFFFFFu;
    bool meets = g < pc.group_count && (lane == 0u || first_slot < block_end);
    if (meets) {
        sh_group_first[lane] = first_slot;
        atomicMax(sh_group_count, lane + 1u);
    }
    uint survivors = 0u;
    for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) survivors += bitCount(sh_words[w]);
    barrier();
    bool starts_here = sh_group_count > 1u || sh_group_first[0] == block_start;
    // Nothing to place and no group base to publish: done.
    if (survivors == 0u && !starts_here) return;

    uint before = survivors_before_block(block);
    if (meets && first_slot >= block_start) {
        uint base = before + local_before(first_slot - block_start);
        sh_group_base[lane] = base;
        group_base[g] = base;
    }
    uint first = sh_group_first[0];
    if (survivors != 0u && first < block_start) {
        // The block's first group began in an earlier block: count from that block's prefix.
        uint origin = first / CULL_BLOCK;
        uint base = survivors_before_block(origin);
        if (lane == 0u) sh_group_base[0] = base + bits_before(origin, first - origin * CULL_BLOCK);
    }
    barrier();

    uint slot = block_start + lane;
    if (slot < pc.slot_count && ((sh_words[lane >> 5u] >> (lane & 31u)) & 1u) != 0u) {
        // This slot's group among the block's groups: the last one starting at or before it.
        uint k = 0u;
        for (uint i = 1u; i < sh_group_count; ++i) {
            if (sh_group_first[i] <= slot) k = i;
        }
        uint position = sh_group_first[k] + (before + local_before(lane) - sh_group_base[k]);
        draw_ids[position] = slot_instances[slot];
    }
}
