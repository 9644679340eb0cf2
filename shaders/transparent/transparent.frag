#version 460
// Transparent (alphaMode BLEND) surfaces, drawn back to front after the lighting and blended
// over the lit image: forward-shaded with the lighting passes' model (sun through its shadows, every point light,
// sky ambient, occlusion, emission), tone-mapped and sRGB-encoded like their output, so the
// blend happens on the encoded values as the output stores them.
//
// Depth is tested here, against the opaque depth of every sample of the pixel (a multisampled
// depth when the method has one): the fragment's alpha is scaled by the share of samples it is
// in front of, so an opaque edge that crosses a transparent surface resolves as the lighting
// resolved it. Transparent surfaces write no depth and hide nothing from the culling.
//
// With VISIBILITY_ORACLE (src/oracle/visibility.rs) the same faces and the same depth test
// mark the instance seen instead of shading it: the oracle's transparent visibility is exactly
// what this pass draws.
#include "../common/material_surface.glsl"
#include "../common/shading.glsl"
#include "../common/emissive_occlusion.glsl"

layout(set = 0, binding = 2, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Lights { GpuPointLight lights[]; };
#include "../common/shadows.glsl"
#ifndef SAMPLES
#define SAMPLES 1
#endif
#if SAMPLES > 1
layout(set = 0, binding = 5) uniform sampler2DMS depth_tex;
#else
layout(set = 0, binding = 5) uniform sampler2D depth_tex;
#endif

layout(push_constant) uniform Settings { float exposure; } settings;

layout(location = 0) in vec3 in_normal;
layout(location = 1) flat in uint in_material;
layout(location = 2) flat in uint in_mirrored;
layout(location = 5) in vec2 in_uv;
layout(location = 6) in vec4 in_tangent;

#ifdef VISIBILITY_ORACLE
layout(location = 4) flat in uint in_instance;
layout(set = 0, binding = 6) writeonly buffer Seen { uint seen[]; };
#else
layout(location = 0) out vec4 out_color;
#endif

vec3 shade_every_light(Surface s) {
    vec3 v = -normalize(s.position);
    vec3 radiance = ambient_light(s, frame.ambient.rgb) + s.emissive;
    radiance += brdf_light(s, v, -frame.sun_direction.xyz, frame.sun_color.rgb) * sun_visibility(s.position, s.normal);
    for (uint i = 0u; i < frame.size_lights.z; ++i) {
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

void main() {
    vec2 dx = dFdx(in_uv), dy = dFdy(in_uv);
    GpuMaterial m = materials[in_material];
    bool front = gl_FrontFacing != (in_mirrored != 0u);
    // One-sided materials drop their back faces here: the sorted draws of mixed materials
    // share one cull mode.
    if (!front && (m.flags & MATERIAL_DOUBLE_SIDED) == 0u) discard;
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    uint in_front = 0u;
    for (int s = 0; s < SAMPLES; ++s) {
#if SAMPLES > 1
        float opaque = texelFetch(depth_tex, pixel, s).r;
#else
        float opaque = texelFetch(depth_tex, pixel, 0).r;
#endif
        if (gl_FragCoord.z >= opaque) in_front += 1u;   // reversed-Z: nearer is larger
    }
    if (in_front == 0u) discard;
#ifdef VISIBILITY_ORACLE
    seen[in_instance] = 1u;
    return;
#endif
    vec3 n = normalize(in_normal);
    if (!front) n = -n;
    MaterialSurface ms = material_surface(m, in_uv, dx, dy, n, in_tangent, front);
    vec2 ndc = gl_FragCoord.xy / vec2(frame.size_lights.xy) * 2.0 - 1.0;
    vec4 p = frame.inv_view_proj * vec4(ndc, gl_FragCoord.z, 1.0);
    Surface s;
    s.position = p.xyz / p.w;
    s.normal = ms.normal;
    s.albedo = ms.albedo;
    s.roughness = ms.roughness;
    s.metallic = ms.metallic;
    s.occlusion = ms.occlusion;
    s.emissive = ms.emissive;
    vec3 color = tonemap_aces(shade_every_light(s) * settings.exposure);
    float coverage = float(in_front) / float(SAMPLES);
#ifndef VISIBILITY_ORACLE
    out_color = vec4(encode_srgb(color), clamp(ms.alpha, 0.0, 1.0) * coverage);
#endif
}
