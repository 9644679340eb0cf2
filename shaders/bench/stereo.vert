#version 460
// Two VR eyes drawn from one instance list (src/bench/multiview/stereo.rs): in a multiview pass
// (MULTIVIEW, view mask 0b11) gl_ViewIndex picks the eye's matrix, drawing the list into both
// layers at once; otherwise one pass per eye pushes its eye. The position is computed as
// gbuffer.vert computes it (eye-relative, invariant), so both ways rasterize identically.
#ifdef MULTIVIEW
#extension GL_EXT_multiview : require
#endif
#include "../common/scene.glsl"
#include "../common/octahedral.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_normal_oct;

struct Eye {
    mat4 view_proj;   // eye-relative world -> clip
    vec4 eye_hi;      // xyz
    vec4 eye_lo;      // xyz
};

#define INSTANCES_BINDING 0
#include "../common/instance_ranges.glsl"
layout(set = 0, binding = 1, scalar) readonly buffer DrawList { uint draw_instance_ids[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Eyes { Eye eyes[2]; };

layout(push_constant) uniform Push { uint eye; } pc;  // the eye of a single-eye pass (0 with MULTIVIEW)

invariant gl_Position;

layout(location = 0) out vec3 out_normal;

void main() {
#ifdef MULTIVIEW
    uint e = pc.eye + uint(gl_ViewIndex);
#else
    uint e = pc.eye;
#endif
    uint id = draw_instance_ids[gl_InstanceIndex];
    GpuInstance inst = instance_record(id);
    vec3 rel = instance_rel_eye(inst, in_position, eyes[e].eye_hi.xyz, eyes[e].eye_lo.xyz);
    gl_Position = eyes[e].view_proj * vec4(rel, 1.0);
    out_normal = instance_normal(inst, oct_decode(in_normal_oct));
}
