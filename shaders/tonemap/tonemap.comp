#version 460
// Tone mapping as a pass of its own: the lighting passes write linear HDR colour (RGBA16F, scene
// radiance before exposure); this pass scales it by the exposure, applies Narkowicz's ACES fit
// and writes the sRGB-encoded result into the 8-bit output. The curve and encoding are the ones
// the lighting passes applied in place before the HDR image existed.
#include "../common/tonemap.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

layout(set = 0, binding = 0) uniform sampler2D in_hdr;   // nearest, texelFetch only
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D out_color;

layout(push_constant) uniform Settings { float exposure; } settings;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(out_color)))) return;
    vec3 hdr = texelFetch(in_hdr, pixel, 0).rgb;
    imageStore(out_color, pixel, vec4(linear_to_srgb(tonemap_aces(hdr * settings.exposure)), 1.0));
}
