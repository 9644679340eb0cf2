#version 460
// Selective AA by depth-edge detection (paper 002 section 5): a pixel is an edge when its
// samples mix background and surface, or when their view depths differ by more than a relative
// threshold (reversed-Z depth is near / view depth, so the ratio of depths is the ratio of
// distances). Interior triangle edges of a continuous surface are not edges: the compressed
// G-buffer then keeps one block there.
layout(local_size_x = 8, local_size_y = 8) in;

#ifndef SAMPLES
#define SAMPLES 1
#endif
#if SAMPLES > 1
layout(set = 0, binding = 0) uniform sampler2DMS depth_tex;
#define DEPTH_AT(p, s) texelFetch(depth_tex, p, int(s)).r
#else
layout(set = 0, binding = 0) uniform sampler2D depth_tex;
#define DEPTH_AT(p, s) texelFetch(depth_tex, p, 0).r
#endif
layout(set = 0, binding = 1, r8ui) uniform writeonly uimage2D mask;

layout(push_constant) uniform Push { float threshold; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(mask)))) return;
    float lo = 1e30, hi = 0.0;
    uint background = 0u;
    for (uint s = 0u; s < SAMPLES; ++s) {
        float d = DEPTH_AT(p, s);
        if (d <= 0.0) {
            background += 1u;
        } else {
            lo = min(lo, d);
            hi = max(hi, d);
        }
    }
    bool mixed = background > 0u && background < SAMPLES;
    bool spread = background < SAMPLES && hi > lo * (1.0 + pc.threshold);
    imageStore(mask, p, uvec4(mixed || spread ? 1u : 0u));
}
