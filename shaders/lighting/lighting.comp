#version 460
// Deferred lighting in compute: one thread per pixel reads the G-buffer and depth, shades the
// sun, every point light and a sky ambient term, tone-maps and writes sRGB-encoded output.
#include "../common/scene.glsl"
#include "../common/shading.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D depth_tex;
layout(set = 0, binding = 1) uniform sampler2D albedo_metallic_tex;
layout(set = 0, binding = 2) uniform sampler2D normal_roughness_tex;
layout(set = 0, binding = 3, scalar) readonly buffer Frame { FrameConstants frame; };
layout(set = 0, binding = 4, scalar) readonly buffer Lights { GpuPointLight lights[]; };
layout(set = 0, binding = 5, rgba8) uniform writeonly image2D out_color;

layout(push_constant) uniform Settings {
    float exposure;
    uint debug_view;   // DEBUG_VIEW_*
} settings;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = frame.size_lights.xy;
    if (any(greaterThanEqual(uvec2(pixel), size))) return;

    vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
    float depth = texelFetch(depth_tex, pixel, 0).r;
    vec4 far_point = frame.inv_view_proj * vec4(ndc, 1e-6, 1.0);
    vec3 view_dir = normalize(far_point.xyz / far_point.w);

    vec3 color;
    if (depth <= 0.0) {
        color = sky_color(view_dir);
    } else {
        vec4 p = frame.inv_view_proj * vec4(ndc, depth, 1.0);
        vec4 am = texelFetch(albedo_metallic_tex, pixel, 0);
        vec4 nr = texelFetch(normal_roughness_tex, pixel, 0);
        Surface s;
        s.position = p.xyz / p.w;
        s.normal = normalize(nr.xyz);
        s.albedo = am.rgb;
        s.metallic = am.a;
        s.roughness = nr.a;
        vec3 v = -normalize(s.position);
        vec3 radiance = ambient_light(s, frame.ambient.rgb);
        radiance += brdf_light(s, v, -frame.sun_direction.xyz, frame.sun_color.rgb);
        uint light_count = frame.size_lights.z;
        for (uint i = 0; i < light_count; ++i) {
            vec3 to_light = lights[i].position_range.xyz - s.position;
            float dist = length(to_light);
            float range = lights[i].position_range.w;
            if (dist >= range) continue;
            vec3 l = to_light / max(dist, 1e-6);
            radiance += brdf_light(s, v, l, lights[i].color.rgb * light_falloff(dist, range));
        }
        color = radiance;
    }
    color = tonemap_aces(color * settings.exposure);
    uint debug_view = settings.debug_view;
    if (debug_view != DEBUG_VIEW_NONE && depth > 0.0) {
        if (debug_view == DEBUG_VIEW_NORMALS) color = normalize(texelFetch(normal_roughness_tex, pixel, 0).xyz) * 0.5 + 0.5;
        if (debug_view == DEBUG_VIEW_ALBEDO) color = texelFetch(albedo_metallic_tex, pixel, 0).rgb;
        if (debug_view == DEBUG_VIEW_DEPTH) color = vec3(fract(log2(depth) * 0.25));
        color = pow(color, vec3(2.2)); // shown as-is after the sRGB encode below
    }
    imageStore(out_color, pixel, vec4(linear_to_srgb(color), 1.0));
}
