#version 460
// Tints the lit image: reads it through a sampler, writes a tinted copy.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D dst;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    vec4 c = texelFetch(src, p, 0);
    imageStore(dst, p, vec4(c.rgb * vec3(1.0, 0.85, 0.7), c.a));
}
