#version 460
// Overlay, view "culled", step 2: one thread per row turns the row's differences into coverage
// counts (an in-place prefix sum).
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) buffer Coverage { uint header[4]; int coverage[]; };

layout(push_constant) uniform Push {
    uint width;
    uint height;
} pc;

void main() {
    uint y = gl_GlobalInvocationID.x;
    if (y >= pc.height) return;
    uint base = y * (pc.width + 1u);
    int sum = 0;
    for (uint x = 0u; x < pc.width; ++x) {
        sum += coverage[base + x];
        coverage[base + x] = sum;
    }
}
