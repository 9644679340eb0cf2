#version 460
// Per texel, the absolute difference of two images (tests/msaa.rs): 0 where they agree.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) uniform readonly image2D first;
layout(set = 0, binding = 1, rgba8) uniform readonly image2D second;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D difference;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(difference)))) return;
    imageStore(difference, p, abs(imageLoad(first, p) - imageLoad(second, p)));
}
