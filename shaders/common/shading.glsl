// The shading model every lighting pass and baseline shares: Lambert diffuse plus GGX
// specular (Smith height-correlated visibility, Schlick Fresnel), ACES-fitted tone map, sRGB
// (tonemap.glsl).
#ifndef CULLGRAPH_SHADING_GLSL
#define CULLGRAPH_SHADING_GLSL

#include "tonemap.glsl"

const float PI = 3.14159265359;

struct Surface {
    vec3 position;   // eye-relative
    vec3 normal;     // unit
    vec3 albedo;
    float roughness;
    float metallic;
    float occlusion;   // ambient occlusion: scales the ambient term only (glTF)
    vec3 emissive;     // radiance the surface emits, added after the lights
};

float d_ggx(float n_dot_h, float a) {
    float a2 = a * a;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float v_smith_ggx(float n_dot_v, float n_dot_l, float a) {
    float a2 = a * a;
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-6);
}

// Outgoing radiance towards the eye from light arriving along `l` with radiance `radiance`.
vec3 brdf_light(Surface s, vec3 v, vec3 l, vec3 radiance) {
    float n_dot_l = dot(s.normal, l);
    if (n_dot_l <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + l);
    float n_dot_v = max(dot(s.normal, v), 1e-4);
    float n_dot_h = max(dot(s.normal, h), 0.0);
    float v_dot_h = max(dot(v, h), 0.0);
    float a = max(s.roughness * s.roughness, 2e-3);
    vec3 f0 = mix(vec3(0.04), s.albedo, s.metallic);
    vec3 f = f0 + (1.0 - f0) * pow(1.0 - v_dot_h, 5.0);
    vec3 specular = d_ggx(n_dot_h, a) * v_smith_ggx(n_dot_v, n_dot_l, a) * f;
    vec3 diffuse = (1.0 - f) * (1.0 - s.metallic) * s.albedo / PI;
    return (diffuse + specular) * radiance * n_dot_l;
}

// Smooth window: 1 near the light, exactly 0 at `range`.
float light_falloff(float dist, float range) {
    float x = dist / range;
    float w = clamp(1.0 - x * x * x * x, 0.0, 1.0);
    return w * w / (dist * dist + 1.0);
}

// Radiance a point or spot light sends to a surface `dist` away, `l` the unit direction from
// the surface to the light: the range window, and for a spot light (spot.w, the cos of its outer
// angle, at least -1) its cone as KHR_lights_punctual defines it, color.w being
// 1 / (cos inner - cos outer).
vec3 punctual_radiance(vec4 color, vec4 spot, vec3 l, float dist, float range) {
    vec3 radiance = color.rgb * light_falloff(dist, range);
    if (spot.w >= -1.0) {
        float t = clamp((dot(-l, spot.xyz) - spot.w) * color.w, 0.0, 1.0);
        radiance *= t * t;
    }
    return radiance;
}

vec3 ambient_light(Surface s, vec3 sky) {
    float up = s.normal.y * 0.5 + 0.5;
    vec3 hemi = mix(sky * 0.35, sky, up);
    return hemi * s.albedo * (1.0 - 0.5 * s.metallic) * s.occlusion;
}

vec3 sky_color(vec3 dir) {
    float t = clamp(dir.y * 0.5 + 0.5, 0.0, 1.0);
    return mix(vec3(0.55, 0.6, 0.68), vec3(0.18, 0.32, 0.62), t);
}

#endif
