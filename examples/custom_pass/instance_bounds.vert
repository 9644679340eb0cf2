#version 460
// The `instance_bounds` example pass (examples/custom_pass.rs): each instance's world-space box
// as 12 lines, 24 vertices per instance, one instance per cull slot. Green where this frame's
// visibility bits say visible, red where they say culled (white without visibility bits).
#extension GL_GOOGLE_include_directive : require
#include "common/scene.glsl"
#include "cull/cull_common.glsl"

layout(set = 0, binding = 0, scalar) readonly buffer Frame { FrameConstants frame; };
layout(set = 0, binding = 1, scalar) readonly buffer Records { CullRecord records[]; };
#if HAS_VISIBILITY
layout(set = 0, binding = 2) readonly buffer Visibility { uint visible_bits[]; };
#endif

// Which boxes to draw: 0 every one, 1 the visible ones, 2 the culled ones.
layout(push_constant) uniform Push { uint show; } pc;

layout(location = 0) out vec3 out_color;

// The two corners of each of the box's 12 edges, as bits of a corner index (x: 1, y: 2, z: 4).
const uint EDGES[24] = uint[](0, 1, 2, 3, 4, 5, 6, 7, 0, 2, 1, 3, 4, 6, 5, 7, 0, 4, 1, 5, 2, 6, 3, 7);

void main() {
    uint slot = gl_InstanceIndex;
    CullRecord r = records[slot];
    bool visible = true;
#if HAS_VISIBILITY
    visible = ((visible_bits[slot >> 5] >> (slot & 31u)) & 1u) != 0u;
    out_color = visible ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
#else
    out_color = vec3(1.0);
#endif
    bool shown = pc.show == 0u || (pc.show == 1u) == visible;
    vec3 lo = vec3(unpackHalf2x16(r.lo_xy), unpackHalf2x16(r.lo_z_radius).x);
    vec3 half_extent = vec3(unpackHalf2x16(r.half_xy), unpackHalf2x16(r.half_z).x);
    uint corner = EDGES[gl_VertexIndex % 24u];
    vec3 side = vec3(corner & 1u, (corner >> 1) & 1u, (corner >> 2) & 1u) * 2.0 - 1.0;
    vec3 p = rel_eye(r.center_hi, lo, frame.eye_hi.xyz, frame.eye_lo.xyz) + side * half_extent;
    // A box not shown goes outside the clip volume, where the rasterizer drops its lines.
    gl_Position = shown ? frame.view_proj * vec4(p, 1.0) : vec4(2.0, 2.0, 2.0, 1.0);
}
