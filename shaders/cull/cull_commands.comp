#version 460
// Instance cull, step 3 of 3 (one workgroup): per draw group the survivors between its base and
// the next group's, one draw command per non-empty group, compacted in group order (so the
// command list is the same every run), the pass's counters; then it resets the scratch counters
// for the pass's next frame.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "cull_common.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 1) readonly buffer GroupBase { uint group_base[]; };
layout(set = 0, binding = 2) buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 3, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 4) writeonly buffer DrawCount { uint draw_count; };
layout(set = 0, binding = 5, scalar) writeonly buffer Stats { CullStats stats; };

layout(push_constant) uniform Push {
    uint group_count;
    uint superblocks;
} pc;

shared uint sh_scan[THREADS];
shared uint sh_total;
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

void main() {
    uint lane = gl_LocalInvocationIndex;
    // Every survivor of the pass: the sum of the superblock counts.
    uint partial = 0u;
    for (uint s = lane; s < pc.superblocks; s += THREADS) partial += scratch[scratch_superblock(s)];
    workgroup_exclusive_scan(partial);
    uint survivors = sh_total;
    barrier();
    uint written = 0u;
    uint64_t triangles = 0ul;
    for (uint chunk = 0u; chunk < pc.group_count; chunk += THREADS) {
        uint g = chunk + lane;
        uint count = 0u;
        DrawGroup group;
        if (g < pc.group_count) {
            group = groups[g];
            uint next = g + 1u < pc.group_count ? group_base[g + 1u] : survivors;
            count = next - group_base[g];
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
    sh_triangles[lane] = triangles;
    barrier();
    if (lane == 0u) {
        uint64_t sum = 0ul;
        for (uint t = 0u; t < THREADS; ++t) sum += sh_triangles[t];
        draw_count = written;
        CullStats s;
        s.tested = scratch[SCRATCH_TESTED];
        s.frustum_culled = scratch[SCRATCH_FRUSTUM];
        s.occlusion_culled = scratch[SCRATCH_OCCLUSION];
        s.drawn = survivors;
        s.draws = written;
        s.triangles_lo = uint(sum);
        s.triangles_hi = uint(sum >> 32);
        s.survivors = scratch[SCRATCH_VISIBLE];
        for (uint i = 0u; i < 8u; ++i) s.pad[i] = 0u;
        stats = s;
    }
    // Ready for this pass's next run: counters and superblock counts back to zero (block counts
    // are overwritten by every run).
    barrier();
    for (uint i = lane; i < SCRATCH_HEADER + pc.superblocks; i += THREADS) scratch[i] = 0u;
}
