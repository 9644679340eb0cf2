#version 460
// Motion vectors of a changing world (src/render/renderer/world_sync.rs): before this frame's
// scatter replaces records, each listed slot's record becomes its previous one. The list holds
// the slots the last frame updated (their previous records are older than last frame's) and
// those this frame updates; every other slot's previous record already equals its record.
#extension GL_EXT_scalar_block_layout : require

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Slots { uint slots[]; };
// 64-byte instance records as four 16-byte words.
layout(set = 0, binding = 1) readonly buffer Instances { uvec4 instance_vec[]; };
layout(set = 0, binding = 2) writeonly buffer Previous { uvec4 previous_vec[]; };

layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    uint base = slots[i] * 4u;
    for (uint k = 0u; k < 4u; ++k) previous_vec[base + k] = instance_vec[base + k];
}
