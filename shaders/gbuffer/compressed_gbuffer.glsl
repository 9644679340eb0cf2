// The compressed G-buffer (thesis 000 section 5, paper 002): a storage buffer holding a header
// and one 14-byte head block per pixel (`gbuffer`), and a second one holding the pool of blocks
// for the other distinct surfaces of edge pixels (`gbuffer_pool`), linked per pixel. Two
// buffers rather than one keep each binding within maxStorageBufferRange at 4K on devices that
// address 128 MiB per binding. Layout mirrors src/passes/gbuffer_compressed.rs.
#ifndef CULLGRAPH_COMPRESSED_GBUFFER_GLSL
#define CULLGRAPH_COMPRESSED_GBUFFER_GLSL

#extension GL_EXT_scalar_block_layout : require

#include "../common/emissive_occlusion.glsl"

// Two 16-byte blocks interleaved in 32 bytes (thesis Fig. 5.3), so every field stays aligned
// and a pair fills one 32-byte memory sector: albedo+metallic (RGBA8) x2, normal (two 16-bit
// octahedral coordinates) x2, surface word (roughness, occlusion, emissive:
// ../common/emissive_occlusion.glsl) x2, link x2. Each block's fields are whole words of its
// own, so the two blocks of a pair, written by different fragments at once, never share one.
struct BlockPair {
    uint albedo_metallic[2];
    uint normal[2];
    uint surface[2];
    uint link[2];
};

// The same 32 bytes as 8 words, for the clear pass.
#define PAIR_WORDS 8u

// Header counters, then the blocks.
#define GBUFFER_HEADER_WORDS 4u
#define GBUFFER_HEADER_ALLOCATED 0u           // pool blocks asked for this frame (may exceed the pool)
#define GBUFFER_HEADER_OVERFLOW_FRAGMENTS 1u  // fragments dropped because the pool was full
#define GBUFFER_HEADER_OVERFLOW_SAMPLES 2u    // samples they covered (the head took their weight)

// Link word: 26-bit pool block index plus one | 3-bit sample count | 3-bit sample index, the
// last two of the block pointed to. Links only ever point into the pool, so index 0 is free to
// be the null link.
#define LINK_INDEX_BITS 26u
#define LINK_INDEX_MASK 0x3FFFFFFu
#define LINK_NULL 0u
#define MAX_POOL_BLOCKS 0x3FFFFFFu

uint link_index(uint link) { return link & LINK_INDEX_MASK; }
// The pool block a non-null link points at.
uint link_slot(uint link) { return (link & LINK_INDEX_MASK) - 1u; }
uint link_count(uint link) { return (link >> 26) & 7u; }
uint link_sample(uint link) { return link >> 29; }
uint make_link(uint slot, uint count, uint sample_index) { return (slot + 1u) | (count << 26) | (sample_index << 29); }

// The `sample_claim` buffer (no stencil): a byte per pixel of the samples claimed. Pixel p's
// byte is byte p / W of word p % W, W = ceil(pixels / 4), so that neighbouring pixels, drawn
// together, claim in different words rather than queueing atomics on a shared one.
uint claim_words(uint pixels) { return (pixels + 3u) / 4u; }
uint claim_word(uint pixel, uint pixels) { return pixel % claim_words(pixels); }
uint claim_shift(uint pixel, uint pixels) { return (pixel / claim_words(pixels)) * 8u; }

struct Block {
    vec3 albedo;
    float metallic;
    vec3 normal;
    float roughness;
    float occlusion;
    vec3 emissive;
};

#endif
