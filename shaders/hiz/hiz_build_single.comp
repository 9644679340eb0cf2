// Hi-Z pyramid in one dispatch (AMD single-pass-downsampler style tiles, the levels above them
// merged with atomics; conservative for any size), stored from chain level 1
// (HIZ_FIRST_LEVEL): stored mip m = chain level m + 1, level 0 being the depth (min over
// samples), which is read once and never written.
//
// Every level is a min over an axis-aligned block of the depth: texel x of level k covers columns
// [x << k, (x + 1) << k), except the last texel of a level, which runs to the end of the row (the
// halving folds the dropped column into it, see common/hiz.glsl). So the pyramid is a tree, and
// the level-6 texels split it into independent subtrees: workgroup g owns the subtree of level-6
// texel g, i.e. level-k texels [g << (6 - k), (g + 1) << (6 - k)) - a 64x64 tile of the depth -
// except that the last workgroup column/row owns up to the level's end (tiles of 64..127
// pixels: the folded columns/rows stay inside the tile that reduces them; no halo, no neighbour
// reads). Workgroups are numbered from the far corner so that these heavier tiles start first.
//
// Levels 1 and 2 in registers: thread t of the 16x16 owns level-2 texel t of its tile (a 4x4
// block of the depth, 4..7 pixels wide at the right/bottom edge of the depth) and reads the block
// as 2x2 quads with textureGather (one instruction per level-1 texel; MSAA: texelFetch of every
// sample). Each quad's min is a level-1 texel of the "padded" pyramid - the plain power-of-two
// tree over the depth extended by clamp-to-edge - and the folded pyramid equals it except that
// the last texel of a level is the min of the padded texels s - 1 and s (s = the level's size:
// the padded texel s covers exactly the columns that the fold adds, and clamped duplicates only
// repeat the last column, which that texel covers anyway). Interior blocks therefore need no
// fold at all (4 gathers, 4 + 1 stores); the blocks on the last column/row of level 2 read a 8x8
// (clamped) block and apply the fold. Levels 3..6 of the tile level by level in shared memory
// (ping-pong, a barrier per level, a texel per thread reading at most 3x3: reducing level 6
// straight from level 2 would leave one thread reading 256..961 values in a row while the rest
// of the workgroup idles, a serial tail longer than the whole read of the depth).
//
// Levels 7.. in the same dispatch: each tile's level-6 texel is merged into the one texel of
// every higher level that contains it, with an atomicMin on its bits (non-negative floats order
// like their bits) in the coherent buffer `above`, by the tile's last thread, which stored
// nothing since level 2, so that its device-scope fence before the done counter has little more
// than these atomics to wait for. The tile that brings the counter to the tile count copies those
// levels into their mips and puts the buffer back to +inf and the counter to 0 for the next build
// (the pass fills it once, before the first). Not a one-workgroup second dispatch for levels 7..:
// that would wait for the whole tile dispatch to drain and then reduce the levels one after
// another on one SM; see src/passes/hiz_build.rs for the alternatives.
#version 460
#extension GL_EXT_control_flow_attributes : require
#include "common/hiz.glsl"

layout(local_size_x = 16, local_size_y = 16) in;  // 256 threads; no subgroup operations

#ifdef HIZ_MSAA
layout(binding = 0) uniform sampler2DMS depth_tex;
#else
layout(binding = 0) uniform sampler2D depth_tex;  // nearest, clamp to edge
#endif
// The tiles' done counter, then chain levels 7.. as the bits of their values, one level after
// another (row-major). 0 and +inf between builds.
layout(binding = 18) coherent buffer Above { uint done_tiles; uint above[]; };
// One storage image per stored mip (binding 2 + mip; mip m = chain level m + 1); mips the image
// lacks are bound to its last mip and never touched.
layout(binding = 2, r32f) uniform writeonly image2D mip0;
layout(binding = 3, r32f) uniform writeonly image2D mip1;
layout(binding = 4, r32f) uniform writeonly image2D mip2;
layout(binding = 5, r32f) uniform writeonly image2D mip3;
layout(binding = 6, r32f) uniform writeonly image2D mip4;
layout(binding = 7, r32f) uniform writeonly image2D mip5;
layout(binding = 8, r32f) uniform writeonly image2D mip6;
layout(binding = 9, r32f) uniform writeonly image2D mip7;
layout(binding = 10, r32f) uniform writeonly image2D mip8;
layout(binding = 11, r32f) uniform writeonly image2D mip9;
layout(binding = 12, r32f) uniform writeonly image2D mip10;
layout(binding = 13, r32f) uniform writeonly image2D mip11;
layout(binding = 14, r32f) uniform writeonly image2D mip12;
layout(binding = 15, r32f) uniform writeonly image2D mip13;
layout(binding = 16, r32f) uniform writeonly image2D mip14;
layout(binding = 17, r32f) uniform writeonly image2D mip15;

layout(push_constant) uniform Push {
    uvec2 base;    // chain level 0 size (the depth's)
    uint levels;   // stored mips to write (chain levels 1 ..= levels), 1 ..= max(1, hiz_level_count(base) - 1)
};
// Depth samples per pixel: a specialization constant, not a push constant, so that the driver
// can unroll the loop over them.
layout(constant_id = 0) const int HIZ_SAMPLES = 1;

const uint SIDE = 16u;         // threads per axis
const uint TILE_LEVEL = 6u;    // chain level: a workgroup owns the subtree of one level-6 texel
#define FAR_INIT uintBitsToFloat(0x7F800000u)  // +inf: min identity

// s_a: level 2 of the tile (<= 31x31, stride 32), then levels 3..6 alternate between s_b and s_a
// (same stride), level 6 ending in s_a[0]. 8 KB in all, kept that small on purpose: every extra
// KB of shared memory per workgroup lowers how many tiles an SM holds at once, and at 16 KB more
// an SM would hold fewer tiles than it has threads for.
shared float s_a[1024];
shared float s_b[1024];
shared bool s_last_tile;  // this tile finished last: it writes levels 7..

vec2 inv_base;  // 1 / base, for gather coordinates

void store_mip(uint mip, ivec2 p, float v) {
    switch (mip) {
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

// Texel q of padded chain level 1: the min over depth pixels 2q .. 2q + 1 per axis (clamped to
// the depth, so that beyond the edge it repeats the last row/column), over every sample.
float padded_l1(ivec2 q) {
#ifdef HIZ_FETCH
    ivec2 last = ivec2(base) - 1;
    ivec2 p0 = min(2 * q, last);
    ivec2 p1 = min(2 * q + 1, last);
    float a = min(texelFetch(depth_tex, p0, 0).r, texelFetch(depth_tex, ivec2(p1.x, p0.y), 0).r);
    float b = min(texelFetch(depth_tex, ivec2(p0.x, p1.y), 0).r, texelFetch(depth_tex, p1, 0).r);
    return min(a, b);
#elif defined(HIZ_MSAA)
    ivec2 last = ivec2(base) - 1;
    ivec2 p0 = min(2 * q, last);
    ivec2 p1 = min(2 * q + 1, last);
    float v = FAR_INIT;
    [[unroll]] for (int s = 0; s < HIZ_SAMPLES; ++s) {
        float a = min(texelFetch(depth_tex, p0, s).r, texelFetch(depth_tex, ivec2(p1.x, p0.y), s).r);
        float b = min(texelFetch(depth_tex, ivec2(p0.x, p1.y), s).r, texelFetch(depth_tex, p1, s).r);
        v = min(v, min(a, b));
    }
    return v;
#else
    // The corner shared by pixels 2q and 2q + 1 selects exactly that 2x2 quad (0.5 texel from any
    // other choice; the rounding of the coordinate is below 0.01 texel up to 32768 pixels).
    vec4 d = textureGather(depth_tex, (vec2(2 * q) + 1.0) * inv_base);
    return min(min(d.x, d.y), min(d.z, d.w));
#endif
}

// Level-2 texel t (s1, s2: sizes of chain levels 1 and 2): stores its level-1 texels (mip 0) and
// itself (mip 1, when stored) and returns its value.
//
// One code path for every block (lavapipe runs both sides of every branch, masked): the block's
// own 2x2 padded level-1 texels, then, on an axis where t is the last level-2 texel, the next 2
// padded texels too (8 pixels, clamped), each folded into the block's owned level-1 texel
// min(index, owned - 1). An interior block runs the loop once: 4 gathers, 4 stores.
float reduce_block(uvec2 t, uvec2 s1, uvec2 s2) {
    ivec2 q = ivec2(t * 2u);  // its first level-1 texel
    bvec2 edge = equal(t, s2 - 1u);
    // Level-1 texels the block owns per axis: 2, or up to the end of level 1 on the depth's last
    // level-2 column/row (2 or 3; 1 on a depth under 4 pixels).
    uvec2 owned = mix(uvec2(2u), s1 - 2u * t, edge);
    uvec2 last = owned - 1u;
    uvec2 parts = mix(uvec2(1u), uvec2(2u), edge);
    float acc[3][3];  // owned texel (i, j) in acc[j][i]
    [[unroll]] for (int j = 0; j < 3; ++j) {
        [[unroll]] for (int i = 0; i < 3; ++i) acc[j][i] = FAR_INIT;
    }
    for (uint part = 0u; part < parts.x * parts.y; ++part) {
        uvec2 o = 2u * uvec2(part % parts.x, part / parts.x);
        float v[4] = float[4](padded_l1(q + ivec2(o)), padded_l1(q + ivec2(o) + ivec2(1, 0)),
                              padded_l1(q + ivec2(o) + ivec2(0, 1)), padded_l1(q + ivec2(o) + ivec2(1, 1)));
        [[unroll]] for (int d = 0; d < 4; ++d) {
            uvec2 to = min(o + uvec2(d & 1, d >> 1), last);
            [[unroll]] for (int j = 0; j < 3; ++j) {
                [[unroll]] for (int i = 0; i < 3; ++i) {
                    if (to == uvec2(i, j)) acc[j][i] = min(acc[j][i], v[d]);
                }
            }
        }
    }
    float m = FAR_INIT;
    [[unroll]] for (int j = 0; j < 3; ++j) {
        [[unroll]] for (int i = 0; i < 3; ++i) {
            if (uint(i) < owned.x && uint(j) < owned.y) imageStore(mip0, q + ivec2(i, j), vec4(acc[j][i]));
            m = min(m, acc[j][i]);
        }
    }
    if (levels > 1u) imageStore(mip1, ivec2(t), vec4(m));
    return m;
}

// Level-k texels [tile_lo, tile_hi) of the subtree of level-6 texel g (n of them per axis).
uvec2 tile_lo(uvec2 g, uint k) {
    return g << (TILE_LEVEL - k);
}
uvec2 tile_hi(uvec2 g, uvec2 n, uint k) {
    return mix((g + 1u) << (TILE_LEVEL - k), hiz_level_size(base, k), equal(g, n - 1u));
}

// Chain level K (3..6) of the tile from its level K - 1 in SRC into DST (both stride 32) and
// mip MIP: the footprints of common/hiz.glsl in tile-local coordinates (the tile's level-K texels
// start at half its level-(K - 1) ones, and a fold never leaves the tile). At most 15x15 texels:
// one per thread. A macro so that the level, the arrays and the image are constants.
#define REDUCE_TILE_LEVEL(K, SRC, DST, MIP)                                                        \
    if (K <= top_level) {                                                                           \
        barrier();                                                                                  \
        uvec2 lo = tile_lo(g, K);                                                                   \
        uvec2 cnt = tile_hi(g, n, K) - lo;                                                          \
        uvec2 t = uvec2(lid % cnt.x, lid / cnt.x);                                                  \
        if (t.y < cnt.y) {                                                                          \
            uvec2 first, count;                                                                     \
            hiz_footprint(lo + t, hiz_level_size(base, K - 1u), first, count);                      \
            first -= 2u * lo;                                                                       \
            float v = FAR_INIT;                                                                     \
            for (uint y = 0u; y < count.y; ++y) {                                                   \
                for (uint x = 0u; x < count.x; ++x) v = min(v, SRC[(first.y + y) * 32u + first.x + x]); \
            }                                                                                       \
            imageStore(MIP, ivec2(lo + t), vec4(v));                                                \
            DST[t.y * 32u + t.x] = v;                                                               \
        }                                                                                           \
    }

// The bits that order a depth like its value for atomicMin: a non-negative float's own (anything
// else, which a depth never is, as 0: the farthest, so conservative).
uint depth_bits(float d) {
    return d > 0.0 ? floatBitsToUint(d) : 0u;
}

// Merges this tile's level-6 texel `v` into levels 7..levels (the texel of level k over level-6
// texel g is min(g >> (k - 6), size_k - 1): the folds put a dropped texel into the last one) and
// counts the tile done; true for the tile that finished last.
bool merge_above(uvec2 g, uvec2 n, float v) {
    uint bits = depth_bits(v);
    uint offset = 0u;
    for (uint k = TILE_LEVEL + 1u; k <= levels; ++k) {
        uvec2 size = hiz_level_size(base, k);
        uvec2 t = min(g >> (k - TILE_LEVEL), size - 1u);
        atomicMin(above[offset + t.y * size.x + t.x], bits);
        offset += size.x * size.y;
    }
    memoryBarrierBuffer();  // the merges before the count
    return atomicAdd(done_tiles, 1u) == n.x * n.y - 1u;
}

// The last tile: levels 7..levels from `above` into their mips, then `above` back to +inf and
// the counter to 0. Flat over the levels (3 load-store round trips at 3840x2160 instead of one
// per level and more).
void write_above(uint lid) {
    memoryBarrierBuffer();  // every tile's merges, seen through its count
    uint total = 0u;
    for (uint k = TILE_LEVEL + 1u; k <= levels; ++k) {
        uvec2 size = hiz_level_size(base, k);
        total += size.x * size.y;
    }
    for (uint i = lid; i < total; i += SIDE * SIDE) {
        // Entry i: texel `at` of chain level k.
        uint k = TILE_LEVEL + 1u;
        uint at = i;
        for (uvec2 size = hiz_level_size(base, k); at >= size.x * size.y; size = hiz_level_size(base, k)) {
            at -= size.x * size.y;
            ++k;
        }
        uvec2 size = hiz_level_size(base, k);
        store_mip(k - 1u, ivec2(at % size.x, at / size.x), uintBitsToFloat(above[i]));
        above[i] = floatBitsToUint(FAR_INIT);
    }
    if (lid == 0u) done_tiles = 0u;
}

void main() {
    uvec2 tid = gl_LocalInvocationID.xy;
    uint lid = gl_LocalInvocationIndex;
    uvec2 n = hiz_level_size(base, TILE_LEVEL);
    uvec2 g = n - 1u - gl_WorkGroupID.xy;  // edge tiles (up to 4x the pixels) first
    uint top_level = min(TILE_LEVEL, levels);  // highest chain level stored inside the tile
    inv_base = 1.0 / vec2(base);

    // Chain levels 1 and 2 from the depth; level 2 of the tile into s_a.
    uvec2 s2 = hiz_level_size(base, 2u);
    uvec2 lo2 = tile_lo(g, 2u);
    {
        uvec2 s1 = hiz_level_size(base, 1u);
        uvec2 cnt = tile_hi(g, n, 2u) - lo2;  // 16, up to 31 on edge tiles
        for (uint ly = tid.y; ly < cnt.y; ly += SIDE) {
            for (uint lx = tid.x; lx < cnt.x; lx += SIDE) {
                s_a[ly * 32u + lx] = reduce_block(lo2 + uvec2(lx, ly), s1, s2);
            }
        }
    }

    // Chain levels 3..6 of the tile, level by level (each starts with a barrier).
    REDUCE_TILE_LEVEL(3u, s_a, s_b, mip2)
    REDUCE_TILE_LEVEL(4u, s_b, s_a, mip3)
    REDUCE_TILE_LEVEL(5u, s_a, s_b, mip4)
    REDUCE_TILE_LEVEL(6u, s_b, s_a, mip5)

    // Chain levels 7.. (see above), merged by the tile's last thread (which stored nothing since
    // level 2) once level 6 is in s_a[0].
    if (levels > TILE_LEVEL) {
        barrier();
        if (lid == SIDE * SIDE - 1u) s_last_tile = merge_above(g, n, s_a[0]);
        barrier();
        if (s_last_tile) write_above(lid);
    }
}
