#version 460
// Deferred lighting in compute over a G-buffer of images: sun, tile-culled point lights, a
// sky ambient term scaled by the surface's occlusion and its emissive colour (with
// EMISSIVE_OCCLUSION: an image holds them; without, none and 1), written as linear HDR colour
// (scene radiance before exposure; the tonemap pass maps it). With multisampled images (the
// per-sample MSAA baseline) a pixel whose samples all hold the same surface (material, normal
// and plane) is shaded once; otherwise every sample is shaded, the tone-mapped results averaged
// and the HDR colour that shows as that average stored (tonemap.glsl). Debug views are display
// colours, stored the same way.
#include "../common/scene.glsl"
#include "../common/shading.glsl"
#include "../common/gbuffer_normal.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

#ifndef SAMPLES
#define SAMPLES 1   // samples per pixel of the depth (and G-buffer) images
#endif
#if SAMPLES > 1
layout(set = 0, binding = 0) uniform sampler2DMS depth_tex;
layout(set = 0, binding = 1) uniform sampler2DMS albedo_metallic_tex;
layout(set = 0, binding = 2) uniform NORMAL_SAMPLER_2DMS normal_roughness_tex;
#ifdef EMISSIVE_OCCLUSION
layout(set = 0, binding = 6) uniform sampler2DMS emissive_occlusion_tex;
#endif
#define FETCH(tex, p, s) texelFetch(tex, p, int(s))
#else
layout(set = 0, binding = 0) uniform sampler2D depth_tex;
layout(set = 0, binding = 1) uniform sampler2D albedo_metallic_tex;
layout(set = 0, binding = 2) uniform NORMAL_SAMPLER_2D normal_roughness_tex;
#ifdef EMISSIVE_OCCLUSION
layout(set = 0, binding = 6) uniform sampler2D emissive_occlusion_tex;
#endif
#define FETCH(tex, p, s) texelFetch(tex, p, 0)
#endif
layout(set = 0, binding = 3, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 4, scalar) readonly buffer Lights { GpuPointLight lights[]; };
// HDR_OUTPUT: linear HDR colour for a tonemap pass; without, the tone-mapped image itself.
#ifdef HDR_OUTPUT
layout(set = 0, binding = 5, rgba16f) uniform writeonly image2D out_color;
#else
layout(set = 0, binding = 5, rgba8) uniform writeonly image2D out_color;
#endif

#include "../lighting/light_tiles.glsl"

layout(push_constant) uniform Settings {
    float exposure;
    uint debug_view;   // DEBUG_VIEW_*
    uint light_tiles;
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

// Linear HDR color of sample `s` of `pixel`, or with a debug view its display color;
// `display` says which.
vec3 shade_sample(ivec2 pixel, uint s, vec2 center, out bool display) {
    display = false;
    float depth = FETCH(depth_tex, pixel, s).r;
    if (depth <= 0.0) return sky_color(view_direction(center));
    vec4 am = FETCH(albedo_metallic_tex, pixel, s);
    vec4 nr = decode_normal_roughness(FETCH(normal_roughness_tex, pixel, s));
    Surface surface;
    surface.position = surface_position(center, depth);
    surface.normal = nr.xyz;
    surface.albedo = am.rgb;
    surface.metallic = am.a;
    surface.roughness = nr.a;
#ifdef EMISSIVE_OCCLUSION
    vec4 eo = FETCH(emissive_occlusion_tex, pixel, s);
    surface.emissive = eo.rgb;
    surface.occlusion = eo.a;
#else
    surface.emissive = vec3(0.0);
    surface.occlusion = 1.0;
#endif
    uint debug_view = settings.debug_view;
    display = debug_view != DEBUG_VIEW_NONE && debug_view != DEBUG_VIEW_SAMPLES;
    if (debug_view == DEBUG_VIEW_NORMALS) return pow(surface.normal * 0.5 + 0.5, vec3(2.2));
    if (debug_view == DEBUG_VIEW_ALBEDO) return pow(am.rgb, vec3(2.2));
    if (debug_view == DEBUG_VIEW_DEPTH) return pow(vec3(fract(log2(depth) * 0.25)), vec3(2.2));
    if (debug_view == DEBUG_VIEW_CASCADES) {
        vec3 lit = tonemap_aces(shade_tile_lights(surface) * settings.exposure);
        return lit * cascade_tint(sun_cascade_of(surface.position, surface.normal));
    }
    return shade_tile_lights(surface);
}

// Tone-mapped color of sample `s` of `pixel` (what the display shows of it).
vec3 shade_sample_display(ivec2 pixel, uint s, vec2 center) {
    bool display;
    vec3 c = shade_sample(pixel, s, center, display);
    return display ? c : tonemap_aces(c * settings.exposure);
}

#if SAMPLES > 1
// Where sample `s` lies in its pixel: Vulkan's standard sample locations.
vec2 sample_location(uint s) {
#if SAMPLES == 2
    const vec2 at[2] = vec2[](vec2(0.75, 0.75), vec2(0.25, 0.25));
    return at[s];
#elif SAMPLES == 4
    const vec2 at[4] = vec2[](vec2(0.375, 0.125), vec2(0.875, 0.375), vec2(0.125, 0.625), vec2(0.625, 0.875));
    return at[s];
#elif SAMPLES == 8
    const vec2 at[8] = vec2[](vec2(0.5625, 0.3125), vec2(0.4375, 0.6875), vec2(0.8125, 0.5625), vec2(0.3125, 0.1875),
                              vec2(0.1875, 0.8125), vec2(0.0625, 0.4375), vec2(0.6875, 0.9375), vec2(0.9375, 0.0625));
    return at[s];
#else
    return vec2(0.5);
#endif
}
#endif

// Whether every sample of `pixel` holds what sample 0 holds (one surface: shade once): the same
// material and normal, and a position on sample 0's plane (two parallel surfaces of one
// material differ only in depth). The plane allows a thousandth of the distance, far more than
// the depth's rounding and far less than what separates two surfaces that should be shaded apart.
bool single_surface(ivec2 pixel) {
    vec4 a0 = FETCH(albedo_metallic_tex, pixel, 0u);
    NORMAL_TEXEL4 n0 = FETCH(normal_roughness_tex, pixel, 0u);
    float d0 = FETCH(depth_tex, pixel, 0u).r;
    bool bg0 = d0 <= 0.0;
#if SAMPLES > 1
    vec3 p0 = surface_position(vec2(pixel) + sample_location(0u), d0);
    vec3 normal0 = decode_normal_roughness(n0).xyz;
#endif
    for (uint s = 1u; s < SAMPLES; ++s) {
        float d = FETCH(depth_tex, pixel, s).r;
        bool bg = d <= 0.0;
        if (bg != bg0) return false;
        if (bg) continue;
        if (FETCH(albedo_metallic_tex, pixel, s) != a0 || FETCH(normal_roughness_tex, pixel, s) != n0) return false;
#ifdef EMISSIVE_OCCLUSION
        if (FETCH(emissive_occlusion_tex, pixel, s) != FETCH(emissive_occlusion_tex, pixel, 0u)) return false;
#endif
#if SAMPLES > 1
        vec3 p = surface_position(vec2(pixel) + sample_location(s), d);
        if (abs(dot(p - p0, normal0)) > 1e-3 * length(p0)) return false;
#endif
    }
    return true;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = frame.size_lights.xy;
    bool inside = all(lessThan(uvec2(pixel), size));
    vec2 center = vec2(pixel) + 0.5;
    tile_begin();
    DepthRange range = depth_range_empty();
    if (inside) {
        for (uint s = 0u; s < SAMPLES; ++s) depth_range_add(range, FETCH(depth_tex, pixel, s).r);
    }
    tile_add_depth_range(range);
    tile_cull_lights(settings.light_tiles != 0u);
    if (!inside) return;
    if (settings.debug_view == DEBUG_VIEW_SAMPLES) {
        store_display(pixel, single_surface(pixel) ? vec3(0.003, 0.003, 0.05) : vec3(1.0, 0.0, 0.0));
    } else if (single_surface(pixel)) {
        bool display;
        vec3 c = shade_sample(pixel, 0u, center, display);
        if (display) {
            store_display(pixel, c);
        } else {
            store_hdr(pixel, c);
        }
    } else {
        vec3 color = vec3(0.0);
        for (uint s = 0u; s < SAMPLES; ++s) color += shade_sample_display(pixel, s, center);
        store_display(pixel, color / float(SAMPLES));
    }
}
