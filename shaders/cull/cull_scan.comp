#version 460
// Instance cull, step 2 of 3 (one workgroup): an exclusive prefix sum over the blocks'
// survivor counts, then per draw group the number of survivors and the group's base in the
// sum, and one draw command per non-empty group, compacted in group order (so the command
// list, like the instance list, is the same every run).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "cull_common.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

layout(set = 0, binding = 0) readonly buffer Flags { uint draw_bits[]; };
layout(set = 0, binding = 1) readonly buffer BlockInfo { uvec4 block_info[]; };
layout(set = 0, binding = 2) coherent buffer BlockPrefix { uint block_prefix[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 4) writeonly buffer GroupBase { uint group_base[]; };
layout(set = 0, binding = 5, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 6) writeonly buffer DrawCount { uint draw_count; };
layout(set = 0, binding = 7, scalar) buffer Stats { CullStats stats; };

layout(push_constant) uniform Push {
    uint slot_count;
    uint block_count;
    uint group_count;
} pc;

shared uint sh_scan[THREADS];
shared uint sh_total;        // sum of the last workgroup_exclusive_scan
shared uint sh_survivors;    // survivors of the whole pass
shared uint64_t sh_triangles[THREADS];

// Exclusive scan of one value per thread; returns the thread's prefix, leaves the sum in sh_total.
uint workgroup_exclusive_scan(uint value) {
    uint lane = gl_LocalInvocationIndex;
    sh_scan[lane] = value;
    barrier();
    for (uint offset = 1u; offset < THREADS; offset <<= 1u) {
        uint add = lane >= offset ? sh_scan[lane - offset] : 0u;
        barrier();
        sh_scan[lane] += add;
        barrier();
    }
    uint inclusive = sh_scan[lane];
    if (lane == THREADS - 1u) sh_total = inclusive;
    barrier();
    return inclusive - value;
}

// Survivors among slots [0, slot): the block's prefix plus the bits before `slot` in its block.
uint survivors_before(uint slot) {
    uint block = slot / CULL_BLOCK;
    if (block >= pc.block_count) return sh_survivors;
    uint count = block_prefix[block];
    uint first_word = block * CULL_WORDS_PER_BLOCK;
    uint word = slot >> 5u;
    for (uint w = first_word; w < word; ++w) count += bitCount(draw_bits[w]);
    uint bit = slot & 31u;
    if (bit != 0u) count += bitCount(draw_bits[word] & ((1u << bit) - 1u));
    return count;
}

void main() {
    uint lane = gl_LocalInvocationIndex;
    // 1. Block prefix: each thread sums a contiguous run of blocks, then the runs are scanned.
    uint per_thread = (pc.block_count + THREADS - 1u) / THREADS;
    uint first = lane * per_thread;
    uint last = min(first + per_thread, pc.block_count);
    uint sum = 0u;
    uvec4 counters = uvec4(0u);   // tested, frustum culled, occlusion culled, visible now
    for (uint b = first; b < last; ++b) {
        uvec4 info = block_info[b * 2u];
        sum += info.x;
        counters += uvec4(info.yzw, block_info[b * 2u + 1u].x);
    }
    uint running = workgroup_exclusive_scan(sum);
    for (uint b = first; b < last; ++b) {
        block_prefix[b] = running;
        running += block_info[b * 2u].x;
    }
    uint total = sh_total;
    // Counter totals, one component at a time through the same scan.
    workgroup_exclusive_scan(counters.x);
    uint tested = sh_total;
    workgroup_exclusive_scan(counters.y);
    uint frustum_culled = sh_total;
    workgroup_exclusive_scan(counters.z);
    uint occlusion_culled = sh_total;
    workgroup_exclusive_scan(counters.w);
    uint visible_now = sh_total;
    if (lane == 0u) sh_survivors = total;
    memoryBarrierBuffer();
    memoryBarrierShared();
    barrier();

    // 2. Per group: survivors and base; commands for non-empty groups, compacted in order.
    uint written = 0u;
    uint64_t triangles = 0ul;
    for (uint chunk = 0u; chunk < pc.group_count; chunk += THREADS) {
        uint g = chunk + lane;
        uint count = 0u;
        uint base = 0u;
        DrawGroup group;
        if (g < pc.group_count) {
            group = groups[g];
            base = survivors_before(group.first_slot);
            count = survivors_before(group.first_slot + group.slot_count) - base;
            group_base[g] = base;
        }
        uint index = written + workgroup_exclusive_scan(count != 0u ? 1u : 0u);
        if (count != 0u) {
            DrawCommand cmd;
            cmd.index_count = group.index_count;
            cmd.instance_count = count;
            cmd.first_index = group.first_index;
            cmd.vertex_offset = group.vertex_offset;
            cmd.first_instance = group.first_slot;
            commands[index] = cmd;
            triangles += uint64_t(group.index_count / 3u) * uint64_t(count);
        }
        written += sh_total;
        barrier();
    }
    // Triangles: a 64-bit sum over the threads.
    sh_triangles[lane] = triangles;
    barrier();
    if (lane == 0u) {
        uint64_t sum_triangles = 0ul;
        for (uint t = 0u; t < THREADS; ++t) sum_triangles += sh_triangles[t];
        draw_count = written;
        CullStats s;
        s.tested = tested;
        s.frustum_culled = frustum_culled;
        s.occlusion_culled = occlusion_culled;
        s.drawn = total;
        s.draws = written;
        s.triangles_lo = uint(sum_triangles);
        s.triangles_hi = uint(sum_triangles >> 32);
        s.survivors = visible_now;
        for (uint i = 0u; i < 8u; ++i) s.pad[i] = 0u;
        stats = s;
    }
}
