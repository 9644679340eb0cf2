#version 460
// Cluster cull, step 1 of 2, in one workgroup: walks the drawn regions of the input list in
// command order. A command of an opaque region (MASKED: or an alpha-masked one) whose level has
// clusters is emptied in the pass-through list (its instances are drawn cluster by cluster
// instead) and gets a range of test tasks, one per instance and chunk of CLUSTER_CHUNK
// clusters; any other is passed on whole. Writes the test step's dispatch size and zeroes its
// counts.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "../common/scene.glsl"
#include "../cull/cull_common.glsl"
#include "cluster_common.glsl"

#define THREADS 256u
layout(local_size_x = THREADS) in;

layout(set = 0, binding = 0, scalar) readonly buffer InCommands { DrawCommand in_commands[]; };
layout(set = 0, binding = 1) readonly buffer InCount { uint in_count[FACE_CULL_REGIONS]; };
layout(set = 0, binding = 2) readonly buffer ClusterMeshes { uvec2 cluster_meshes[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Clusters { Cluster clusters[]; };
layout(set = 0, binding = 6) readonly buffer ClusterRanges { uvec2 cluster_ranges[]; };
layout(set = 0, binding = 7, scalar) writeonly buffer PassCommands { DrawCommand pass_commands[]; };
layout(set = 0, binding = 8) writeonly buffer PassCount { uint pass_count[FACE_CULL_REGIONS]; };
layout(set = 0, binding = 9) buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 10) writeonly buffer ClusterCount { uint cluster_count[CLUSTER_REGIONS]; };
layout(set = 0, binding = 11) buffer Stats { uint stats[STAT_WORDS]; };
#ifdef MASKED
layout(set = 0, binding = 12) writeonly buffer MaskedClusterCount { uint masked_cluster_count[CLUSTER_REGIONS]; };
#endif
// The test step's VkDispatchIndirectCommand (x, y, z), in the pass's own buffer: written here,
// so that no copy (and no barrier before and after it) stands between the two steps.
layout(set = 0, binding = 13) writeonly buffer TestDispatch { uint test_dispatch[3]; };

layout(push_constant) uniform Push {
    uint region_first[FACE_CULL_REGIONS];   // first command of each region
    uint region_len[FACE_CULL_REGIONS];     // commands each region holds
    uint max_groups;      // the test step's largest dispatch
    uint tasks_per_group; // tasks its workgroups take at a time
    uint clustered_capacity; // clustered commands the scratch holds
    uint clustered_meshes;   // entries of cluster_meshes
    uint clustered_regions;  // regions drawn cluster by cluster: the opaque ones (MASKED: and the masked ones)
} pc;

#define RANGES_PER_MESH 8u

// The clusters of the level that `c` draws: (first, count), count 0 for none. A command names
// its mesh by its vertex offset (no two meshes share one) and its level by its first index, at
// which the level's first cluster starts.
uvec2 clusters_of(DrawCommand c) {
    if (c.instance_count == 0u || pc.clustered_meshes == 0u) return uvec2(0u);
    uint offset = uint(c.vertex_offset);
    uint lo = 0u, hi = pc.clustered_meshes;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (cluster_meshes[mid].x <= offset) lo = mid; else hi = mid;
    }
    if (cluster_meshes[lo].x != offset) return uvec2(0u);
    uint mesh = cluster_meshes[lo].y;
    for (uint level = 0u; level < RANGES_PER_MESH; ++level) {
        uvec2 range = cluster_ranges[mesh * RANGES_PER_MESH + level];
        if (range.y != 0u && clusters[range.x].first_index == c.first_index) return range;
    }
    return uvec2(0u);
}

shared uint sh_sums[THREADS / 4u][2];  // per subgroup (subgroups of 4 invocations or more)
shared uint sh_total[2];

void main() {
    uint lane = gl_LocalInvocationID.x;
    if (lane < STAT_WORDS) stats[lane] = 0u;
    memoryBarrierBuffer();
    barrier();
    uint tasks = 0u;
    uint clustered = 0u;
    uint whole = 0u;
    for (uint r = 0u; r < FACE_CULL_REGIONS; ++r) {
        // The transparent region is drawn by the transparent pass, from another list.
        uint count = r + 1u < FACE_CULL_REGIONS ? min(in_count[r], pc.region_len[r]) : 0u;
        if (lane == 0u) {
            pass_count[r] = count;
            if (r < CLUSTER_REGIONS) cluster_count[r] = 0u;
#ifdef MASKED
            if (r >= CLUSTER_REGIONS && r < 2u * CLUSTER_REGIONS) masked_cluster_count[r - CLUSTER_REGIONS] = 0u;
#endif
        }
        for (uint base = 0u; base < count; base += THREADS) {
            uint i = pc.region_first[r] + base + lane;
            bool valid = base + lane < count;
            DrawCommand c = DrawCommand(0u, 0u, 0u, 0, 0u);
            uvec2 range = uvec2(0u);
            if (valid) {
                c = in_commands[i];
                range = clusters_of(c);
            }
            // The opaque regions, then (MASKED) the masked ones, whose clusters go to a list of
            // their own (drawn with the pipelines that alpha-test).
            bool split = valid && range.y != 0u && r < pc.clustered_regions;
            uint chunks = (range.y + CLUSTER_CHUNK - 1u) / CLUSTER_CHUNK;
            uint my_tasks = split ? c.instance_count * chunks : 0u;
            // Exclusive prefix over the workgroup of (tasks, clustered commands).
            uvec2 mine = uvec2(my_tasks, split ? 1u : 0u);
            uvec2 inclusive = subgroupInclusiveAdd(mine);
            // Subgroups of any size: each writes its total, then one thread scans the totals.
            uint subgroup_slot = gl_SubgroupID;
            if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) {
                sh_sums[subgroup_slot][0] = inclusive.x;
                sh_sums[subgroup_slot][1] = inclusive.y;
            }
            barrier();
            if (lane == 0u) {
                uvec2 run = uvec2(0u);
                for (uint s = 0u; s < gl_NumSubgroups; ++s) {
                    uvec2 here = uvec2(sh_sums[s][0], sh_sums[s][1]);
                    sh_sums[s][0] = run.x;
                    sh_sums[s][1] = run.y;
                    run += here;
                }
                sh_total[0] = run.x;
                sh_total[1] = run.y;
            }
            barrier();
            uvec2 before = uvec2(sh_sums[subgroup_slot][0], sh_sums[subgroup_slot][1]) + inclusive - mine;
            if (valid) {
                DrawCommand out_c = c;
                if (split) {
                    out_c.instance_count = 0u;
                    uint k = clustered + before.y;
                    if (k < pc.clustered_capacity) {
                        uint at = SCRATCH_HEADER_WORDS + k * 8u;
                        scratch[at + 0u] = tasks + before.x;
                        scratch[at + 1u] = chunks;
                        scratch[at + 2u] = range.x;
                        scratch[at + 3u] = range.y;
                        scratch[at + 4u] = i;
                        scratch[at + 5u] = r;
                    }
                } else if (c.instance_count != 0u) {
                    atomicAdd(stats[STAT_WHOLE], 1u);
                }
                pass_commands[i] = out_c;
            }
            tasks += sh_total[0];
            clustered += sh_total[1];
            barrier();
        }
    }
    if (lane == 0u) {
        clustered = min(clustered, pc.clustered_capacity);
        scratch[SCRATCH_CLUSTERED] = clustered;
        scratch[SCRATCH_TASKS] = tasks;
        test_dispatch[0] = min((tasks + pc.tasks_per_group - 1u) / pc.tasks_per_group, pc.max_groups);
        test_dispatch[1] = 1u;
        test_dispatch[2] = 1u;
    }
}
