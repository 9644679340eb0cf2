#version 460
// Shading from the visibility buffer (seed 003) with MSAA: per pixel, the distinct
// (instance, triangle) ids among its samples (PACKED_IDS: both in one word, see visibility.frag)
// are each shaded once: the triangle is fetched from the shared pools, the camera ray through
// the pixel center gives its barycentrics (the attributes a rasterizer interpolates at the pixel
// center), and the tone-mapped result is weighted by the samples the id covers. The background
// is sky. The mean is stored as the linear HDR colour the tonemap pass shows as it
// (tonemap.glsl). Texture coordinates and their screen derivatives come from the same ray casts through
// the pixel center and its right and lower neighbours' (the rasterizer's own derivatives are
// the differences between neighbouring pixels, so both methods pick the same mips).
#include "../common/material_surface.glsl"
#include "../common/shading.glsl"
#include "../common/octahedral.glsl"
#include "../common/emissive_occlusion.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

#ifndef SAMPLES
#define SAMPLES 1
#endif
#if SAMPLES > 1
layout(set = 0, binding = 0) uniform sampler2DMS depth_tex;
layout(set = 0, binding = 1) uniform usampler2DMS id_tex;
#define FETCH(tex, p, s) texelFetch(tex, p, int(s))
#else
layout(set = 0, binding = 0) uniform sampler2D depth_tex;
layout(set = 0, binding = 1) uniform usampler2D id_tex;
#define FETCH(tex, p, s) texelFetch(tex, p, 0)
#endif
layout(set = 0, binding = 2, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 3, scalar) readonly buffer Lights { GpuPointLight lights[]; };
// HDR_OUTPUT: linear HDR colour for a tonemap pass; without, the tone-mapped image itself.
#ifdef HDR_OUTPUT
layout(set = 0, binding = 4, rgba16f) uniform writeonly image2D out_color;
#else
layout(set = 0, binding = 4, rgba8) uniform writeonly image2D out_color;
#endif
#define INSTANCES_BINDING 5
#include "../common/instance_ranges.glsl"
layout(set = 0, binding = 6, scalar) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 7, scalar) readonly buffer PoolPositions { vec3 positions[]; };
layout(set = 0, binding = 10) readonly buffer PoolNormals { uint normals[]; };
layout(set = 0, binding = 11, scalar) readonly buffer PoolSurface { SurfaceVertex surface[]; };
layout(set = 0, binding = 8) readonly buffer Indices { uint indices[]; };
layout(set = 0, binding = 9) readonly buffer TriangleBases { uvec2 triangle_bases[]; };

#include "light_tiles.glsl"

layout(push_constant) uniform Settings {
    float exposure;
    uint debug_view;
    uint light_tiles;
    uint triangle_bits;    // PACKED_IDS: low bits of an id word that hold the triangle
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

// Sample `s`'s (instance id, triangle id).
uvec2 load_id(ivec2 pixel, uint s) {
#ifdef PACKED_IDS
    uint word = FETCH(id_tex, pixel, s).x;
    return uvec2(word >> settings.triangle_bits, word & ((1u << settings.triangle_bits) - 1u));
#else
    return FETCH(id_tex, pixel, s).xy;
#endif
}

// Barycentric weights (of vertices 1 and 2) of the hit of the ray through `pixel` on the plane of
// the triangle p0, p0 + e1, p0 + e2 (Moller-Trumbore without bounds); false when the ray runs
// along the plane.
bool plane_hit(vec2 pixel, vec3 p0, vec3 e1, vec3 e2, out vec2 uv) {
    vec3 dir = view_direction(pixel);
    vec3 pv = cross(dir, e2);
    float det = dot(e1, pv);
    if (abs(det) <= 1e-20) {
        uv = vec2(0.0);
        return false;
    }
    vec3 t = -p0;
    uv = vec2(dot(t, pv), dot(dir, cross(t, e1))) / det;
    return true;
}

// The surface of triangle `prim` of instance `id` seen through `center`, at `depth`.
Surface rebuild(uint id, uint prim, vec2 center, float depth) {
    GpuInstance inst = instance_record(id);
    uvec2 base = triangle_bases[id];
    vec3 p[3];
    vec3 n[3];
    vec2 t[3];
    vec4 tangent[3];
    mat3 m3 = transpose(mat3(inst.row0.xyz, inst.row1.xyz, inst.row2.xyz));
    bool mirrored = instance_is_mirrored(inst);
    for (uint k = 0u; k < 3u; ++k) {
        uint vertex = indices[base.x + 3u * prim + k] + base.y;
        SurfaceVertex v = surface[vertex];
        p[k] = instance_rel_eye(inst, positions[vertex], frame.eye_hi.xyz, frame.eye_lo.xyz);
        n[k] = instance_normal(inst, oct_decode(unpackSnorm2x16(normals[vertex])));
        t[k] = v.uv;
        vec4 local = vec4(unpackSnorm2x16(v.tangent_xy), unpackSnorm2x16(v.tangent_zw));
        tangent[k] = vec4(m3 * local.xyz, (local.w < 0.0) != mirrored ? -1.0 : 1.0);
    }
    vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
    vec2 b, bx, by;
    vec3 normal = n[0];
    vec2 uv = t[0], duv_dx = vec2(0.0), duv_dy = vec2(0.0);
    vec4 tan = tangent[0];
    if (plane_hit(center, p[0], e1, e2, b)) {
        float w = 1.0 - b.x - b.y;
        normal = w * n[0] + b.x * n[1] + b.y * n[2];
        uv = w * t[0] + b.x * t[1] + b.y * t[2];
        tan = vec4(w * tangent[0].xyz + b.x * tangent[1].xyz + b.y * tangent[2].xyz, tangent[0].w);
        if (plane_hit(center + vec2(1.0, 0.0), p[0], e1, e2, bx) && plane_hit(center + vec2(0.0, 1.0), p[0], e1, e2, by)) {
            mat2 dt = mat2(t[1] - t[0], t[2] - t[0]);
            duv_dx = dt * (bx - b);
            duv_dy = dt * (by - b);
        }
    }
    normal = normalize(normal);
    // As gl_FrontFacing: the winding seen on screen, flipped by a mirroring transform.
    bool front = (dot(cross(e1, e2), view_direction(center)) < 0.0) != mirrored;
    if (!front) normal = -normal;
    GpuMaterial m = materials[instance_material(inst)];
    MaterialSurface textured_surface = material_surface(m, uv, duv_dx, duv_dy, normal, tan, front);
    Surface s;
    s.position = surface_position(center, depth);
    s.normal = textured_surface.normal;
    // The material as the G-buffer methods store it (albedo and metallic in RGBA8 UNORM, roughness
    // in 8 bits), so that every method shades the same inputs: the 8-bit steps of a dark albedo
    // alone shift whole surfaces by about one output level.
    vec4 albedo_metallic = unpackUnorm4x8(packUnorm4x8(vec4(textured_surface.albedo, textured_surface.metallic)));
    s.albedo = albedo_metallic.rgb;
    s.metallic = albedo_metallic.a;
    s.roughness = unpackUnorm4x8(packUnorm4x8(vec4(textured_surface.roughness))).x;
    s.emissive = textured_surface.emissive;
    s.occlusion = textured_surface.occlusion;
    round_like_gbuffer(s.emissive, s.occlusion);
    return s;
}

vec3 shade(Surface s) {
    if (settings.debug_view == DEBUG_VIEW_NORMALS) return pow(s.normal * 0.5 + 0.5, vec3(2.2));
    if (settings.debug_view == DEBUG_VIEW_ALBEDO) return pow(s.albedo, vec3(2.2));
    vec3 tint = settings.debug_view == DEBUG_VIEW_CASCADES ? cascade_tint(sun_cascade_of(s.position, s.normal)) : vec3(1.0);
    return tonemap_aces(shade_tile_lights(s) * settings.exposure) * tint;
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
    // Distinct ids among the samples, with the samples each covers and the first of them.
    uvec2 ids[SAMPLES];
    uint counts[SAMPLES];
    uint firsts[SAMPLES];
    uint distinct = 0u, background = 0u;
    for (uint s = 0u; s < SAMPLES; ++s) {
        if (FETCH(depth_tex, pixel, s).r <= 0.0) {
            background += 1u;
            continue;
        }
        uvec2 id = load_id(pixel, s);
        uint k = 0u;
        while (k < distinct && ids[k] != id) ++k;
        if (k == distinct) {
            ids[k] = id;
            counts[k] = 0u;
            firsts[k] = s;
            distinct += 1u;
        }
        counts[k] += 1u;
    }
    vec3 sum = tonemap_aces(sky_color(view_direction(center)) * settings.exposure) * float(background);
    for (uint k = 0u; k < distinct; ++k) {
        Surface s = rebuild(ids[k].x, ids[k].y, center, FETCH(depth_tex, pixel, firsts[k]).r);
        sum += shade(s) * float(counts[k]);
    }
    vec3 color = sum / float(SAMPLES);
    if (settings.debug_view == DEBUG_VIEW_SAMPLES) {
        color = distinct + (background > 0u ? 1u : 0u) > 1u ? vec3(1.0, 0.0, 0.0) : vec3(0.003, 0.003, 0.05);
    }
    store_display(pixel, color);
}
