// Hi-Z pyramid in one dispatch (AMD single-pass-downsampler style, conservative for any size).
//
// Every level is a min over an axis-aligned block of level 0: texel x of level k covers level-0
// columns [x << k, (x + 1) << k), except the last texel of a level, which runs to the end of the
// row (the halving folds the dropped column into it, see common/hiz.glsl). So the pyramid is a
// tree, and the level-6 texels split it into independent subtrees: workgroup g owns the subtree
// of level-6 texel g, i.e. level-k texels [g << (6 - k), (g + 1) << (6 - k)) - a 64x64 level-0
// tile - except that the last workgroup column/row owns up to the level's end (tiles of 64..127
// texels: the folded columns/rows stay inside the tile that reduces them; no halo, no
// neighbour reads). Each workgroup (16x16 threads striding over the tile's texels of a level)
// writes levels 0..6 of its tile (level 0 from the depth, min over samples, on the way to level
// 1; levels 2..6 through shared memory), and the last workgroup to finish (a global atomic
// counter the pass clears before the dispatch) reduces levels 7.. from level 6.
//
// Memory model (GLSL450 model, GL_KHR_memory_scope_semantics): a tile's level-6 texel is stored
// to a coherent image, released at device scope by a control barrier and by the counter's
// acquire-release atomicAdd; the last workgroup acquires through the same atomic and a control
// barrier before its coherent loads of level 6.
#version 460
#extension GL_KHR_memory_scope_semantics : require
#include "common/hiz.glsl"

layout(local_size_x = 16, local_size_y = 16) in;  // 256 threads; any subgroup size

#ifdef HIZ_MSAA
layout(binding = 0) uniform sampler2DMS depth_tex;
#else
layout(binding = 0) uniform sampler2D depth_tex;
#endif
layout(binding = 1) coherent buffer Counter { uint tiles_done; };
// One storage image per mip (binding 2 + level); mips the image lacks are bound to its last mip
// and never touched.
layout(binding = 2, r32f) uniform coherent image2D mip0;
layout(binding = 3, r32f) uniform coherent image2D mip1;
layout(binding = 4, r32f) uniform coherent image2D mip2;
layout(binding = 5, r32f) uniform coherent image2D mip3;
layout(binding = 6, r32f) uniform coherent image2D mip4;
layout(binding = 7, r32f) uniform coherent image2D mip5;
layout(binding = 8, r32f) uniform coherent image2D mip6;
layout(binding = 9, r32f) uniform coherent image2D mip7;
layout(binding = 10, r32f) uniform coherent image2D mip8;
layout(binding = 11, r32f) uniform coherent image2D mip9;
layout(binding = 12, r32f) uniform coherent image2D mip10;
layout(binding = 13, r32f) uniform coherent image2D mip11;
layout(binding = 14, r32f) uniform coherent image2D mip12;
layout(binding = 15, r32f) uniform coherent image2D mip13;
layout(binding = 16, r32f) uniform coherent image2D mip14;
layout(binding = 17, r32f) uniform coherent image2D mip15;

layout(push_constant) uniform Push {
    uvec2 base;    // level-0 size (the depth's)
    uint levels;   // mips to write, 1 ..= hiz_level_count(base)
    uint samples;  // depth samples per pixel
};

const uint SIDE = 16u;           // threads per axis
const uint TILE_LEVEL = 6u;       // a workgroup owns the subtree of one level-6 texel
#define FAR_INIT uintBitsToFloat(0x7F800000u)  // +inf: min identity

// Levels 1..6 of the tile: odd levels in s_odd (level 1 <= 63x63, 3 <= 15x15, 5 <= 3x3), even
// levels in s_even (2 <= 31x31, 4 <= 7x7, 6: 1x1). Level k is read while k + 1 is written.
shared float s_odd[64 * 64];
shared float s_even[32 * 32];
shared bool s_last;

void store_mip(uint level, ivec2 p, float v) {
    switch (level) {
        case 0u: imageStore(mip0, p, vec4(v)); break;
        case 1u: imageStore(mip1, p, vec4(v)); break;
        case 2u: imageStore(mip2, p, vec4(v)); break;
        case 3u: imageStore(mip3, p, vec4(v)); break;
        case 4u: imageStore(mip4, p, vec4(v)); break;
        case 5u: imageStore(mip5, p, vec4(v)); break;
        case 6u: imageStore(mip6, p, vec4(v)); break;
        case 7u: imageStore(mip7, p, vec4(v)); break;
        case 8u: imageStore(mip8, p, vec4(v)); break;
        case 9u: imageStore(mip9, p, vec4(v)); break;
        case 10u: imageStore(mip10, p, vec4(v)); break;
        case 11u: imageStore(mip11, p, vec4(v)); break;
        case 12u: imageStore(mip12, p, vec4(v)); break;
        case 13u: imageStore(mip13, p, vec4(v)); break;
        case 14u: imageStore(mip14, p, vec4(v)); break;
        default: imageStore(mip15, p, vec4(v)); break;
    }
}

// Levels read back: 6 (written by every workgroup) and above (by the last one).
float load_mip(uint level, ivec2 p) {
    switch (level) {
        case 6u: return imageLoad(mip6, p).r;
        case 7u: return imageLoad(mip7, p).r;
        case 8u: return imageLoad(mip8, p).r;
        case 9u: return imageLoad(mip9, p).r;
        case 10u: return imageLoad(mip10, p).r;
        case 11u: return imageLoad(mip11, p).r;
        case 12u: return imageLoad(mip12, p).r;
        case 13u: return imageLoad(mip13, p).r;
        default: return imageLoad(mip14, p).r;
    }
}

// Farthest (minimum) depth over the samples of pixel p.
float depth_min(ivec2 p) {
#ifdef HIZ_MSAA
    float v = texelFetch(depth_tex, p, 0).r;
    for (int s = 1; s < int(samples); ++s) v = min(v, texelFetch(depth_tex, p, s).r);
    return v;
#else
    return texelFetch(depth_tex, p, 0).r;
#endif
}

// Level-k texels [tile_lo, tile_hi) of the subtree of level-6 texel g (n of them per axis).
uvec2 tile_lo(uvec2 g, uint k) {
    return g << (TILE_LEVEL - k);
}
uvec2 tile_hi(uvec2 g, uvec2 n, uint k) {
    return mix((g + 1u) << (TILE_LEVEL - k), hiz_level_size(base, k), equal(g, n - 1u));
}

// Level K of the tile from level K - 1 in shared array SRC (row stride SRC_STRIDE), into mip
// image MIP and shared array DST (row stride DST_STRIDE). A macro so that the level, the image
// and the arrays are constants (no switch on the level, no array copies).
#define REDUCE_TILE_LEVEL(K, SRC, SRC_STRIDE, MIP, DST, DST_STRIDE)                                    \
    if (K <= tile_top) {                                                                            \
        barrier(); /* level K - 1 complete in shared memory, level K - 2 no longer read */          \
        uvec2 src_lo = tile_lo(g, K - 1u);                                                          \
        uvec2 src_size = hiz_level_size(base, K - 1u);                                              \
        uvec2 lo = tile_lo(g, K);                                                                   \
        uvec2 cnt = tile_hi(g, n, K) - lo;                                                          \
        for (uint ly = tid.y; ly < cnt.y; ly += SIDE) {                                             \
            for (uint lx = tid.x; lx < cnt.x; lx += SIDE) {                                         \
                uvec2 first, count;                                                                 \
                hiz_footprint(lo + uvec2(lx, ly), src_size, first, count);                          \
                first -= src_lo;                                                                    \
                float v = FAR_INIT;                                                                 \
                for (uint y = 0u; y < count.y; ++y) {                                               \
                    for (uint x = 0u; x < count.x; ++x) {                                           \
                        v = min(v, SRC[(first.y + y) * SRC_STRIDE + first.x + x]);                  \
                    }                                                                               \
                }                                                                                   \
                imageStore(MIP, ivec2(lo + uvec2(lx, ly)), vec4(v));                                \
                DST[ly * DST_STRIDE + lx] = v;                                                      \
            }                                                                                       \
        }                                                                                           \
    }

void main() {
    uvec2 tid = gl_LocalInvocationID.xy;
    uvec2 n = hiz_level_size(base, TILE_LEVEL);
    uvec2 g = gl_WorkGroupID.xy;

    // Level 1 of the tile straight from the depth; each level-1 footprint is a disjoint block
    // of level 0, so level 0 is written on the way. (With a single level, the same loop writes
    // level 0 alone.)
    {
        uvec2 lo = tile_lo(g, 1u);
        uvec2 cnt = tile_hi(g, n, 1u) - lo;
        for (uint ly = tid.y; ly < cnt.y; ly += SIDE) {
            for (uint lx = tid.x; lx < cnt.x; lx += SIDE) {
                uvec2 first, count;
                hiz_footprint(lo + uvec2(lx, ly), base, first, count);
                float v;
                if (count == uvec2(2u)) {  // all but the edge texels: a plain 2x2 block
                    ivec2 p = ivec2(first);
                    float d00 = depth_min(p), d10 = depth_min(p + ivec2(1, 0));
                    float d01 = depth_min(p + ivec2(0, 1)), d11 = depth_min(p + ivec2(1, 1));
                    imageStore(mip0, p, vec4(d00));
                    imageStore(mip0, p + ivec2(1, 0), vec4(d10));
                    imageStore(mip0, p + ivec2(0, 1), vec4(d01));
                    imageStore(mip0, p + ivec2(1, 1), vec4(d11));
                    v = min(min(d00, d10), min(d01, d11));
                } else {
                    v = FAR_INIT;
                    for (uint y = 0u; y < count.y; ++y) {
                        for (uint x = 0u; x < count.x; ++x) {
                            ivec2 p = ivec2(first + uvec2(x, y));
                            float d = depth_min(p);
                            imageStore(mip0, p, vec4(d));
                            v = min(v, d);
                        }
                    }
                }
                if (levels > 1u) imageStore(mip1, ivec2(lo + uvec2(lx, ly)), vec4(v));
                s_odd[ly * 64u + lx] = v;
            }
        }
    }

    // Levels 2..6 of the tile through shared memory.
    uint tile_top = min(TILE_LEVEL, levels - 1u);
    REDUCE_TILE_LEVEL(2u, s_odd, 64u, mip2, s_even, 32u)
    REDUCE_TILE_LEVEL(3u, s_even, 32u, mip3, s_odd, 64u)
    REDUCE_TILE_LEVEL(4u, s_odd, 64u, mip4, s_even, 32u)
    REDUCE_TILE_LEVEL(5u, s_even, 32u, mip5, s_odd, 64u)
    REDUCE_TILE_LEVEL(6u, s_odd, 64u, mip6, s_even, 32u)
    if (levels <= TILE_LEVEL + 1u) return;  // no level above the tiles

    // Publish this tile's level-6 texel; the last tile to arrive reduces the rest.
    uint lid = gl_LocalInvocationIndex;
    controlBarrier(gl_ScopeWorkgroup, gl_ScopeDevice, gl_StorageSemanticsImage, gl_SemanticsAcquireRelease);
    if (lid == 0u) {
        uint before = atomicAdd(tiles_done, 1u, gl_ScopeDevice, gl_StorageSemanticsBuffer | gl_StorageSemanticsImage,
                                gl_SemanticsAcquireRelease);
        s_last = before == n.x * n.y - 1u;
    }
    controlBarrier(gl_ScopeWorkgroup, gl_ScopeDevice, gl_StorageSemanticsImage | gl_StorageSemanticsShared,
                   gl_SemanticsAcquireRelease);
    if (!s_last) return;

    // Levels 7.. by this workgroup alone, through the (coherent) image.
    for (uint k = TILE_LEVEL + 1u; k < levels; ++k) {
        uvec2 src_size = hiz_level_size(base, k - 1u);
        uvec2 size = hiz_level_size(base, k);
        for (uint ty = tid.y; ty < size.y; ty += SIDE) {
            for (uint tx = tid.x; tx < size.x; tx += SIDE) {
                uvec2 first, count;
                hiz_footprint(uvec2(tx, ty), src_size, first, count);
                float v = FAR_INIT;
                for (uint y = 0u; y < count.y; ++y) {
                    for (uint x = 0u; x < count.x; ++x) {
                        v = min(v, load_mip(k - 1u, ivec2(first + uvec2(x, y))));
                    }
                }
                store_mip(k, ivec2(tx, ty), v);
            }
        }
        controlBarrier(gl_ScopeWorkgroup, gl_ScopeWorkgroup, gl_StorageSemanticsImage, gl_SemanticsAcquireRelease);
    }
}
