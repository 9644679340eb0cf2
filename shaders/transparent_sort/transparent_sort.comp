#version 460
// Transparent (alphaMode BLEND) instances in back-to-front order, as draw commands of one
// instance each for the `transparent` pass. The blended region of the culled list, or of two
// lists that together hold this frame's visible instances (the instances the culling kept), is
// gathered with each instance's distance from the eye (its origin, as Bevy and Granite sort),
// sorted by one workgroup (a bitonic sort over the next power of two, in the scratch buffer),
// and written out. Keys are (distance, gather position), so equal distances keep the list's
// slot order and the order never depends on timing.
#extension GL_EXT_scalar_block_layout : require
#include "../common/scene.glsl"
#include "../cull/cull_common.glsl"

#define THREADS 256u
layout(local_size_x = THREADS) in;

layout(set = 0, binding = 0, scalar) uniform Frame { FrameConstants frame; };
#define INSTANCES_BINDING 1
#include "../common/instance_ranges.glsl"
layout(set = 0, binding = 2, scalar) readonly buffer ListCommands { DrawCommand list_commands[]; };
layout(set = 0, binding = 3, scalar) readonly buffer ListCount { uint list_count[]; };
layout(set = 0, binding = 4, scalar) readonly buffer ListIds { uint list_ids[]; };
// A second list (`second_list_*`), or the first again when `lists` is 1.
layout(set = 0, binding = 9, scalar) readonly buffer SecondCommands { DrawCommand second_commands[]; };
layout(set = 0, binding = 10, scalar) readonly buffer SecondCount { uint second_count[]; };
layout(set = 0, binding = 11, scalar) readonly buffer SecondIds { uint second_ids[]; };
// pairs[0, keys): sort keys (distance key, entry); pairs[keys, keys + capacity): the entries
// (instance, the command's place in its list's region, plus `region_commands` for the second list).
layout(set = 0, binding = 5, scalar) coherent buffer Scratch { uvec2 pairs[]; };
layout(set = 0, binding = 6, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 7, scalar) writeonly buffer Count { uint count; };
layout(set = 0, binding = 8, scalar) writeonly buffer Ids { uint ids[]; };

layout(push_constant) uniform Push {
    uint first_command;   // the blended region's first command in the list
    uint region_commands; // commands the region may hold
    uint capacity;        // instances the output and scratch buffers hold
    uint keys;            // sort keys the scratch holds: a power of two >= capacity
    uint count_index;     // the region's count in list_count
    uint lists;           // 1 or 2
} pc;

const uvec2 PAD = uvec2(0xFFFFFFFFu);

// Command `index` of list 0 or 1 (field by field: the two buffers' structs are distinct types).
DrawCommand load_command(uint list, uint index) {
    DrawCommand dc;
    if (list == 0u) {
        dc.index_count = list_commands[index].index_count;
        dc.instance_count = list_commands[index].instance_count;
        dc.first_index = list_commands[index].first_index;
        dc.vertex_offset = list_commands[index].vertex_offset;
        dc.first_instance = list_commands[index].first_instance;
    } else {
        dc.index_count = second_commands[index].index_count;
        dc.instance_count = second_commands[index].instance_count;
        dc.first_index = second_commands[index].first_index;
        dc.vertex_offset = second_commands[index].vertex_offset;
        dc.first_instance = second_commands[index].first_instance;
    }
    return dc;
}

bool key_less(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

void sync() {
    memoryBarrierBuffer();
    barrier();
}

void main() {
    uint tid = gl_LocalInvocationID.x;
    // Gather. The loops over commands are uniform: every thread sees the same counts.
    uint n = 0u;
    for (uint list = 0u; list < pc.lists; ++list) {
        uint region_count = list == 0u ? list_count[pc.count_index] : second_count[pc.count_index];
        uint commands_in_region = min(region_count, pc.region_commands);
        for (uint c = 0u; c < commands_in_region && n < pc.capacity; ++c) {
            uint command = pc.first_command + c;
            DrawCommand dc = load_command(list, command);
            uint take = min(dc.instance_count, pc.capacity - n);
            for (uint i = tid; i < take; i += THREADS) {
                uint at = dc.first_instance + i;
                uint id = list == 0u ? list_ids[at] : second_ids[at];
                vec3 rel = instance_rel_eye(instance_record(id), vec3(0.0), frame.eye_hi.xyz, frame.eye_lo.xyz);
                // Farthest first: the complement of a non-negative float's bits sorts descending.
                pairs[n + i] = uvec2(~floatBitsToUint(dot(rel, rel)), n + i);
                pairs[pc.keys + n + i] = uvec2(id, c + list * pc.region_commands);
            }
            n += take;
        }
    }
    uint m = 1u;
    while (m < n) m <<= 1u;
    for (uint i = n + tid; i < m; i += THREADS) pairs[i] = PAD;
    sync();
    // Bitonic sort of pairs[0, m).
    for (uint k = 2u; k <= m; k <<= 1u) {
        for (uint j = k >> 1u; j > 0u; j >>= 1u) {
            for (uint i = tid; i < m; i += THREADS) {
                uint l = i ^ j;
                if (l <= i) continue;
                uvec2 a = pairs[i], b = pairs[l];
                bool ascending = (i & k) == 0u;
                if (key_less(b, a) == ascending) {
                    pairs[i] = b;
                    pairs[l] = a;
                }
            }
            sync();
        }
    }
    // One command of one instance per entry, in sorted order.
    for (uint i = tid; i < n; i += THREADS) {
        uvec2 entry = pairs[pc.keys + pairs[i].y];
        uint list = entry.y < pc.region_commands ? 0u : 1u;
        DrawCommand dc = load_command(list, pc.first_command + entry.y - list * pc.region_commands);
        commands[i].index_count = dc.index_count;
        commands[i].instance_count = 1u;
        commands[i].first_index = dc.first_index;
        commands[i].vertex_offset = dc.vertex_offset;
        commands[i].first_instance = i;
        ids[i] = entry.x;
    }
    if (tid == 0u) count = n;
}
