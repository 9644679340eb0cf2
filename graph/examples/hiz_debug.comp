#version 460
// Shows a Hi-Z pyramid: vertical band i of the output is level i, each pixel reading the texel
// that covers it (hiz_texel_of_pixel). Grey = reversed-Z depth on a log scale, brighter = nearer;
// black = nothing (depth 0, the infinitely far clear value).
#include "common/hiz.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D hiz;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D view;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(view);
    if (any(greaterThanEqual(p, size))) return;
    uint levels = uint(textureQueryLevels(hiz));
    uint level = min(uint(p.x) * levels / uint(size.x), levels - 1u);
    uvec2 base = uvec2(textureSize(hiz, 0));
    uvec2 t = hiz_texel_of_pixel(uvec2(p), level, hiz_level_size(base, level));
    float d = texelFetch(hiz, ivec2(t), int(level)).r;
    float g = d > 0.0 ? clamp(1.0 + log2(d) / 16.0, 0.0, 1.0) : 0.0;
    // A thin red line between bands.
    bool edge = level != min(uint(p.x + 1) * levels / uint(size.x), levels - 1u);
    imageStore(view, p, edge ? vec4(1.0, 0.0, 0.0, 1.0) : vec4(vec3(g), 1.0));
}
