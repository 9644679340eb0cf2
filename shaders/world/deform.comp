#version 460
// Posed instances of a changing world (src/render/renderer/deform.rs): each workgroup row
// deforms one instance's own copy of its mesh from the shared rest mesh, morph targets first
// and then linear blend skinning, as MeshDeform::deform does on the CPU
// (src/scene/deform.rs), and its first thread writes the instance's draw group bounds (a box
// of the pose from the CPU, src/scene/posing.rs), which the scatter after it derives the cull
// record from.
//
// Per source mesh, `deform_data` holds for a skinned mesh 6 words a vertex (joints as two
// 16-bit pairs, then 4 float weights), then per morph target 6 floats a vertex (position and
// normal offsets).
#extension GL_EXT_scalar_block_layout : require
#include "../common/octahedral.glsl"

layout(local_size_x = 64) in;

struct Entry {
    uint src_vertex;
    uint dst_vertex;
    uint vertex_count;
    uint data_offset;    // words into deform_data
    uint params_offset;  // floats into params: joint rows (12 a joint), then morph weights
    uint joint_count;    // 0: not skinned
    uint target_count;   // morph weights given (the rest are 0)
    uint group;
    vec4 center_radius;  // the pose's group bounds
    vec4 half_extent;
};

// A pool vertex's surface stream (src/passes/shared/vertex_streams.rs SurfaceVertex).
struct SurfaceVertex {
    vec2 uv;
    uint tangent_xy;  // snorm16 x2
    uint tangent_zw;  // snorm16 x2 (w: handedness)
};

struct GroupBounds {
    vec4 center_radius;
    vec4 half_extent;
};

layout(set = 0, binding = 0, scalar) readonly buffer Entries { Entry entries[]; };
layout(set = 0, binding = 1, scalar) readonly buffer Params { float params[]; };
layout(set = 0, binding = 2, scalar) readonly buffer DeformData { uint deform_data[]; };
// The pool's streams (positions, octahedral normals as snorm16 x2, surface).
layout(set = 0, binding = 3, scalar) buffer PoolPositions { vec3 positions[]; };
layout(set = 0, binding = 6, scalar) buffer PoolNormals { uint normals[]; };
layout(set = 0, binding = 7, scalar) buffer PoolSurface { SurfaceVertex surface[]; };
layout(set = 0, binding = 4, scalar) writeonly buffer Bounds { GroupBounds group_bounds[]; };
// The positions the previous frame drew (motion vectors): the copy's position before this
// frame's deformation. An entry with group REFRESH only sets them to the current positions (a
// pose that changed last frame but not this one shows no motion).
layout(set = 0, binding = 5, scalar) buffer PrevPositions { vec3 prev_positions[]; };

const uint REFRESH = 0xFFFFFFFFu;

layout(push_constant) uniform Push {
    uint count;
    uint base;   // the entry of this dispatch's first row
    uint still;  // 1: the previous positions are the new ones (a scene uploaded again)
} pc;

mat3x4 joint_rows(uint at) {
    return mat3x4(vec4(params[at], params[at + 1u], params[at + 2u], params[at + 3u]),
                  vec4(params[at + 4u], params[at + 5u], params[at + 6u], params[at + 7u]),
                  vec4(params[at + 8u], params[at + 9u], params[at + 10u], params[at + 11u]));
}

void main() {
    uint e = pc.base + gl_WorkGroupID.y;
    if (e >= pc.count) return;
    Entry entry = entries[e];
    uint i = gl_GlobalInvocationID.x;
    if (i == 0u && entry.group != REFRESH) group_bounds[entry.group] = GroupBounds(entry.center_radius, entry.half_extent);
    if (i >= entry.vertex_count) return;
    prev_positions[entry.dst_vertex + i] = positions[entry.dst_vertex + i];
    if (entry.group == REFRESH) return;

    uint s = entry.src_vertex + i;
    SurfaceVertex src = surface[s];
    vec3 p = positions[s];
    vec3 n = oct_decode(max(unpackSnorm2x16(normals[s]), vec2(-1.0)));
    vec4 t = vec4(unpackSnorm2x16(src.tangent_xy), unpackSnorm2x16(src.tangent_zw));

    uint skin_words = entry.joint_count > 0u ? 6u * entry.vertex_count : 0u;
    uint weights_at = entry.params_offset + 12u * entry.joint_count;
    for (uint k = 0u; k < entry.target_count; ++k) {
        float w = params[weights_at + k];
        if (w == 0.0) continue;
        uint at = entry.data_offset + skin_words + (k * entry.vertex_count + i) * 6u;
        p += w * uintBitsToFloat(uvec3(deform_data[at], deform_data[at + 1u], deform_data[at + 2u]));
        n += w * uintBitsToFloat(uvec3(deform_data[at + 3u], deform_data[at + 4u], deform_data[at + 5u]));
    }
    if (entry.joint_count > 0u) {
        uint at = entry.data_offset + i * 6u;
        uint j01 = deform_data[at], j23 = deform_data[at + 1u];
        uint joints[4] = uint[4](j01 & 0xFFFFu, j01 >> 16, j23 & 0xFFFFu, j23 >> 16);
        mat3x4 m = mat3x4(0.0);
        for (uint k = 0u; k < 4u; ++k) {
            float w = uintBitsToFloat(deform_data[at + 2u + k]);
            if (w > 0.0) m += w * joint_rows(entry.params_offset + 12u * min(joints[k], entry.joint_count - 1u));
        }
        // Rows of the blended 3x4 matrix: position = rows * (p, 1).
        p = vec4(p, 1.0) * m;
        n = vec4(n, 0.0) * m;
        t.xyz = vec4(t.xyz, 0.0) * m;
    }
    n = length(n) > 0.0 ? normalize(n) : vec3(0.0, 1.0, 0.0);
    t.xyz = length(t.xyz) > 0.0 ? normalize(t.xyz) : vec3(1.0, 0.0, 0.0);

    uint d = entry.dst_vertex + i;
    positions[d] = p;
    normals[d] = packSnorm2x16(oct_encode(n));
    surface[d] = SurfaceVertex(src.uv, packSnorm2x16(t.xy), packSnorm2x16(vec2(t.z, t.w < 0.0 ? -1.0 : 1.0)));
    if (pc.still != 0u) prev_positions[entry.dst_vertex + i] = p;
}
