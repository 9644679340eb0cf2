#version 460
// Instance cull, step 2 of 2. Workgroup 0 writes the commands; every other workgroup places the
// survivors of one block. Both read only what the test step finished writing, so neither waits
// for the other (Vulkan does not promise that a waiting workgroup lets another make progress).
//
// Survivors are compacted in slot order: a survivor's position is the number of survivors in
// slots before it (superblock counts before its superblock + block counts before its block in
// the superblock + bits before it in the block). Slots are sorted by draw group, so each group's
// survivors form one slice, in instance order, every run; the group's command starts there
// (first instance = the survivors of the groups before it, summed from the group counts).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "cull_common.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

layout(set = 0, binding = 0) readonly buffer DrawBits { uint draw_bits[]; };
layout(set = 0, binding = 1) buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 5) buffer GroupCounts { uint group_counts[]; };
layout(set = 0, binding = 6, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 7) writeonly buffer DrawCount { uint draw_count; };
layout(set = 0, binding = 8, scalar) writeonly buffer Stats { CullStats stats; };

layout(push_constant) uniform Push {
    uint slot_count;
    uint group_count;
    uint superblocks;
} pc;

// Placing a block.
shared uint sh_words[CULL_WORDS_PER_BLOCK];
shared uint sh_before;
// Writing the commands.
shared uvec2 sh_scan[THREADS];
shared uint sh_totals[8];

// Survivors among this block's bits below slot offset `k` (0..CULL_BLOCK).
uint local_before(uint k) {
    uint count = 0u;
    for (uint w = 0u; w < (k >> 5u); ++w) count += bitCount(sh_words[w]);
    uint bit = k & 31u;
    if (bit != 0u) count += bitCount(sh_words[k >> 5u] & ((1u << bit) - 1u));
    return count;
}

void place_block(uint block) {
    uint lane = gl_LocalInvocationIndex;
    // Nothing to place (every invocation reads the same word, so all return together).
    if (scratch[scratch_block(pc.superblocks, block)] == 0u) return;
    uint run = scratch[SCRATCH_PLACE_RUN];
    if (lane < CULL_WORDS_PER_BLOCK) sh_words[lane] = draw_bits[block * CULL_WORDS_PER_BLOCK + lane];
    if (lane == 0u) sh_before = 0u;
    uint super_index = block / CULL_SUPERBLOCK;
    uint sum = 0u;
    for (uint s = lane; s < super_index; s += THREADS) {
        sum += scratch[scratch_super(pc.superblocks, run, s) + SUPER_SURVIVORS];
    }
    for (uint k = super_index * CULL_SUPERBLOCK + lane; k < block; k += THREADS) {
        sum += scratch[scratch_block(pc.superblocks, k)];
    }
    barrier();
    sum = subgroupAdd(sum);
    if (subgroupElect() && sum != 0u) atomicAdd(sh_before, sum);
    barrier();
    // Bits past the last slot are never set.
    if (((sh_words[lane >> 5u] >> (lane & 31u)) & 1u) != 0u) {
        draw_ids[sh_before + local_before(lane)] = slot_instances[block * CULL_BLOCK + lane];
    }
}

// Inclusive scan of one pair per invocation in invocation order; returns the invocation's
// exclusive prefix, and the pair's total over the workgroup in `total`.
uvec2 workgroup_exclusive_scan(uvec2 value, out uvec2 total) {
    uint lane = gl_LocalInvocationIndex;
    sh_scan[lane] = value;
    barrier();
    for (uint offset = 1u; offset < THREADS; offset <<= 1u) {
        uvec2 add = lane >= offset ? sh_scan[lane - offset] : uvec2(0u);
        barrier();
        sh_scan[lane] += add;
        barrier();
    }
    uvec2 inclusive = sh_scan[lane];
    total = sh_scan[THREADS - 1u];
    barrier();
    return inclusive - value;
}

// Counters of the run: sums of the superblock records (indices into sh_totals).
#define TOTAL_TESTED 0
#define TOTAL_FRUSTUM 1
#define TOTAL_OCCLUSION 2
#define TOTAL_VISIBLE 3
#define TOTAL_TRIANGLES 5   // three words: triangle count bits 0-23, 24-47, 48-63

void write_commands() {
    uint lane = gl_LocalInvocationIndex;
    uint run = scratch[SCRATCH_PLACE_RUN];
    if (lane < 8u) sh_totals[lane] = 0u;
    barrier();
    uvec4 counters = uvec4(0u);
    for (uint s = lane; s < pc.superblocks; s += THREADS) {
        uint at = scratch_super(pc.superblocks, run, s);
        counters += uvec4(scratch[at + SUPER_TESTED], scratch[at + SUPER_FRUSTUM], scratch[at + SUPER_OCCLUSION],
                          scratch[at + SUPER_VISIBLE]);
    }
    // The next run's half back to zero (its last readers finished in the previous run).
    uint next = scratch_super(pc.superblocks, run + 1u, 0u);
    for (uint i = lane; i < pc.superblocks * SUPER_WORDS; i += THREADS) scratch[next + i] = 0u;

    // One command per non-empty group, in group order; each group's count back to zero.
    uint written = 0u;
    uint placed = 0u;
    uint64_t triangles = 0ul;
    for (uint chunk = 0u; chunk < pc.group_count; chunk += THREADS) {
        uint g = chunk + lane;
        uint count = 0u;
        DrawGroup group;
        if (g < pc.group_count) {
            count = group_counts[g];
            if (count != 0u) {
                group = groups[g];
                group_counts[g] = 0u;
            }
        }
        uvec2 total;
        uvec2 before = workgroup_exclusive_scan(uvec2(count, count != 0u ? 1u : 0u), total);
        if (count != 0u) {
            DrawCommand cmd;
            cmd.index_count = group.index_count;
            cmd.instance_count = count;
            cmd.first_index = group.first_index;
            cmd.vertex_offset = group.vertex_offset;
            cmd.first_instance = placed + before.x;
            commands[written + before.y] = cmd;
            triangles += uint64_t(group.index_count / 3u) * uint64_t(count);
        }
        placed += total.x;
        written += total.y;
    }

    // Sums over the workgroup: each part is below 2^24 per invocation, so a sum over 256 fits.
    counters = subgroupAdd(counters);
    uvec3 parts = subgroupAdd(uvec3(uint(triangles) & 0xFFFFFFu, uint(triangles >> 24) & 0xFFFFFFu,
                                    uint(triangles >> 48)));
    if (subgroupElect()) {
        for (uint i = 0u; i < 4u; ++i) atomicAdd(sh_totals[TOTAL_TESTED + i], counters[i]);
        for (uint i = 0u; i < 3u; ++i) atomicAdd(sh_totals[TOTAL_TRIANGLES + i], parts[i]);
    }
    barrier();
    if (lane == 0u) {
        uint64_t sum = uint64_t(sh_totals[TOTAL_TRIANGLES]) + (uint64_t(sh_totals[TOTAL_TRIANGLES + 1]) << 24)
            + (uint64_t(sh_totals[TOTAL_TRIANGLES + 2]) << 48);
        draw_count = written;
        CullStats s;
        s.tested = sh_totals[TOTAL_TESTED];
        s.frustum_culled = sh_totals[TOTAL_FRUSTUM];
        s.occlusion_culled = sh_totals[TOTAL_OCCLUSION];
        s.drawn = placed;
        s.draws = written;
        s.triangles_lo = uint(sum);
        s.triangles_hi = uint(sum >> 32);
        s.survivors = sh_totals[TOTAL_VISIBLE];
        for (uint i = 0u; i < 8u; ++i) s.pad[i] = 0u;
        stats = s;
        // Nothing reads this word in this dispatch: the next run's test step does.
        scratch[SCRATCH_TEST_RUN] = run + 1u;
    }
}

void main() {
    if (gl_WorkGroupID.x == 0u) {
        write_commands();
    } else {
        place_block(gl_WorkGroupID.x - 1u);
    }
}
