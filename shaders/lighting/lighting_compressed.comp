#version 460
// Lighting over the compressed G-buffer (thesis 000 section 4.3, resolve): per pixel, every
// block of its list is shaded once with the tile's lights, tone-mapped, and weighted by the
// samples it covers; the background samples (depth 0) are sky; the head takes the rest (its own
// samples and any a full pool dropped). The weighted mean is written sRGB-encoded.
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
    BlockPair pairs[];
} gb;
layout(set = 0, binding = 2, scalar) readonly buffer Frame { FrameConstants frame; };
layout(set = 0, binding = 3, scalar) readonly buffer Lights { GpuPointLight lights[]; };
layout(set = 0, binding = 4, rgba8) uniform writeonly image2D out_color;
#ifdef WRITE_STATS
// Pool counters and blocks per pixel (GbufferCounters in src/stats/gbuffer.rs).
layout(set = 0, binding = 5) buffer Stats {
    uint allocated;
    uint overflow_fragments;
    uint overflow_samples;
    uint pool_blocks;
    uint pixels;
    uint surfaces;           // distinct surfaces over all pixels (sky counts as one)
    uint pad[2];
    uint histogram[8];       // pixels with 1..8 distinct surfaces (sky counts as one)
} stats;
shared uint local_histogram[8];
#endif

#include "light_tiles.glsl"

layout(push_constant) uniform Settings {
    float exposure;
    uint debug_view;   // DEBUG_VIEW_*; 4: distinct surfaces per pixel
    uint light_tiles;
    uint pool_blocks;
} settings;

Block read_block(uint index) {
    uint pair = index >> 1, k = index & 1u;
    vec4 am = unpackUnorm4x8(gb.pairs[pair].albedo_metallic[k]);
    Block b;
    b.albedo = am.rgb;
    b.metallic = am.a;
    b.normal = oct_decode(unpackSnorm2x16(gb.pairs[pair].normal[k]));
    b.roughness = float(uint(gb.pairs[pair].roughness[k])) / 255.0;
    b.ao = float(uint(gb.pairs[pair].ao[k])) / 255.0;
    return b;
}

vec3 shade_block(Block b, vec2 center, float depth) {
    Surface s;
    s.position = surface_position(center, depth);
    s.normal = b.normal;
    s.albedo = b.albedo;
    s.metallic = b.metallic;
    s.roughness = b.roughness;
    vec3 color = shade_tile_lights(s);   // ambient occlusion is stored but 1 in every scene so far
    if (settings.debug_view == DEBUG_VIEW_NORMALS) return pow(b.normal * 0.5 + 0.5, vec3(2.2));
    if (settings.debug_view == DEBUG_VIEW_ALBEDO) return pow(b.albedo, vec3(2.2));
    return tonemap_aces(color * settings.exposure);
}

vec3 heat(uint surfaces) {
    const vec3 ramp[5] = vec3[5](vec3(0.05, 0.05, 0.3), vec3(0.0, 0.6, 0.2), vec3(0.9, 0.8, 0.0), vec3(1.0, 0.35, 0.0), vec3(1.0, 0.0, 0.0));
    return pow(ramp[min(surfaces, 5u) - 1u], vec3(2.2));
}

// Shades and writes one pixel; returns its number of distinct surfaces (the sky counts as one).
uint resolve_pixel(ivec2 pixel, vec2 center, uint background) {
    uvec2 size = frame.size_lights.xy;
    uint head = uint(pixel.y) * size.x + uint(pixel.x);
    bool head_surface = DEPTH_AT(pixel, 0u) > 0.0;
    vec3 sum = vec3(0.0);
    uint listed = 0u;
    uint surfaces = (background > 0u ? 1u : 0u) + (head_surface ? 1u : 0u);
    vec3 first_listed = vec3(0.0);
    uint link = gb.pairs[head >> 1].link[head & 1u];
    // At most SAMPLES - 1 blocks can be listed (one per sample not owned by the head); the bound
    // also keeps a corrupted list from looping.
    for (uint n = 0u; n < SAMPLES && link_index(link) != LINK_NULL; ++n) {
        uint index = link_index(link);
        uint count = link_count(link);
        vec3 c = shade_block(read_block(index), center, DEPTH_AT(pixel, link_sample(link)));
        if (listed == 0u) first_listed = c;
        sum += c * float(count);
        listed += count;
        surfaces += 1u;
        link = gb.pairs[index >> 1].link[index & 1u];
    }
    vec3 sky = tonemap_aces(sky_color(view_direction(center)) * settings.exposure);
    sum += sky * float(background);
    // The rest: the head's own samples and any the full pool dropped.
    uint rest = SAMPLES - min(SAMPLES, listed + background);
    if (rest > 0u) {
        if (head_surface) {
            sum += shade_block(read_block(head), center, DEPTH_AT(pixel, 0u)) * float(rest);
        } else {
            sum += (listed > 0u ? first_listed : sky) * float(rest);
        }
    }
    vec3 color = sum / float(SAMPLES);
    if (settings.debug_view == DEBUG_VIEW_SAMPLES) color = heat(max(surfaces, 1u));
    imageStore(out_color, pixel, vec4(linear_to_srgb(color), 1.0));
    return max(surfaces, 1u);
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = frame.size_lights.xy;
    bool inside = all(lessThan(uvec2(pixel), size));
    vec2 center = vec2(pixel) + 0.5;

    tile_begin();
#ifdef WRITE_STATS
    if (gl_LocalInvocationIndex < 8u) local_histogram[gl_LocalInvocationIndex] = 0u;
#endif
    uint background = 0u;
    if (inside) {
        for (uint s = 0u; s < SAMPLES; ++s) {
            float d = DEPTH_AT(pixel, s);
            tile_add_depth(d);
            if (d <= 0.0) background += 1u;
        }
    }
    tile_cull_lights(settings.light_tiles != 0u);
    uint surfaces = 0u;
    if (inside) surfaces = resolve_pixel(pixel, center, background);
#ifdef WRITE_STATS
    if (inside) atomicAdd(local_histogram[clamp(surfaces, 1u, 8u) - 1u], 1u);
    barrier();
    if (gl_LocalInvocationIndex < 8u) atomicAdd(stats.histogram[gl_LocalInvocationIndex], local_histogram[gl_LocalInvocationIndex]);
    if (gl_GlobalInvocationID.xy == uvec2(0u)) {
        stats.allocated = gb.header[GBUFFER_HEADER_ALLOCATED];
        stats.overflow_fragments = gb.header[GBUFFER_HEADER_OVERFLOW_FRAGMENTS];
        stats.overflow_samples = gb.header[GBUFFER_HEADER_OVERFLOW_SAMPLES];
        stats.pool_blocks = settings.pool_blocks;
        stats.pixels = size.x * size.y;
    }
    if (inside) atomicAdd(stats.surfaces, surfaces);
#endif
}

