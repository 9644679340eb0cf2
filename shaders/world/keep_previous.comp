#version 460
// Motion vectors of a changing world (src/render/renderer/world_sync.rs): before this frame's
// scatter replaces records, each listed slot's record becomes its previous one. The list holds
// the slots the last frame updated (their previous records are older than last frame's) and
// those this frame updates; every other slot's previous record already equals its record.
#extension GL_EXT_scalar_block_layout : require
#extension GL_GOOGLE_include_directive : require
#include "../common/line_dispatch.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Slots { uint slots[]; };
// 64-byte instance records as four 16-byte words.
#define INSTANCE_WORDS_BINDING 1
#define PREV_INSTANCE_WORDS_BINDING 2
#include "../common/scene.glsl"
#include "../common/instance_ranges.glsl"

layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = line_invocation();
    if (i >= pc.count) return;
    uint slot = slots[i];
    for (uint k = 0u; k < 4u; ++k) set_prev_instance_word(slot, k, instance_word(slot, k));
}
