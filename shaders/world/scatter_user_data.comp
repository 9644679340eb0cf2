#version 460
// A changing world's user data updates (src/render/renderer/world_sync.rs): each thread writes
// one slot's words. An entry is the slot, then its WORDS words; the list holds each slot once,
// so no two threads write the same words.
#extension GL_GOOGLE_include_directive : require
#include "../common/line_dispatch.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Updates { uint updates[]; };
layout(std430, binding = 1) writeonly buffer UserData { uint user_data[]; };

layout(push_constant) uniform Push {
    uint count;
    uint words;
};

void main() {
    uint i = line_invocation();
    if (i >= count) {
        return;
    }
    uint entry = i * (words + 1);
    uint slot = updates[entry];
    for (uint k = 0; k < words; ++k) {
        user_data[slot * words + k] = updates[entry + 1 + k];
    }
}
