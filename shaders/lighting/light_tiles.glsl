// Point lights culled per 16x16-pixel tile, shared by every lighting pass so that all methods
// shade identically. A workgroup is one tile: it gathers the depth range of its samples, tests
// each light's sphere against the tile's four side planes and that range, and marks survivors
// in a bit set. Shading walks the set in light order, so the sum is the same, bit for bit, as
// looping over every light (a culled light is one whose window falloff is exactly zero on
// every pixel of the tile, and the loop skips those too).
//
// Needs: FrameConstants frame, GpuPointLight lights[], local size 16x16.
#ifndef CULLGRAPH_LIGHT_TILES_GLSL
#define CULLGRAPH_LIGHT_TILES_GLSL

#include "../common/shadows.glsl"

#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#define TILE_SIZE 16u
#define TILE_LIGHT_WORDS 32u                       // up to 1024 lights are culled per tile
#define TILE_MAX_LIGHTS (TILE_LIGHT_WORDS * 32u)

shared uint tile_far_bits;    // smallest reversed-Z depth with geometry (farthest surface)
shared uint tile_near_bits;   // largest (nearest surface)
shared uint tile_light_bits[TILE_LIGHT_WORDS];

void tile_begin() {
    uint t = gl_LocalInvocationIndex;
    if (t == 0u) {
        tile_far_bits = floatBitsToUint(1.0);
        tile_near_bits = 0u;
    }
    if (t < TILE_LIGHT_WORDS) tile_light_bits[t] = 0u;
    barrier();
}

// A running depth range over one invocation's samples; background (0) is ignored.
struct DepthRange {
    float farthest;   // smallest reversed-Z depth with geometry
    float nearest;    // largest; 0: no geometry yet
};

DepthRange depth_range_empty() { return DepthRange(1.0, 0.0); }

void depth_range_add(inout DepthRange range, float depth) {
    if (depth > 0.0) {
        range.farthest = min(range.farthest, depth);
        range.nearest = max(range.nearest, depth);
    }
}

// Adds one invocation's depth range to the tile. Every invocation of the workgroup calls it, in
// uniform control flow: the subgroup reduces first, so the tile takes one shared atomic per
// subgroup instead of two per sample (which would serialise on two addresses). Positive floats order
// like uints.
void tile_add_depth_range(DepthRange range) {
    bool any_geometry = range.nearest > 0.0;
    uint far_bits = subgroupMin(any_geometry ? floatBitsToUint(range.farthest) : 0xFFFFFFFFu);
    uint near_bits = subgroupMax(any_geometry ? floatBitsToUint(range.nearest) : 0u);
    if (subgroupElect() && near_bits != 0u) {
        atomicMin(tile_far_bits, far_bits);
        atomicMax(tile_near_bits, near_bits);
    }
}

vec3 tile_corner_ray(vec2 pixel, vec2 size) {
    vec2 ndc = pixel / size * 2.0 - 1.0;
    vec4 p = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    return p.xyz / p.w;
}

// Marks the lights that may light a pixel of this tile. `enabled` false (or an orthographic
// view, or more lights than the set holds) marks every light.
void tile_cull_lights(bool enabled) {
    barrier();
    uint count = min(frame.size_lights.z, TILE_MAX_LIGHTS);
    vec2 size = vec2(frame.size_lights.xy);
    vec2 lo = vec2(gl_WorkGroupID.xy * TILE_SIZE);
    vec2 hi = min(lo + vec2(TILE_SIZE), size);
    // Perspective: clip w is the view depth, w = dot(row 3, p); near = clip z (reversed-Z, infinite far).
    vec4 row_w = vec4(frame.view_proj[0][3], frame.view_proj[1][3], frame.view_proj[2][3], frame.view_proj[3][3]);
    bool perspective = row_w.w == 0.0 && dot(row_w.xyz, row_w.xyz) > 0.0;
    bool cull = enabled && perspective && frame.size_lights.z <= TILE_MAX_LIGHTS;
    float near = frame.view_proj[3][2];
    bool any_geometry = tile_near_bits != 0u;
    // View-depth range of the tile's surfaces (depth d = near / view depth).
    float z_min = any_geometry ? near / uintBitsToFloat(tile_near_bits) : 0.0;
    float z_max = any_geometry ? near / uintBitsToFloat(tile_far_bits) : 0.0;
    vec3 c00 = tile_corner_ray(lo, size), c10 = tile_corner_ray(vec2(hi.x, lo.y), size);
    vec3 c11 = tile_corner_ray(hi, size), c01 = tile_corner_ray(vec2(lo.x, hi.y), size);
    vec3 center = c00 + c10 + c11 + c01;
    vec3 planes[4] = vec3[4](cross(c00, c10), cross(c10, c11), cross(c11, c01), cross(c01, c00));
    for (int p = 0; p < 4; ++p) {
        vec3 n = normalize(planes[p]);
        planes[p] = dot(n, center) < 0.0 ? -n : n;   // inward
    }
    for (uint i = gl_LocalInvocationIndex; i < count; i += TILE_SIZE * TILE_SIZE) {
        bool touches = true;
        if (cull) {
            vec3 c = lights[i].position_range.xyz;
            // Widened a little so rounding in the reconstructed positions never drops a light.
            float r = lights[i].position_range.w * 1.001 + 1e-4 * length(c);
            float w = dot(row_w.xyz, c);
            touches = any_geometry && w + r >= z_min * 0.999 && w - r <= z_max * 1.001;
            for (int p = 0; p < 4 && touches; ++p) touches = dot(planes[p], c) >= -r;
        }
        if (touches) atomicOr(tile_light_bits[i >> 5], 1u << (i & 31u));
    }
    barrier();
}

// Radiance towards the eye from surface `s`: sky ambient, the sun (through its shadows), and the tile's point lights
// (every light past the set's capacity too).
vec3 shade_tile_lights(Surface s) {
    vec3 v = -normalize(s.position);
    vec3 radiance = ambient_light(s, frame.ambient.rgb) + s.emissive;
    radiance += brdf_light(s, v, -frame.sun_direction.xyz, frame.sun_color.rgb) * sun_visibility(s.position, s.normal);
    uint count = frame.size_lights.z;
    for (uint word = 0u; word < TILE_LIGHT_WORDS && word * 32u < count; ++word) {
        uint bits = tile_light_bits[word];
        while (bits != 0u) {
            uint i = word * 32u + uint(findLSB(bits));
            bits &= bits - 1u;
            vec3 to_light = lights[i].position_range.xyz - s.position;
            float dist = length(to_light);
            float range = lights[i].position_range.w;
            if (dist >= range) continue;
            vec3 l = to_light / max(dist, 1e-6);
            radiance += brdf_light(s, v, l, punctual_radiance(lights[i].color, lights[i].spot, l, dist, range))
                * local_light_visibility(lights[i], s.position, s.normal, l, dist);
        }
    }
    for (uint i = TILE_MAX_LIGHTS; i < count; ++i) {
        vec3 to_light = lights[i].position_range.xyz - s.position;
        float dist = length(to_light);
        float range = lights[i].position_range.w;
        if (dist >= range) continue;
        vec3 l = to_light / max(dist, 1e-6);
            radiance += brdf_light(s, v, l, punctual_radiance(lights[i].color, lights[i].spot, l, dist, range))
                * local_light_visibility(lights[i], s.position, s.normal, l, dist);
    }
    return radiance;
}

// Position (eye-relative) of the surface seen at `pixel_center` (pixels) with depth `depth`.
vec3 surface_position(vec2 pixel_center, float depth) {
    vec2 ndc = pixel_center / vec2(frame.size_lights.xy) * 2.0 - 1.0;
    vec4 p = frame.inv_view_proj * vec4(ndc, depth, 1.0);
    return p.xyz / p.w;
}

// Direction from the eye through `pixel_center`, for the sky.
vec3 view_direction(vec2 pixel_center) {
    vec2 ndc = pixel_center / vec2(frame.size_lights.xy) * 2.0 - 1.0;
    vec4 far_point = frame.inv_view_proj * vec4(ndc, 1e-6, 1.0);
    return normalize(far_point.xyz / far_point.w);
}

#endif
