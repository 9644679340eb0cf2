#version 460
// Temporal blend: mixes this frame's lit image with last frame's blended result.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D current;
layout(set = 0, binding = 1) uniform sampler2D previous;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D blended;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(blended)))) return;
    vec4 now = texelFetch(current, p, 0);
    vec4 before = texelFetch(previous, p, 0);
    imageStore(blended, p, mix(now, before, 0.5));
}
