#version 460
// Reverses every pixel's list of pool blocks in place (tests/msaa.rs): the lighting must give
// the same image whatever order a pixel's blocks were pushed in, which is the order fragments
// happened to run. Marks, per pixel, what the test needs to see happen: r = 1/255 where a list
// of two or more blocks was reversed; g = 1/255 where, in addition, the pixel has no head and
// its head samples (covered samples no block lists: dropped fragments') go to one of the blocks.
#include "gbuffer/compressed_gbuffer.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2DMS depth;
layout(set = 0, binding = 1, scalar) buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    BlockPair pairs[];
} gbuffer;
layout(set = 0, binding = 3, scalar) buffer GbufferPool { BlockPair pairs[]; } gbuffer_pool;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D marks;

void main() {
    ivec2 size = textureSize(depth);
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, size))) return;
    uint head = uint(p.y * size.x + p.x);
    // links[i] points to the i-th block; at most 7 blocks (one per sample besides the head's).
    uint links[8];
    uint n = 0u, listed = 0u;
    uint link = gbuffer.pairs[head >> 1].link[head & 1u];
    while (link_index(link) != LINK_NULL && n < 8u) {
        listed += link_count(link);
        links[n++] = link;
        uint slot = link_slot(link);
        link = gbuffer_pool.pairs[slot >> 1].link[slot & 1u];
    }
    uint covered = 0u;
    for (int s = 0; s < textureSamples(depth); ++s) covered += texelFetch(depth, p, s).r > 0.0 ? 1u : 0u;
    bool headless_with_dropped = texelFetch(depth, p, 0).r <= 0.0 && covered > listed;
    imageStore(marks, p, vec4(n >= 2u ? 1.0 : 0.0, n >= 2u && headless_with_dropped ? 1.0 : 0.0, 0.0, 0.0) / 255.0);
    if (n < 2u) return;
    // head -> last, each block -> the one listed before it, the first -> null.
    gbuffer.pairs[head >> 1].link[head & 1u] = links[n - 1u];
    for (uint i = n - 1u; i > 0u; --i) {
        uint slot = link_slot(links[i]);
        gbuffer_pool.pairs[slot >> 1].link[slot & 1u] = links[i - 1u];
    }
    uint first = link_slot(links[0]);
    gbuffer_pool.pairs[first >> 1].link[first & 1u] = LINK_NULL;
}
