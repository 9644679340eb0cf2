// Shadows: every lighting method and the transparent pass look them up here. The including
// shader declares `frame` (FrameConstants) first. The sun's cascades are layers of one D32
// array, bound at SHADOW_BINDING, the spot and point lights' faces layers of another, bound at
// LOCAL_SHADOW_BINDING, both with a comparison sampler (reversed-Z: a lookup gives the share of
// texels the reference is at or in front of). With no cascades (frame.sun_shadows.info.x == 0),
// or a light without faces (shadow.x == NO_SHADOW), nothing is read and the light is unblocked.
#ifndef CULLGRAPH_SHADOWS_GLSL
#define CULLGRAPH_SHADOWS_GLSL

// Without SHADOWS (a view without shadows: the lighting kinds pick that variant) nothing is
// bound or looked up, and every light reaches every point.
#ifdef SHADOWS

#ifndef SHADOW_BINDING
#define SHADOW_BINDING 15
#endif
#ifndef LOCAL_SHADOW_BINDING
#define LOCAL_SHADOW_BINDING 14
#endif
layout(set = 0, binding = SHADOW_BINDING) uniform sampler2DArrayShadow sun_shadow_maps;
layout(set = 0, binding = LOCAL_SHADOW_BINDING) uniform sampler2DArrayShadow local_shadow_maps;

// Offsets that keep a surface from shadowing itself, in texels of the cascade it is looked up
// in: along its normal (the texel's footprint on a slope), then towards the sun (the depth the
// bilinear filter and the map's own rounding may add). Both scale with the texel, so every
// cascade gets the same bias relative to its resolution.
const float SHADOW_NORMAL_OFFSET = 1.5;
const float SHADOW_SUN_OFFSET = 1.0;
// A lookup stays this many texels inside a cascade's border (the filter's reach), else the
// next cascade shades the point.
const float SHADOW_BORDER = 2.5;

// Which cascade shades the eye-relative point `p` (-1: none), with its position in that
// cascade's map: xy in texels' units 0..1, z the reversed depth.
int sun_shadow_cascade(vec3 p, vec3 normal, out vec3 map) {
    SunShadows sh = frame.sun_shadows;
    uint count = min(sh.info.x, 4u);
    float size = float(max(sh.info.y, 1u));
    vec3 to_sun = -frame.sun_direction.xyz;
    for (uint c = 0u; c < count; ++c) {
        float texel = sh.texel[c];
        vec3 q = p + normal * (texel * SHADOW_NORMAL_OFFSET) + to_sun * (texel * SHADOW_SUN_OFFSET);
        vec4 clip = sh.cascades[c] * vec4(q, 1.0);
        vec2 uv = clip.xy * 0.5 + 0.5;
        float border = SHADOW_BORDER / size;
        if (all(greaterThanEqual(uv, vec2(border))) && all(lessThanEqual(uv, vec2(1.0 - border))) && clip.z >= 0.0 && clip.z <= 1.0) {
            map = vec3(uv, clip.z);
            return int(c);
        }
    }
    return -1;
}

// How much of the sun reaches the eye-relative point `p` with surface normal `normal`: 0 in
// shadow, 1 lit, filtered over 4x4 texels (nine bilinear comparisons, weighted as a tent).
float sun_visibility(vec3 p, vec3 normal) {
    vec3 map;
    int c = sun_shadow_cascade(p, normal, map);
    if (c < 0) return 1.0;
    float texel = 1.0 / float(max(frame.sun_shadows.info.y, 1u));
    float lit = 0.0;
    for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
            float w = float((2 - abs(x)) * (2 - abs(y)));
            vec2 uv = map.xy + vec2(x, y) * texel;
            lit += w * texture(sun_shadow_maps, vec4(uv, float(c), map.z));
        }
    }
    return lit / 16.0;
}

// The face of a cube map that holds direction `v` (from the light): +x, -x, +y, -y, +z, -z.
uint cube_face(vec3 v) {
    vec3 a = abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z) return v.y >= 0.0 ? 2u : 3u;
    return v.z >= 0.0 ? 4u : 5u;
}

// How much of light `light` reaches the eye-relative point `p` with normal `normal`, `l` the
// unit direction from `p` to the light `dist` away: 0 in its shadow, 1 lit, filtered over 4x4
// texels of its face as the sun's cascades are, with offsets in texels of the face at `p`.
float local_light_visibility(GpuPointLight light, vec3 p, vec3 normal, vec3 l, float dist) {
    uint first = light.shadow.x;
    if (first == NO_SHADOW) return 1.0;
    uint face = first + (light.shadow.y == 6u ? cube_face(-l) : 0u);
    float texel = uintBitsToFloat(light.shadow.z) * dist;
    vec3 q = p + normal * (texel * SHADOW_NORMAL_OFFSET) + l * (texel * SHADOW_SUN_OFFSET);
    vec4 clip = frame.local_shadows.faces[face] * vec4(q, 1.0);
    if (clip.w <= 0.0) return 1.0;
    vec3 ndc = clip.xyz / clip.w;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    ivec2 size = textureSize(local_shadow_maps, 0).xy;
    vec2 step = 1.0 / vec2(size);
    float lit = 0.0;
    for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
            float w = float((2 - abs(x)) * (2 - abs(y)));
            lit += w * texture(local_shadow_maps, vec4(uv + vec2(x, y) * step, float(face), ndc.z));
        }
    }
    return lit / 16.0;
}

// The cascade that shades the eye-relative point `p` (-1: none).
int sun_cascade_of(vec3 p, vec3 normal) {
    vec3 map;
    return sun_shadow_cascade(p, normal, map);
}


#else

float sun_visibility(vec3 p, vec3 normal) { return 1.0; }
float local_light_visibility(GpuPointLight light, vec3 p, vec3 normal, vec3 l, float dist) { return 1.0; }
int sun_cascade_of(vec3 p, vec3 normal) { return -1; }

#endif

// The tint `DEBUG_VIEW_CASCADES` gives a pixel shaded by cascade `c` (-1: none).
vec3 cascade_tint(int c) {
    const vec3 tints[4] = vec3[](vec3(1.0, 0.35, 0.35), vec3(0.35, 1.0, 0.35), vec3(0.4, 0.5, 1.0), vec3(1.0, 1.0, 0.3));
    return c < 0 ? vec3(1.0) : tints[c];
}

#endif
