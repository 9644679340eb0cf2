// Checks each pixel's compressed G-buffer list against the MSAA depth. Writes, per pixel:
// r = error bits (0: fine), g = listed blocks, b = covered samples, a = sum of listed counts.
//   1: a link points outside the pool
//   2: a block's sample count is 0 or more than the samples left
//   4: a block's sample index is 0 (the head's), uncovered, or another block's
//   8: the listed blocks cover more samples than the pixel's covered ones not owned by the head
//  16: a pixel without a surface at sample 0 (no head) has covered samples no block lists
//  32: the list is longer than the samples allow
//  64: (SAMPLE_CLAIM) the claimed samples are not the covered samples, from which the lighting
//      gives the head every covered sample its list does not hold
// 128: against an independent oracle, the triangle each sample shows (`ids`, drawn by a
//      visibility-buffer pass of the same lists): the listed blocks of some triangle other than
//      the head's do not add up to that triangle's samples, or the head's triangle's blocks
//      leave the head none (a fragment was lost; a full pool or a selective-AA cap drops
//      fragments on purpose, so there this bit is expected). A triangle may own several blocks:
//      lavapipe may run more than one fragment invocation for one triangle in one pixel, each
//      with part of its coverage.
// Included by compressed_check.comp (stencil) and compressed_check_claim.comp (sample claims).
#include "gbuffer/compressed_gbuffer.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2DMS depth;
layout(set = 0, binding = 1, scalar) readonly buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    BlockPair pairs[];
} gbuffer;
layout(set = 0, binding = 5, scalar) readonly buffer GbufferPool { BlockPair pairs[]; } gbuffer_pool;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D check;
#ifdef SAMPLE_CLAIM
layout(set = 0, binding = 3) readonly buffer SampleClaim { uint words[]; } sample_claim;
#endif
layout(set = 0, binding = 4) uniform usampler2DMS ids;

// The covered samples of pixel `p` that show the same triangle as sample `s`.
uint same_triangle(ivec2 p, uint s, uint covered, uint samples) {
    uvec2 id = texelFetch(ids, p, int(s)).xy;
    uint mask = 0u;
    for (uint t = 0u; t < samples; ++t) {
        if ((covered & (1u << t)) != 0u && texelFetch(ids, p, int(t)).xy == id) mask |= 1u << t;
    }
    return mask;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(check);
    if (any(greaterThanEqual(p, size))) return;
    uint samples = uint(textureSamples(depth));
    uint covered = 0u;
    for (uint s = 0u; s < samples; ++s) {
        if (texelFetch(depth, p, int(s)).r > 0.0) covered |= 1u << s;
    }
    uint pixels = uint(size.x * size.y);
    uint pool_blocks = uint(gbuffer_pool.pairs.length()) * 2u;
    uint head = uint(p.y * size.x + p.x);
    uint link = gbuffer.pairs[head >> 1].link[head & 1u];
    uint errors = 0u, listed = 0u, sum = 0u, used = 0u;
    // The oracle's view: listed samples per triangle, kept at the triangle's lowest sample.
    uint per_triangle[8] = uint[8](0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);
    while (link_index(link) != LINK_NULL && listed <= samples) {
        uint slot = link_slot(link), count = link_count(link), sample_index = link_sample(link);
        if (slot >= pool_blocks) { errors |= 1u; break; }
        if (count == 0u || count >= samples) errors |= 2u;
        uint bit = 1u << sample_index;
        if (sample_index == 0u || sample_index >= samples || (covered & bit) == 0u || (used & bit) != 0u) errors |= 4u;
        if (sample_index < samples && (covered & bit) != 0u) {
            per_triangle[findLSB(same_triangle(p, sample_index, covered, samples))] += count;
        }
        used |= bit;
        sum += count;
        listed += 1u;
        link = gbuffer_pool.pairs[slot >> 1].link[slot & 1u];
    }
    uint head_owned = (covered & 1u) != 0u ? 1u : 0u;
    for (uint s = 0u; s < samples; ++s) {
        uint triangle = (covered & (1u << s)) != 0u ? same_triangle(p, s, covered, samples) : 0u;
        if (triangle == 0u || findLSB(triangle) != int(s)) continue;
        // The head's triangle keeps at least sample 0 for the head; every other triangle is
        // listed whole.
        bool heads = head_owned != 0u && s == 0u;
        uint want = uint(bitCount(triangle));
        if (heads ? per_triangle[s] >= want : per_triangle[s] != want) errors |= 128u;
    }
    if (sum + head_owned > uint(bitCount(covered))) errors |= 8u;
    if (head_owned == 0u && sum != uint(bitCount(covered))) errors |= 16u;
    if (listed >= samples) errors |= 32u;
#ifdef SAMPLE_CLAIM
    // The lighting takes the covered samples from the claims (the background is the rest).
    uint claimed = (sample_claim.words[claim_word(head, pixels)] >> claim_shift(head, pixels)) & 0xFFu;
    if (claimed != covered) errors |= 64u;
#endif
    imageStore(check, p, vec4(float(errors), float(listed), float(bitCount(covered)), float(sum)) / 255.0);
}
