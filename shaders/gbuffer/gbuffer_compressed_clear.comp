#version 460
// Start of the compressed G-buffer pass: zero the header counters, every head's link (an
// empty list) and, without stencil, the claimed samples, and put every head's AO in place
// (BLOCK_AO; its fragment then stores only albedo, normal and roughness). The other head
// attributes need no clearing: a head whose pixel has no surface at sample 0 is never read
// (the lighting pass sees the background in the depth).
#include "compressed_gbuffer.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    BlockPairWords pairs[];
} gb;

#ifdef SAMPLE_CLAIM
layout(set = 0, binding = 2) buffer SampleClaim { uint sample_claim[]; };
#endif

layout(push_constant) uniform Push {
    uint head_pairs;
    uint claim_words;   // ceil(pixels / 4): one byte per pixel
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < GBUFFER_HEADER_WORDS) gb.header[i] = 0u;
    if (i < pc.head_pairs) {
        gb.pairs[i].roughness_ao = HEAD_ROUGHNESS_AO_CLEARED;
        gb.pairs[i].link[0] = LINK_NULL;
        gb.pairs[i].link[1] = LINK_NULL;
    }
#ifdef SAMPLE_CLAIM
    if (i < pc.claim_words) sample_claim[i] = 0u;
#endif
}
