#version 460
// One depth per pixel from a multisampled (or single-sample) depth image, for an engine's
// post-processing: the nearest sample, which with reversed-Z is the largest value. The nearest
// is what a TAA or depth-of-field pass expects of an edge pixel (the foreground's silhouette
// keeps its depth; an average would invent a depth between the two surfaces). Background
// samples are 0 (the infinite far plane), so a pixel is 0 only where every sample is sky.
layout(local_size_x = 16, local_size_y = 16) in;

#ifndef SAMPLES
#define SAMPLES 1
#endif
#if SAMPLES > 1
layout(set = 0, binding = 0) uniform sampler2DMS depth_tex;
#else
layout(set = 0, binding = 0) uniform sampler2D depth_tex;
#endif
layout(set = 0, binding = 1, r32f) uniform writeonly image2D out_depth;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(out_depth)))) return;
    float nearest = 0.0;
    for (int s = 0; s < SAMPLES; ++s) {
#if SAMPLES > 1
        nearest = max(nearest, texelFetch(depth_tex, pixel, s).r);
#else
        nearest = max(nearest, texelFetch(depth_tex, pixel, 0).r);
#endif
    }
    imageStore(out_depth, pixel, vec4(nearest));
}
