#version 460
// Reverses every pixel's list of pool blocks in place (tests/msaa.rs): the lighting must give
// the same image whatever order a pixel's blocks were pushed in, which is the order fragments
// happened to run.
#include "gbuffer/compressed_gbuffer.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2DMS depth;
layout(set = 0, binding = 1, scalar) buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    BlockPair pairs[];
} gbuffer;

void main() {
    ivec2 size = textureSize(depth);
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, size))) return;
    uint head = uint(p.y * size.x + p.x);
    // links[i] points to the i-th block; at most 7 blocks (one per sample besides the head's).
    uint links[8];
    uint n = 0u;
    uint link = gbuffer.pairs[head >> 1].link[head & 1u];
    while (link_index(link) != LINK_NULL && n < 8u) {
        links[n++] = link;
        uint index = link_index(link);
        link = gbuffer.pairs[index >> 1].link[index & 1u];
    }
    if (n < 2u) return;
    // head -> last, each block -> the one listed before it, the first -> null.
    gbuffer.pairs[head >> 1].link[head & 1u] = links[n - 1u];
    for (uint i = n - 1u; i > 0u; --i) {
        uint index = link_index(links[i]);
        gbuffer.pairs[index >> 1].link[index & 1u] = links[i - 1u];
    }
    uint first = link_index(links[0]);
    gbuffer.pairs[first >> 1].link[first & 1u] = LINK_NULL;
}
