#version 460
// Lighting over the compressed G-buffer (thesis 000 section 4.3, resolve): per pixel, every
// block of its list is shaded once with the tile's lights, tone-mapped, and weighted by the
// samples it covers; the background samples (depth 0) are sky; the head takes the rest (its own
// samples and any a full pool or an AA cap dropped; where the pixel has no head, the listed
// block with the lowest sample does). The weighted mean of the tone-mapped colours is stored as
// the linear HDR colour the tonemap pass shows as that mean (tonemap.glsl).
//
// A workgroup is a 16x16 tile. Its pixels' pool blocks are gathered into one shared list and
// shaded by all 256 invocations together, so that an edge pixel's extra blocks do not make its
// whole subgroup wait on a loop (the divergence the thesis notes in its resolve loop); every
// block is still shaded exactly once.
//
// A pixel's list is in the order its fragments happened to run, which no GPU fixes, so nothing
// here depends on it: the weighted colors are summed in fixed point (exact, so in any order),
// and samples the head would take where there is no head go to the block holding the lowest
// sample, not to the first listed.
#include "../common/scene.glsl"
#include "../common/shading.glsl"
#include "../common/octahedral.glsl"
#include "../gbuffer/compressed_gbuffer.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

#ifndef SAMPLES
#define SAMPLES 1   // samples per pixel of the depth (and G-buffer) images
#endif
#if SAMPLES > 1
layout(set = 0, binding = 0) uniform sampler2DMS depth_tex;
#define DEPTH_AT(p, s) texelFetch(depth_tex, p, int(s)).r
#else
layout(set = 0, binding = 0) uniform sampler2D depth_tex;
#define DEPTH_AT(p, s) texelFetch(depth_tex, p, 0).r
#endif
layout(set = 0, binding = 1, scalar) readonly buffer Gbuffer {
    uint header[GBUFFER_HEADER_WORDS];
    BlockPair pairs[];   // the heads
} gb;
layout(set = 0, binding = 7, scalar) readonly buffer GbufferPool { BlockPair pairs[]; } pool;
layout(set = 0, binding = 2, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 3, scalar) readonly buffer Lights { GpuPointLight lights[]; };
// HDR_OUTPUT: linear HDR colour for a tonemap pass; without, the tone-mapped image itself.
#ifdef HDR_OUTPUT
layout(set = 0, binding = 4, rgba16f) uniform writeonly image2D out_color;
#else
layout(set = 0, binding = 4, rgba8) uniform writeonly image2D out_color;
#endif
#ifdef WRITE_STATS
// Pool counters and blocks per pixel (GbufferCounters in src/stats/gbuffer.rs).
layout(set = 0, binding = 5) buffer Stats {
    uint allocated;
    uint overflow_fragments;
    uint overflow_samples;
    uint pool_blocks;
    uint pixels;
    uint pad[3];
    uint histogram[8];       // pixels with 2..8 distinct surfaces (sky counts as one); [0] is
                             // left to the CPU (pixels minus the rest): counting only edge
                             // pixels keeps the statistics nearly free
} stats;
shared uint local_histogram[8];
#endif

#ifdef SAMPLE_CLAIM
// The samples the geometry pass's fragments claimed (graph/msaa_compressed_claim.ron), a byte
// per pixel: exactly the covered samples, so one word replaces reading every depth sample.
layout(set = 0, binding = 6) readonly buffer SampleClaim { uint sample_claim[]; };
#endif

// The tile's pool blocks, shaded by all its invocations together. Each pixel chains its own
// entries in list order (`next`); blocks that do not fit wait for the next round (at most
// MAX_SHARED_ROUNDS, then their pixels shade them). SHARED_BLOCKS 0 (the graph's shared_blocks
// setting) turns the shared list off: every pixel loops over its own list, the thesis's resolve.
#ifndef SHARED_BLOCKS
#define SHARED_BLOCKS 512
#endif
#ifndef SHARED_MIN_BLOCKS
#define SHARED_MIN_BLOCKS 0u   // at most this many pool blocks in a tile: each pixel shades its own
#endif
#define ENTRY_NONE 0xFFFFu
#if SHARED_BLOCKS > 0
shared uint sh_block_link[SHARED_BLOCKS];    // the link that points at the block
shared uint sh_block_meta[SHARED_BLOCKS];    // local pixel | next entry of the pixel << 8 (ENTRY_NONE: last)
shared uvec2 sh_block_color[SHARED_BLOCKS];  // tone-mapped color, half floats (small shared use keeps occupancy up)
#endif
shared uint sh_block_total;

#include "light_tiles.glsl"

layout(push_constant) uniform Settings {
    float exposure;
    uint debug_view;   // DEBUG_VIEW_*; 4: distinct surfaces per pixel
    uint light_tiles;
    uint pool_blocks;
} settings;

// Writes a pixel's linear HDR colour, or without HDR_OUTPUT what the tonemap pass would make of it.
void store_hdr(ivec2 pixel, vec3 hdr) {
#ifdef HDR_OUTPUT
    imageStore(out_color, pixel, vec4(hdr, 1.0));
#else
    imageStore(out_color, pixel, vec4(linear_to_srgb(tonemap_aces(hdr * settings.exposure)), 1.0));
#endif
}

// Writes a pixel given as a tone-mapped (display) colour: with HDR_OUTPUT the HDR colour the
// tonemap pass shows as it (tonemap.glsl).
void store_display(ivec2 pixel, vec3 display) {
#ifdef HDR_OUTPUT
    imageStore(out_color, pixel, vec4(hdr_from_display(display, settings.exposure), 1.0));
#else
    imageStore(out_color, pixel, vec4(linear_to_srgb(display), 1.0));
#endif
}

// A block's words as loaded: albedo + metallic, normal, and its surface word.
struct BlockWords {
    uint albedo_metallic;
    uint normal;
    uint surface;
};

BlockWords load_head_block(uint pixel) {
    uint pair = pixel >> 1, k = pixel & 1u;
    BlockWords w;
    w.albedo_metallic = gb.pairs[pair].albedo_metallic[k];
    w.normal = gb.pairs[pair].normal[k];
    w.surface = gb.pairs[pair].surface[k];
    return w;
}

BlockWords load_pool_block(uint slot) {
    uint pair = slot >> 1, k = slot & 1u;
    BlockWords w;
    w.albedo_metallic = pool.pairs[pair].albedo_metallic[k];
    w.normal = pool.pairs[pair].normal[k];
    w.surface = pool.pairs[pair].surface[k];
    return w;
}

// The link stored in pool block `slot` (the next of its pixel's list).
uint pool_link(uint slot) { return pool.pairs[slot >> 1].link[slot & 1u]; }

Block decode_block(BlockWords w) {
    vec4 am = unpackUnorm4x8(w.albedo_metallic);
    Block b;
    b.albedo = am.rgb;
    b.metallic = am.a;
    b.normal = oct_decode(unpackSnorm2x16(w.normal));
    b.roughness = surface_word_roughness(w.surface);
    b.occlusion = surface_word_occlusion(w.surface);
    b.emissive = surface_word_emissive(w.surface);
    return b;
}

// The pool block a non-null link points at.
Block read_linked_block(uint link) { return decode_block(load_pool_block(link_slot(link))); }

vec3 shade_block(Block b, vec2 center, float depth) {
    Surface s;
    s.position = surface_position(center, depth);
    s.normal = b.normal;
    s.albedo = b.albedo;
    s.metallic = b.metallic;
    s.roughness = b.roughness;
    s.occlusion = b.occlusion;
    s.emissive = b.emissive;
    vec3 color = shade_tile_lights(s);
    if (settings.debug_view == DEBUG_VIEW_NORMALS) return pow(b.normal * 0.5 + 0.5, vec3(2.2));
    if (settings.debug_view == DEBUG_VIEW_ALBEDO) return pow(b.albedo, vec3(2.2));
    vec3 tint = settings.debug_view == DEBUG_VIEW_CASCADES ? cascade_tint(sun_cascade_of(s.position, s.normal)) : vec3(1.0);
    return tonemap_aces(color * settings.exposure) * tint;
}

vec3 heat(uint surfaces) {
    const vec3 ramp[5] = vec3[5](vec3(0.05, 0.05, 0.3), vec3(0.0, 0.6, 0.2), vec3(0.9, 0.8, 0.0), vec3(1.0, 0.35, 0.0), vec3(1.0, 0.0, 0.0));
    return pow(ramp[min(surfaces, 5u) - 1u], vec3(2.2));
}

// One pixel's list, as gathered before the lights are culled.
struct PixelList {
    float head_depth;      // depth at sample 0; 0: background there, so no head block
    uint kept;             // samples the head stands for (its own, and any dropped by a full pool or an AA cap)
    uint blocks;           // pool blocks listed
    uint listed;           // samples they cover
    uint lowest_sample;    // lowest sample a listed block holds (SAMPLES: none)
    uint background;       // samples with no geometry
    uint first_entry;      // first of its entries in the tile's shared list, or ENTRY_NONE
    uint next_link;        // the link to its first block not in the shared list yet (LINK_NULL: none)
};

uint head_index(ivec2 pixel) { return uint(pixel.y) * frame.size_lights.x + uint(pixel.x); }
uint pixel_count() { return frame.size_lights.x * frame.size_lights.y; }

uint entry_meta_pixel(uint meta) { return meta & 0xFFu; }
uint entry_meta_next(uint meta) { return meta >> 8; }

// Weight of a listed block: its samples, plus those the head stands for when there is no head
// block (given to the block with the lowest sample, whatever the list's order).
uint listed_weight(PixelList list, uint link) {
    bool takes_kept = list.head_depth <= 0.0 && link_sample(link) == list.lowest_sample;
    return link_count(link) + (takes_kept ? list.kept : 0u);
}

// A pixel's weighted sum of tone-mapped colors (each within [0, 1]) in units of 2^-24: at most
// 2^24 * SAMPLES <= 2^27, and integer sums do not depend on their order.
#define SUM_UNIT 16777216.0
void add_weighted(inout uvec3 sum, vec3 color, uint weight) {
    sum += uvec3(clamp(color, 0.0, 1.0) * SUM_UNIT + 0.5) * weight;
}

// What a pixel's head holds, loaded before anything waits on it (so that the loads' latencies
// overlap each other and the tile's first barrier instead of forming a chain).
struct HeadLoads {
    uint link;           // the head's link
    BlockWords block;
#ifdef SAMPLE_CLAIM
    float depth;         // depth at sample 0
    uint claim_word;     // the word of `sample_claim` holding the pixel's byte
#else
    float depth[SAMPLES];   // every sample's depth: the covered ones, and each block's
#endif
};

HeadLoads load_head(ivec2 pixel) {
    uint head = head_index(pixel);
    HeadLoads h;
    h.link = gb.pairs[head >> 1].link[head & 1u];
    h.block = load_head_block(head);
#ifdef SAMPLE_CLAIM
    h.depth = DEPTH_AT(pixel, 0u);
    h.claim_word = sample_claim[claim_word(head, pixel_count())];
#else
    for (uint s = 0u; s < SAMPLES; ++s) h.depth[s] = DEPTH_AT(pixel, s);
#endif
    return h;
}

float head_depth(HeadLoads h) {
#ifdef SAMPLE_CLAIM
    return h.depth;
#else
    return h.depth[0];
#endif
}

// Depth at sample `s` of the pixel whose head `h` is.
float loaded_depth(HeadLoads h, ivec2 pixel, uint s) {
#ifdef SAMPLE_CLAIM
    return DEPTH_AT(pixel, s);
#else
    return h.depth[s];
#endif
}

// Samples of the pixel that some surface covers.
uint covered_samples(HeadLoads h, uint head) {
#ifdef SAMPLE_CLAIM
    return uint(bitCount((h.claim_word >> claim_shift(head, pixel_count())) & 0xFFu));
#else
    uint covered = 0u;
    for (uint s = 0u; s < SAMPLES; ++s) covered += h.depth[s] > 0.0 ? 1u : 0u;
    return covered;
#endif
}

#if SHARED_BLOCKS > 0
// Puts the block `link` points to on the tile's shared list, after `last_entry` (the pixel's
// previous entry, or ENTRY_NONE); false when the list is full.
bool push_block(uint link, inout uint first_entry, inout uint last_entry) {
    uint entry = atomicAdd(sh_block_total, 1u);
    if (entry >= uint(SHARED_BLOCKS)) return false;
    sh_block_link[entry] = link;
    sh_block_meta[entry] = gl_LocalInvocationIndex | (ENTRY_NONE << 8);
    if (last_entry == ENTRY_NONE) {
        first_entry = entry;
    } else {
        sh_block_meta[last_entry] = (sh_block_meta[last_entry] & 0xFFu) | (entry << 8);
    }
    last_entry = entry;
    return true;
}
#endif

PixelList gather_pixel(ivec2 pixel, HeadLoads h, inout DepthRange range) {
    PixelList list;
    list.head_depth = head_depth(h);
    list.blocks = 0u;
    list.listed = 0u;
    list.lowest_sample = SAMPLES;
    list.first_entry = ENTRY_NONE;
    list.next_link = LINK_NULL;
    depth_range_add(range, list.head_depth);
    uint head = head_index(pixel);
    uint link = h.link;
    uint last_entry = ENTRY_NONE;
    // At most SAMPLES - 1 blocks can be listed (one per sample not owned by the head); the bound
    // also keeps a corrupted list from looping.
    for (uint n = 0u; n < SAMPLES && link_index(link) != LINK_NULL; ++n) {
        list.blocks += 1u;
        list.listed += link_count(link);
        list.lowest_sample = min(list.lowest_sample, link_sample(link));
        // Light culling must cover the depth each block is shaded at.
        depth_range_add(range, loaded_depth(h, pixel, link_sample(link)));
#if SHARED_BLOCKS > 0
        // Blocks past a full list wait for the next round (`shade_remaining_rounds`), in order.
        if (list.next_link == LINK_NULL && !push_block(link, list.first_entry, last_entry)) list.next_link = link;
#endif
        link = pool_link(link_slot(link));
    }
    // The head stands for every covered sample no listed block has: its own, and those of
    // fragments that kept no block (a full pool, an AA cap).
    uint covered = covered_samples(h, head);
    list.kept = covered - min(covered, list.listed);
    list.background = SAMPLES - min(SAMPLES, covered);
    return list;
}

uvec2 pack_color(vec3 c) { return uvec2(packHalf2x16(c.rg), packHalf2x16(vec2(c.b, 0.0))); }
vec3 unpack_color(uvec2 p) { return vec3(unpackHalf2x16(p.x), unpackHalf2x16(p.y).x); }

// Shades the tile's shared entries, spread over all invocations.
void shade_shared_blocks() {
#if SHARED_BLOCKS > 0
    uint total = min(sh_block_total, uint(SHARED_BLOCKS));
    for (uint e = gl_LocalInvocationIndex; e < total; e += TILE_SIZE * TILE_SIZE) {
        uint local_pixel = entry_meta_pixel(sh_block_meta[e]);  // every entry below the total was pushed
        ivec2 pixel = ivec2(gl_WorkGroupID.xy * TILE_SIZE + uvec2(local_pixel % TILE_SIZE, local_pixel / TILE_SIZE));
        uint link = sh_block_link[e];
        sh_block_color[e] = pack_color(shade_block(read_linked_block(link), vec2(pixel) + 0.5, DEPTH_AT(pixel, link_sample(link))));
    }
#endif
}

// Distinct surfaces of a pixel (the sky counts as one).
uint pixel_surfaces(PixelList list) {
    return max((list.background > 0u ? 1u : 0u) + (list.head_depth > 0.0 ? 1u : 0u) + list.blocks, 1u);
}

// Adds the pixel's entries in this round of the shared list to `sum` (`n`: the pixel's blocks
// summed so far).
uvec3 add_shared_blocks(PixelList list, uvec3 sum, inout uint n) {
#if SHARED_BLOCKS > 0
    for (uint e = list.first_entry; e != ENTRY_NONE; e = entry_meta_next(sh_block_meta[e]), ++n) {
        add_weighted(sum, unpack_color(sh_block_color[e]), listed_weight(list, sh_block_link[e]));
    }
#endif
    return sum;
}

// Rounds of the shared list at most (the first included): at 8x a tile has at most 1792 pool
// blocks, which the default 512-entry list takes in four. Blocks left after them are shaded by
// their pixels (`resolve_pixel`). (The bound also keeps loops with barriers short: lavapipe
// loses whole tiles when such a loop runs a few hundred times, as a 1-entry list would need.)
#define MAX_SHARED_ROUNDS 4u

// When the tile had more blocks than the shared list holds, its pixels put the rest on the
// list in further rounds, each shaded by all invocations together, and add them to their sums
// (`n`: the pixel's blocks summed so far). A pixel left to loop over its own blocks would hold
// its whole subgroup in the light loop once per block, and detailed tiles hold hundreds of
// blocks, so those serial loops would dominate the pass. Called by every invocation of the
// tile, `round_total` (the first round's pushes) the same for all.
uvec3 shade_remaining_rounds(bool inside, inout PixelList list, uvec3 sum, inout uint n, uint round_total) {
#if SHARED_BLOCKS > 0
    for (uint round = 1u; round < MAX_SHARED_ROUNDS && round_total > uint(SHARED_BLOCKS); ++round) {
        barrier();   // everyone has read this round's entries
        if (gl_LocalInvocationIndex == 0u) sh_block_total = 0u;
        barrier();
        list.first_entry = ENTRY_NONE;
        uint link = inside ? list.next_link : LINK_NULL;
        uint last_entry = ENTRY_NONE;
        for (uint guard = 0u; guard < SAMPLES && link_index(link) != LINK_NULL; ++guard) {
            if (!push_block(link, list.first_entry, last_entry)) break;
            link = pool_link(link_slot(link));
        }
        list.next_link = link;
        barrier();
        round_total = sh_block_total;
        shade_shared_blocks();
        barrier();
        if (inside) sum = add_shared_blocks(list, sum, n);
    }
#endif
    return sum;
}

// Adds the pixel's blocks from `link` on, the `n`-th of its list first, shaded by itself (a
// tile that did not share its blocks, or blocks left after the shared rounds), and its sky to
// `sum` (its head and shared blocks already in), and writes it.
void resolve_pixel(ivec2 pixel, vec2 center, PixelList list, uvec3 sum, uint link, uint n) {
    bool has_head = list.head_depth > 0.0;
    for (; n < list.blocks && link_index(link) != LINK_NULL; ++n) {
        vec3 c = shade_block(read_linked_block(link), center, DEPTH_AT(pixel, link_sample(link)));
        // Rounded as the shared list stores its colors: which blocks a tile shares depends on
        // the order of its lists, and the image must not.
        add_weighted(sum, unpack_color(pack_color(c)), listed_weight(list, link));
        link = pool_link(link_slot(link));
    }
    // Sky: the background samples, and the head's when the pixel has no surface at all.
    uint sky_weight = list.background + (!has_head && list.blocks == 0u ? list.kept : 0u);
    if (sky_weight > 0u) add_weighted(sum, tonemap_aces(sky_color(view_direction(center)) * settings.exposure), sky_weight);
    vec3 color = vec3(sum) * (1.0 / (SUM_UNIT * float(SAMPLES)));
    if (settings.debug_view == DEBUG_VIEW_SAMPLES) color = heat(pixel_surfaces(list));
    store_display(pixel, color);
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = frame.size_lights.xy;
    bool inside = all(lessThan(uvec2(pixel), size));
    vec2 center = vec2(pixel) + 0.5;

    HeadLoads head;
    if (inside) head = load_head(pixel);
    if (gl_LocalInvocationIndex == 0u) sh_block_total = 0u;
#ifdef WRITE_STATS
    if (gl_LocalInvocationIndex < 8u) local_histogram[gl_LocalInvocationIndex] = 0u;
#endif
    tile_begin();   // (its barrier also publishes the zeroed counters)
    DepthRange range = depth_range_empty();
    PixelList list;
    if (inside) list = gather_pixel(pixel, head, range);
#ifdef WRITE_STATS
    // Pixels with more than one distinct surface, per tile in shared memory (few, so few atomics).
    if (inside) {
        uint surfaces = min(pixel_surfaces(list), 8u);
        if (surfaces > 1u) atomicAdd(local_histogram[surfaces - 1u], 1u);
    }
#endif
    tile_add_depth_range(range);
    tile_cull_lights(settings.light_tiles != 0u);   // (its barriers publish the shared list)
    // A tile with at most SHARED_MIN_BLOCKS pool blocks leaves them to its pixels (0 by default:
    // sharing costs no more than per-pixel shading even for a tile with few blocks).
    bool distribute = false;
#if SHARED_BLOCKS > 0
    uint round_total = sh_block_total;
    distribute = round_total > SHARED_MIN_BLOCKS;
#endif
    // Every invocation shades its pixel's head, then all of them the tile's shared blocks.
    vec3 head_color = vec3(0.0);
    if (inside && list.head_depth > 0.0 && list.kept > 0u) {
        head_color = shade_block(decode_block(head.block), center, list.head_depth);
    }
    uvec3 sum = uvec3(0u);
    if (inside && list.head_depth > 0.0) add_weighted(sum, head_color, list.kept);
    // Blocks this pixel shades itself: all of them, or those the shared rounds left.
    uint own_link = inside ? head.link : LINK_NULL, own_n = 0u;
#if SHARED_BLOCKS > 0
    if (distribute) {
        shade_shared_blocks();
        barrier();
        if (inside) sum = add_shared_blocks(list, sum, own_n);
        sum = shade_remaining_rounds(inside, list, sum, own_n, round_total);
        own_link = inside ? list.next_link : LINK_NULL;
    }
#endif
    if (inside) resolve_pixel(pixel, center, list, sum, own_link, own_n);
#ifdef WRITE_STATS
    // The tile's counts were summed before the light culling's barriers: one global atomic per
    // counter and tile.
    uint lane = gl_LocalInvocationIndex;
    if (lane > 0u && lane < 8u && local_histogram[lane] != 0u) atomicAdd(stats.histogram[lane], local_histogram[lane]);
    if (gl_GlobalInvocationID.xy == uvec2(0u)) {
        stats.allocated = gb.header[GBUFFER_HEADER_ALLOCATED];
        stats.overflow_fragments = gb.header[GBUFFER_HEADER_OVERFLOW_FRAGMENTS];
        stats.overflow_samples = gb.header[GBUFFER_HEADER_OVERFLOW_SAMPLES];
        stats.pool_blocks = settings.pool_blocks;
        stats.pixels = size.x * size.y;
    }
#endif
}
