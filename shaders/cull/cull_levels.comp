#version 460
// Instance cull with levels of detail, between the test and the compact steps: one workgroup
// turns the superblocks' per-level counts into where each superblock's slots of each list and
// level start in the level-major order (every slot of lower levels first), so that a placing
// workgroup reads its own superblock's starts instead of every superblock's counts.
// MULTI_VIEW: workgroup v does so for view v of the views culled together, whose scratch it
// reaches through the table of their buffers (`cull_views.glsl`).
//
// Each invocation sums a contiguous range of superblocks per level; a scan within each subgroup and
// one over the subgroups' totals (one barrier) give each range's start; each thread then walks
// its range again. Subgroup operations only sum, so any subgroup size gives the same starts.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#define LOD 1
#include "cull_common.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

#ifdef MULTI_VIEW
#include "cull_views.glsl"
layout(set = 0, binding = 1, scalar) readonly buffer ViewTable { ViewBuffers view_table[]; };
#else
layout(set = 0, binding = 0) buffer Scratch { uint scratch[]; };
#endif

layout(push_constant) uniform Push {
    uint slot_count;
    uint superblocks;
} pc;

// Per level, each subgroup's total (at most THREADS subgroups, of one invocation each).
shared uint sh_subgroup_sums[LOD_LEVELS][THREADS];

void main() {
#ifdef MULTI_VIEW
    select_view_buffers(view_table[gl_WorkGroupID.x], gl_WorkGroupID.x);
#endif
    uint run = scratch[SCRATCH_PLACE_RUN];
    // Ranges follow the subgroups' order, so that the scans below see them in order however
    // invocations map to subgroups (256 invocations fill subgroups of any power-of-two size).
    uint index = gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
    uint per_thread = (pc.superblocks + THREADS - 1u) / THREADS;
    uint first = min(index * per_thread, pc.superblocks);
    uint last = min(first + per_thread, pc.superblocks);
    for (uint list = 0u; list < 2u; ++list) {
        uint sums[LOD_LEVELS];
        for (uint l = 0u; l < LOD_LEVELS; ++l) sums[l] = 0u;
        for (uint s = first; s < last; ++s) {
            uint at = scratch_super(pc.superblocks, run, s);
            for (uint l = 0u; l < LOD_LEVELS; ++l) sums[l] += scratch[at + SUPER_LEVEL(list, l)];
        }
        uint within[LOD_LEVELS];
        for (uint l = 0u; l < LOD_LEVELS; ++l) {
            within[l] = subgroupExclusiveAdd(sums[l]);
            uint total = subgroupAdd(sums[l]);
            if (subgroupElect()) sh_subgroup_sums[l][gl_SubgroupID] = total;
        }
        barrier();
        // Level l starts after every slot of the levels below it; a range after the subgroups
        // before its own and the ranges before it in its subgroup.
        uint start[LOD_LEVELS];
        uint lower = 0u;
        for (uint l = 0u; l < LOD_LEVELS; ++l) {
            uint before = 0u, all = 0u;
            for (uint g = 0u; g < gl_NumSubgroups; ++g) {
                uint n = sh_subgroup_sums[l][g];
                before += g < gl_SubgroupID ? n : 0u;
                all += n;
            }
            start[l] = lower + before + within[l];
            lower += all;
        }
        for (uint s = first; s < last; ++s) {
            uint at = scratch_super(pc.superblocks, run, s);
            for (uint l = 0u; l < LOD_LEVELS; ++l) {
                scratch[scratch_level_start(pc.superblocks, pc.slot_count, s, list, l)] = start[l];
                start[l] += scratch[at + SUPER_LEVEL(list, l)];
            }
        }
        // The next list reuses the shared sums.
        barrier();
    }
}
