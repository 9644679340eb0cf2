#version 460
// Cluster cull, step 2 of 2: each workgroup takes TASKS_PER_GROUP tasks at a time (a task: one
// instance's chunk of CLUSTER_CHUNK clusters of its level) and tests each cluster: outside the frustum, covering no sample
// position (SMALL_OBJECTS), facing away from the eye (its normal cone, for one-sided materials
// under rotation and uniform scale), or behind the Hi-Z (HAS_HIZ). Each survivor is appended to
// its face-cull region of the cluster list (MASKED: a masked instance's to the masked list) as
// one command of its index range and its instance.
// Every test is conservative, so the triangles dropped could make no fragment.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#define CULL_HIZ_MIN_LEVEL 1u

#include "../common/scene.glsl"
#include "../common/hiz.glsl"
#include "../cull/cull_common.glsl"
#include "cluster_common.glsl"

// Tasks a workgroup tests together: its survivors are counted in shared memory and reserved
// with one atomic per region, so few workgroups contend for the list's counts.
#define TASKS_PER_GROUP 4u
layout(local_size_x = CLUSTER_CHUNK * TASKS_PER_GROUP) in;

layout(set = 0, binding = 0, scalar) uniform Frame { FrameConstants frame; };
#define INSTANCES_BINDING 1
#include "../common/instance_ranges.glsl"
layout(set = 0, binding = 2, scalar) readonly buffer InCommands { DrawCommand in_commands[]; };
layout(set = 0, binding = 3) readonly buffer InIds { uint in_ids[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Clusters { Cluster clusters[]; };
layout(set = 0, binding = 5) readonly buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 6, scalar) writeonly buffer ClusterCommands { DrawCommand cluster_commands[]; };
layout(set = 0, binding = 7) buffer ClusterCount { uint cluster_count[CLUSTER_REGIONS]; };
layout(set = 0, binding = 8) buffer Stats { uint stats[STAT_WORDS]; };
#ifdef MASKED
layout(set = 0, binding = 10, scalar) writeonly buffer MaskedClusterCommands { DrawCommand masked_cluster_commands[]; };
layout(set = 0, binding = 11) buffer MaskedClusterCount { uint masked_cluster_count[CLUSTER_REGIONS]; };
#define REGIONS (2u * CLUSTER_REGIONS)
#else
#define REGIONS CLUSTER_REGIONS
#endif
#ifdef HAS_HIZ
layout(set = 0, binding = 9) uniform sampler2D hiz_tex;
float hiz_load(uint level, uvec2 texel) { return texelFetch(hiz_tex, ivec2(texel), int(hiz_stored_mip(level))).r; }
#endif

layout(push_constant) uniform Push {
    uint region_capacity;          // commands each region of the cluster list holds
    uint masked_region_capacity;   // MASKED: of the masked instances' list
} pc;

// Normal cones are tested with this much to spare, so a triangle seen nearly edge-on, which
// the rasterizer's fixed-point facing test may still take as front-facing, is kept.
#define CONE_MARGIN 1e-3

// The clustered command whose tasks hold `task` (the last one starting at or before it).
uint command_of(uint task, uint commands) {
    uint lo = 0u, hi = commands;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (scratch[SCRATCH_HEADER_WORDS + mid * 8u] <= task) lo = mid; else hi = mid;
    }
    return lo;
}

// Whether the linear part `m` is a rotation (or mirror) times one scale: the normal cone then
// maps to the world as the cluster's points do.
bool uniform_scale(mat3 m) {
    vec3 l = vec3(dot(m[0], m[0]), dot(m[1], m[1]), dot(m[2], m[2]));
    float most = max(l.x, max(l.y, l.z));
    vec3 off = abs(vec3(dot(m[0], m[1]), dot(m[1], m[2]), dot(m[2], m[0])));
    return min(l.x, min(l.y, l.z)) >= most * (1.0 - 1e-4) && max(off.x, max(off.y, off.z)) <= most * 1e-4;
}

// 0: drawn; else the counter of the test that dropped it.
uint test_cluster(Cluster cl, GpuInstance inst, bool one_sided) {
    CullView view = frame.cull_view;
    mat3 m = transpose(mat3(inst.row0.xyz, inst.row1.xyz, inst.row2.xyz));
    float scale = sqrt(max(dot(m[0], m[0]), max(dot(m[1], m[1]), dot(m[2], m[2]))));
    vec3 c = instance_rel_eye(inst, cl.center, frame.eye_hi.xyz, frame.eye_lo.xyz);
    float radius = cl.radius * scale * (1.0 + 1e-5);
    if (!cull_sphere_in_frustum(view, c, radius)) return STAT_FRUSTUM;
    if (one_sided && cl.cone_cutoff < 1.0 && view.orthographic == 0u && uniform_scale(m)) {
        // The eye is at the origin of eye-relative space.
        vec3 apex = instance_rel_eye(inst, cl.cone_apex, frame.eye_hi.xyz, frame.eye_lo.xyz);
        vec3 axis = normalize(m * cl.cone_axis);
        // A NaN (the eye at the apex) compares false: kept.
        if (dot(normalize(apex), axis) >= cl.cone_cutoff + CONE_MARGIN) return STAT_BACKFACING;
    }
    uvec4 rect;
    float nearest;
    bool covers;
    uint status = cull_project_sphere(view, c, radius, rect, nearest, covers);
    if (status == CULL_ON_SCREEN) {
#ifdef SMALL_OBJECTS
        if (!covers) return STAT_FRUSTUM;
#endif
#ifdef HAS_HIZ
        if (cull_hiz_occluded(rect, nearest, view.viewport, false)) return STAT_OCCLUDED;
#endif
    }
    return 0u;
}

shared uint sh_region_count[REGIONS];
shared uint sh_region_base[REGIONS];

// Reserves `n` commands in region `r` (of both lists, MASKED): the first one's place.
uint reserve(uint r, uint n) {
#ifdef MASKED
    if (r >= CLUSTER_REGIONS) return atomicAdd(masked_cluster_count[r - CLUSTER_REGIONS], n);
#endif
    return atomicAdd(cluster_count[r], n);
}
shared uint sh_stats[8];

void main() {
    uint lane = gl_LocalInvocationID.x % CLUSTER_CHUNK;
    uint slot_in_group = gl_LocalInvocationID.x / CLUSTER_CHUNK;
    uint commands = scratch[SCRATCH_CLUSTERED];
    uint tasks = scratch[SCRATCH_TASKS];
    if (gl_LocalInvocationID.x < 8u) sh_stats[gl_LocalInvocationID.x] = 0u;
    uvec4 counts = uvec4(0u);   // tested, drawn, triangles tested, triangles drawn
    uvec3 dropped = uvec3(0u);  // frustum, back-facing, occluded
    uint rounds = (tasks + TASKS_PER_GROUP - 1u) / TASKS_PER_GROUP;
    for (uint round = gl_WorkGroupID.x; round < rounds; round += gl_NumWorkGroups.x) {
        if (gl_LocalInvocationID.x < REGIONS) sh_region_count[gl_LocalInvocationID.x] = 0u;
        barrier();
        uint task = round * TASKS_PER_GROUP + slot_in_group;
        bool has_task = task < tasks;
        bool drawn = false;
        uint region = 0u;
        uint local_slot = 0u;
        DrawCommand c;
        Cluster cl;
        uint instance = 0u;
        if (has_task) {
            uint k = command_of(task, commands);
            uint at = SCRATCH_HEADER_WORDS + k * 8u;
            uint local = task - scratch[at];
            uint chunks = scratch[at + 1u];
            region = scratch[at + 5u];
            c = in_commands[scratch[at + 4u]];
            instance = local / chunks;
            uint index = (local % chunks) * CLUSTER_CHUNK + lane;
            if (index < scratch[at + 3u]) {
                cl = clusters[scratch[at + 2u] + index];
                GpuInstance inst = instance_record(in_ids[c.first_instance + instance]);
                // The last region of each list draws double-sided materials: both faces, so no
                // cone test.
                uint verdict = test_cluster(cl, inst, region % CLUSTER_REGIONS != 2u);
                drawn = verdict == 0u;
                uint triangles = cl.index_count / 3u;
                counts += uvec4(1u, drawn ? 1u : 0u, triangles, drawn ? triangles : 0u);
                dropped += uvec3(verdict == STAT_FRUSTUM, verdict == STAT_BACKFACING, verdict == STAT_OCCLUDED);
                if (drawn) local_slot = atomicAdd(sh_region_count[region], 1u);
            }
        }
        barrier();
        if (gl_LocalInvocationID.x < REGIONS) {
            uint n = sh_region_count[gl_LocalInvocationID.x];
            sh_region_base[gl_LocalInvocationID.x] = n != 0u ? reserve(gl_LocalInvocationID.x, n) : 0u;
        }
        barrier();
        if (drawn) {
            uint slot = sh_region_base[region] + local_slot;
            // The list holds a command per cluster of every instance; never written past.
            DrawCommand out_c = DrawCommand(cl.index_count, 1u, cl.first_index, c.vertex_offset, c.first_instance + instance);
#ifdef MASKED
            if (region >= CLUSTER_REGIONS) {
                if (slot < pc.masked_region_capacity) {
                    masked_cluster_commands[(region - CLUSTER_REGIONS) * pc.masked_region_capacity + slot] = out_c;
                }
            } else
#endif
            if (slot < pc.region_capacity) {
                cluster_commands[region * pc.region_capacity + slot] = out_c;
            }
        }
    }
    // The counters: summed per subgroup, then per workgroup, then one atomic each.
    counts = subgroupAdd(counts);
    dropped = subgroupAdd(dropped);
    if (subgroupElect() && counts.x != 0u) {
        atomicAdd(sh_stats[0], counts.x);
        atomicAdd(sh_stats[1], counts.y);
        atomicAdd(sh_stats[2], counts.z);
        atomicAdd(sh_stats[3], counts.w);
        atomicAdd(sh_stats[4], dropped.x);
        atomicAdd(sh_stats[5], dropped.y);
        atomicAdd(sh_stats[6], dropped.z);
    }
    barrier();
    if (gl_LocalInvocationID.x == 0u && sh_stats[0] != 0u) {
        atomicAdd(stats[STAT_TESTED], sh_stats[0]);
        atomicAdd(stats[STAT_DRAWN], sh_stats[1]);
        atomicAdd(stats[STAT_TRIANGLES_TESTED], sh_stats[2]);
        atomicAdd(stats[STAT_TRIANGLES_DRAWN], sh_stats[3]);
        atomicAdd(stats[STAT_FRUSTUM], sh_stats[4]);
        atomicAdd(stats[STAT_BACKFACING], sh_stats[5]);
        atomicAdd(stats[STAT_OCCLUDED], sh_stats[6]);
    }
}
