// Hi-Z pyramid, one dispatch per level (the baseline of hiz_build_single.comp), stored from chain
// level 1: stored mip m = chain level m + 1. With HIZ_FROM_DEPTH, chain level 1 (mip 0) straight
// from the depth: each texel the min over its footprint of depth pixels (2x2, 2x3, 3x2 or 3x3 at
// the odd edges, see common/hiz.glsl; 1 pixel on a unit axis) and over their samples with
// HIZ_MSAA; otherwise level k + 1 from level k, the same footprints. The pass puts a barrier on
// the written mip between dispatches.
#version 460
#extension GL_EXT_control_flow_attributes : require
#include "common/hiz.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef HIZ_FROM_DEPTH
#ifdef HIZ_MSAA
layout(binding = 0) uniform sampler2DMS depth_tex;
#else
layout(binding = 0) uniform sampler2D depth_tex;
#endif
#else
layout(binding = 0, r32f) uniform readonly image2D src_mip;
#endif
layout(binding = 1, r32f) uniform writeonly image2D dst_mip;

layout(push_constant) uniform Push {
    uvec2 src_size;  // size of the level read (the depth's for chain level 1)
    uvec2 dst_size;  // size of the level written
};
// Depth samples per pixel (HIZ_FROM_DEPTH with HIZ_MSAA), as in hiz_build_single.comp.
layout(constant_id = 0) const int HIZ_SAMPLES = 1;

// One texel of the source: the min over a pixel's samples, or a texel of the previous level.
float load_src(ivec2 p) {
#ifdef HIZ_FROM_DEPTH
    float v = texelFetch(depth_tex, p, 0).r;
#ifdef HIZ_MSAA
    [[unroll]] for (int s = 1; s < HIZ_SAMPLES; ++s) v = min(v, texelFetch(depth_tex, p, s).r);
#endif
    return v;
#else
    return imageLoad(src_mip, p).r;
#endif
}

void main() {
    uvec2 t = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(t, dst_size))) return;
    uvec2 first, count;
    hiz_footprint(t, src_size, first, count);
    float v = uintBitsToFloat(0x7F800000u);  // +inf: min identity
    for (uint y = 0u; y < count.y; ++y) {
        for (uint x = 0u; x < count.x; ++x) {
            v = min(v, load_src(ivec2(first + uvec2(x, y))));
        }
    }
    imageStore(dst_mip, ivec2(t), vec4(v));
}
