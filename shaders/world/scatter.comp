#version 460
// A changing world's slot updates (src/render/renderer/world_sync.rs): each thread copies one
// slot's instance record (64 bytes) and cull bound (32 bytes) from the host-visible update
// list into the scene buffers. One dispatch replaces thousands of tiny copy regions, which cost
// the copy engine far more than the bytes they move.
#extension GL_EXT_scalar_block_layout : require

layout(local_size_x = 64) in;

struct SlotUpdate {
    uint slot;
    uint instance[16];   // GpuInstance
    uint record[8];      // GpuCullRecord
};

layout(set = 0, binding = 0, scalar) readonly buffer Updates { SlotUpdate updates[]; };
layout(set = 0, binding = 1) writeonly buffer Instances { uint instance_words[]; };
layout(set = 0, binding = 2) writeonly buffer Records { uint record_words[]; };

layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    uint slot = updates[i].slot;
    for (uint k = 0u; k < 16u; ++k) instance_words[slot * 16u + k] = updates[i].instance[k];
    for (uint k = 0u; k < 8u; ++k) record_words[slot * 8u + k] = updates[i].record[k];
}
