#version 460
// Per texel, the absolute difference of two images' colors (tests/msaa.rs): 0 where they
// agree; alpha carries the texel of `marks` (red in its low bit, green in the next).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) uniform readonly image2D first;
layout(set = 0, binding = 1, rgba8) uniform readonly image2D second;
layout(set = 0, binding = 2, rgba8) uniform readonly image2D marks;
layout(set = 0, binding = 3, rgba8) uniform writeonly image2D difference;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(difference)))) return;
    vec4 m = imageLoad(marks, p) * 255.0;
    float flags = round(m.r) + 2.0 * round(m.g);
    imageStore(difference, p, vec4(abs(imageLoad(first, p).rgb - imageLoad(second, p).rgb), flags / 255.0));
}
