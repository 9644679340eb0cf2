#version 460
// Exact-visibility oracle: draws every instance (no culling) exactly as the G-buffer pass
// positions it, writing the instance id. Same transform code, so the same rasterization.
#include "../common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 2) in vec2 in_uv;

#define INSTANCES_BINDING 0
#include "../common/instance_ranges.glsl"
layout(set = 0, binding = 1, scalar) readonly buffer DrawList { uint draw_instance_ids[]; };
layout(set = 0, binding = 2, scalar) uniform Frame { FrameConstants frame; };

invariant gl_Position;  // identical to shaders/gbuffer/gbuffer.vert

layout(location = 0) flat out uint out_instance;
layout(location = 1) flat out uint out_material;
layout(location = 2) out vec2 out_uv;

void main() {
    uint id = draw_instance_ids[gl_InstanceIndex];
    GpuInstance inst = instance_record(id);
    vec3 rel = instance_rel_eye(inst, in_position, frame.eye_hi.xyz, frame.eye_lo.xyz);
    gl_Position = frame.view_proj * vec4(rel, 1.0);
    out_instance = id;
    out_material = instance_material(inst);
    out_uv = in_uv;
}
