#version 460
// Atomic-append variant, step 1: one thread per draw group writes the group's command with no
// instances yet (the test step bumps instanceCount atomically), and thread 0 resets the
// counters and sets each face-cull region's draw count to all its groups (empty ones are no-op
// draws).
#extension GL_GOOGLE_include_directive : require
#include "cull_common.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 1, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 2) writeonly buffer DrawCount { uint draw_count[FACE_CULL_REGIONS]; };
layout(set = 0, binding = 3, scalar) writeonly buffer Stats { CullStats stats; };

layout(push_constant) uniform Push {
    uint group_count;
    uint region_first[FACE_CULL_REGIONS];  // first group of each face cull's region
} pc;

void main() {
    uint g = gl_GlobalInvocationID.x;
    if (g == 0u) {
        for (uint r = 0u; r < FACE_CULL_REGIONS; ++r) {
            uint end = r + 1u < FACE_CULL_REGIONS ? pc.region_first[r + 1u] : pc.group_count;
            draw_count[r] = end - pc.region_first[r];
        }
        CullStats s;
        s.tested = 0u;
        s.frustum_culled = 0u;
        s.occlusion_culled = 0u;
        s.drawn = 0u;
        s.draws = pc.group_count;
        s.triangles_lo = 0u;
        s.triangles_hi = 0u;
        s.survivors = 0u;
        for (uint i = 0u; i < 8u; ++i) s.level_instances[i] = 0u;
        stats = s;
    }
    if (g >= pc.group_count) return;
    DrawGroup group = groups[g];
    DrawCommand cmd;
    cmd.index_count = group.index_count;
    cmd.instance_count = 0u;
    cmd.first_index = group.first_index;
    cmd.vertex_offset = group.vertex_offset;
    cmd.first_instance = group.first_slot;
    commands[g] = cmd;
}
