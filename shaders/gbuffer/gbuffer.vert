#version 460
// G-buffer geometry pass, vertex stage: instances come from the draw group's slice of the
// compacted instance list (gl_InstanceIndex includes firstInstance).
#include "../common/scene.glsl"
#include "../common/octahedral.glsl"

// The pool's streams (src/passes/shared/vertex_streams.rs): a pass fetches only what it reads.
// NO_NORMALS (depth-only passes) and NO_SURFACE (no texture is sampled) leave a stream out; the
// outputs it would feed get constants that nothing downstream reads.
layout(location = 0) in vec3 in_position;
#ifndef NO_NORMALS
layout(location = 1) in vec2 in_normal_oct;
#endif
#ifndef NO_SURFACE
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
#endif

#define INSTANCES_BINDING 0
layout(set = 0, binding = 1, scalar) readonly buffer DrawList { uint draw_instance_ids[]; };
layout(set = 0, binding = 2, scalar) uniform Frame { FrameConstants frame; };

invariant gl_Position;  // the oracle (shaders/oracle/id.vert) and later passes must rasterize identically

layout(location = 0) out vec3 out_normal;
layout(location = 1) flat out uint out_material;
layout(location = 2) flat out uint out_mirrored;
layout(location = 3) flat out uint out_flags;      // FLAG_* of the instance (selective AA reads FLAG_NO_AA)
layout(location = 4) flat out uint out_instance;   // instance id (the visibility buffer stores it)
layout(location = 5) out vec2 out_uv;
layout(location = 6) out vec4 out_tangent;         // world tangent, w: bitangent sign

#ifdef MOTION
// Motion vectors: the instance's record of the world's previous frame.
#define PREV_INSTANCES_BINDING 8
// Each pool vertex's position last frame (a posed instance's copy moves with its pose).
layout(set = 0, binding = 9, scalar) readonly buffer PrevPositions { vec3 prev_positions[]; };
// Unjittered clip positions now and last frame: the fragment divides each by its w (the
// difference of projected points is not linear across a triangle; clip positions are).
layout(location = 7) out vec4 out_clip;
layout(location = 8) out vec4 out_prev_clip;
#endif
#include "../common/instance_ranges.glsl"

void main() {
    uint id = draw_instance_ids[gl_InstanceIndex];
    GpuInstance inst = instance_record(id);
    out_instance = id;
    vec3 rel = instance_rel_eye(inst, in_position, frame.eye_hi.xyz, frame.eye_lo.xyz);
    gl_Position = frame.view_proj * vec4(rel, 1.0);
#ifdef MOTION
    // Last frame's position relative to last frame's eye, through last frame's unjittered
    // matrix: neither frame's jitter shows as motion.
    vec3 prev_rel = instance_rel_eye(prev_instance_record(id), prev_positions[gl_VertexIndex], frame.prev_eye_hi.xyz,
                                     frame.prev_eye_lo.xyz);
    out_clip = frame.view_proj_unjittered * vec4(rel, 1.0);
    out_prev_clip = frame.prev_view_proj_unjittered * vec4(prev_rel, 1.0);
#endif
#ifdef NO_NORMALS
    out_normal = vec3(0.0, 0.0, 1.0);
#else
    out_normal = instance_normal(inst, oct_decode(in_normal_oct));
#endif
    out_material = instance_material(inst);
    bool mirrored = instance_is_mirrored(inst);
    out_mirrored = mirrored ? 1u : 0u;
    out_flags = instance_flags(inst);
#ifdef NO_SURFACE
    out_uv = vec2(0.0);
    out_tangent = vec4(1.0, 0.0, 0.0, 1.0);
#else
    out_uv = in_uv;
    mat3 m = transpose(mat3(inst.row0.xyz, inst.row1.xyz, inst.row2.xyz));
    // A mirrored instance flips the bitangent along with the winding.
    out_tangent = vec4(m * in_tangent.xyz, (in_tangent.w < 0.0) != mirrored ? -1.0 : 1.0);
#endif
}
