#version 460
// Compressed G-buffer geometry pass (thesis 000 section 4.3): depth EQUAL against the MSAA
// depth, one stencil bit per sample so each sample passes for exactly one fragment, and the
// coverage after those tests (post-depth coverage). Without stencil (SAMPLE_CLAIM) fragments
// claim their samples with an atomic OR instead. The fragment that owns sample 0 writes the
// pixel's head block; every other fragment takes a pool block with an atomic and pushes it on
// the pixel's list. A full pool drops the fragment: its samples fall to the head's weight (to
// a listed block's where the pixel has no head). The head's sample count is not stored: the
// lighting pass derives it as the covered samples (from the depth, or from the claimed
// samples) minus those its list holds.
#extension GL_ARB_post_depth_coverage : require
#ifdef CLAIM_IN_DRAW_ORDER
#extension GL_ARB_fragment_shader_interlock : require
#endif
#include "../common/material_surface.glsl"
#include "../common/octahedral.glsl"
#include "compressed_gbuffer.glsl"

layout(early_fragment_tests) in;
layout(post_depth_coverage) in;
#ifdef CLAIM_IN_DRAW_ORDER
// The claims run in an ordered critical section per sample, so fragments that cover the same
// sample claim it in primitive (draw) order, as the stencil test decides. Only the claim: the
// lighting does not depend on the order of a pixel's list. A sample interlock, not a pixel
// one: fragments that share a pixel but not a sample need not wait for each other, and the list
// push stays outside the critical section, which it would only lengthen (docs/msaa.md).
layout(sample_interlock_ordered) in;
#endif

layout(set = 0, binding = 2, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 4, scalar) buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    BlockPair pairs[];   // the heads
} gb;
layout(set = 0, binding = 6, scalar) buffer GbufferPool { BlockPair pairs[]; } pool;

#ifdef AA_MASK
// Selective AA by depth edges (an aa_edges pass): 0 = this pixel keeps one block.
layout(set = 0, binding = 5) uniform usampler2D aa_mask;
#endif

layout(push_constant) uniform Push {
    uint width;
    uint height;
    uint pool_blocks;        // usable pool blocks (clamped to MAX_POOL_BLOCKS)
    uint aa_region;          // 0 all, 1 ellipse, 2 rectangle
    float aa_region_size;    // fraction of the screen's width and height
    float aa_max_distance;   // 0: no limit
    uint aa_object_flags;    // 1: FLAG_NO_AA instances keep one block
} pc;

#ifdef SAMPLE_CLAIM
// Stencil-free ownership (graph/msaa_compressed_claim.ron): a byte per pixel (claim_word) of
// the samples already claimed (at most 8 samples). A fragment keeps the samples of its
// post-depth coverage that no other fragment claimed before it. Depth EQUAL still settles
// intersecting triangles. Exactly coplanar fragments go to whichever claims first: with
// CLAIM_IN_DRAW_ORDER the first in draw order, as with the stencil; without it whichever
// arrives first, which may change from run to run. Every covered sample belongs to exactly one
// fragment either way.
layout(set = 0, binding = 7) buffer SampleClaim { uint sample_claim[]; };
uint claim_samples(uint pixel, uint mask) {
    uint pixels = pc.width * pc.height;
    uint shift = claim_shift(pixel, pixels);
    uint old = atomicOr(sample_claim[claim_word(pixel, pixels)], mask << shift);
    return mask & ~(old >> shift) & 0xFFu;
}
#else
uint claim_samples(uint pixel, uint mask) { return mask; }   // the stencil already decided
#endif


layout(location = 0) in vec3 in_normal;
layout(location = 1) flat in uint in_material;
layout(location = 2) flat in uint in_mirrored;
layout(location = 5) in vec2 in_uv;
layout(location = 6) in vec4 in_tangent;
layout(location = 3) flat in uint in_flags;

// A head block's attributes (its link belongs to the list).
void write_head(uint pixel, MaterialSurface s) {
    uint pair = pixel >> 1, k = pixel & 1u;
    gb.pairs[pair].albedo_metallic[k] = packUnorm4x8(vec4(s.albedo, s.metallic));
    gb.pairs[pair].normal[k] = packSnorm2x16(oct_encode(s.normal));
    gb.pairs[pair].surface[k] = pack_surface_word(s.roughness, s.occlusion, s.emissive);
}

// A pool block's attributes.
void write_pool_block(uint slot, MaterialSurface s) {
    uint pair = slot >> 1, k = slot & 1u;
    pool.pairs[pair].albedo_metallic[k] = packUnorm4x8(vec4(s.albedo, s.metallic));
    pool.pairs[pair].normal[k] = packSnorm2x16(oct_encode(s.normal));
    pool.pairs[pair].surface[k] = pack_surface_word(s.roughness, s.occlusion, s.emissive);
}

// Selective AA (paper 002 section 5): whether this fragment may take a pool block.
bool may_allocate() {
    vec2 ndc = gl_FragCoord.xy / vec2(pc.width, pc.height) * 2.0 - 1.0;
    vec2 r = ndc / max(pc.aa_region_size, 1e-6);
    if (pc.aa_region == 1u && dot(r, r) > 1.0) return false;
    if (pc.aa_region == 2u && max(abs(r.x), abs(r.y)) > 1.0) return false;
    if (pc.aa_object_flags != 0u && (in_flags & FLAG_NO_AA) != 0u) return false;
#ifdef AA_MASK
    if (texelFetch(aa_mask, ivec2(gl_FragCoord.xy), 0).r == 0u) return false;
#endif
    if (pc.aa_max_distance > 0.0) {
        vec4 p = frame.inv_view_proj * vec4(ndc, gl_FragCoord.z, 1.0);
        if (length(p.xyz / p.w) > pc.aa_max_distance) return false;
    }
    return true;
}

void main() {
    // Derivatives while every invocation of the quad is still running.
    vec2 duv_dx = dFdx(in_uv), duv_dy = dFdy(in_uv);
    uint mask = uint(gl_SampleMaskIn[0]);
    uint pixel = uint(gl_FragCoord.y) * pc.width + uint(gl_FragCoord.x);
#ifdef CLAIM_IN_DRAW_ORDER
    // (The interlock calls may not sit in flow control nor after a return.)
    beginInvocationInterlockARB();
    if (mask != 0u) mask = claim_samples(pixel, mask);
    endInvocationInterlockARB();
#else
    if (mask != 0u) mask = claim_samples(pixel, mask);
#endif
    if (mask == 0u) return;
    bool head = (mask & 1u) != 0u;
    // Capped to one surface: the head takes these samples (the lighting gives the head every
    // covered sample that no listed block has).
    if (!head && !may_allocate()) return;
    GpuMaterial m = materials[in_material];
    vec3 n = normalize(in_normal);
    // Seen from behind (open meshes): light the side that faces the eye. A mirrored instance
    // flips the winding, so its outside shows as a back face.
    bool front = gl_FrontFacing != (in_mirrored != 0u);
    if (!front) n = -n;
    // The textured surface. (No alpha test here: the depth EQUAL test against a depth that has
    // the masked holes already rejects their fragments.)
    MaterialSurface s = material_surface(m, in_uv, duv_dx, duv_dy, n, in_tangent, front);
    if (head) {
        write_head(pixel, s);
        return;
    }
    // The list's order is whichever order the fragments run in; the lighting does not depend on it.
    uint slot = atomicAdd(gb.header[GBUFFER_HEADER_ALLOCATED], 1u);
    if (slot >= pc.pool_blocks) {
        atomicAdd(gb.header[GBUFFER_HEADER_OVERFLOW_FRAGMENTS], 1u);
        atomicAdd(gb.header[GBUFFER_HEADER_OVERFLOW_SAMPLES], uint(bitCount(mask)));
        return;   // these samples fall to the head (or a listed block), as above
    }
    write_pool_block(slot, s);
    uint link = make_link(slot, uint(bitCount(mask)), uint(findLSB(mask)));
    uint head_link = atomicExchange(gb.pairs[pixel >> 1].link[pixel & 1u], link);
    pool.pairs[slot >> 1].link[slot & 1u] = head_link;
}
