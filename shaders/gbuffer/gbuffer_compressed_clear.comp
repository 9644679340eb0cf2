#version 460
// Start of the compressed G-buffer pass: zero the header counters, every head's link (an
// empty list) and, without stencil, the claimed samples. The other head attributes need no
// clearing (a head whose pixel has no surface at sample 0 is never read: the lighting pass sees
// the background in the depth), but the pairs are written whole, all eight words, so that a
// warp's stores fill whole 32-byte sectors: writing only the links would leave every sector
// partly written, and partly written sectors cost more than the extra bytes of whole pairs
// (docs/msaa.md).
#include "compressed_gbuffer.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    uint words[];   // PAIR_WORDS per pair
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
    // Word j * head_pairs + i in store j: consecutive threads, consecutive words.
    if (i < pc.head_pairs) {
        for (uint j = 0u; j < PAIR_WORDS; ++j) {
            uint word = j * pc.head_pairs + i;
            // Zero is the null link and a harmless attribute.
            gb.words[word] = LINK_NULL;
        }
    }
#ifdef SAMPLE_CLAIM
    if (i < pc.claim_words) sample_claim[i] = 0u;
#endif
}
