#version 460
// Instance cull, step 1 of 2 (BLOCK_STEP: the step before it where the scene has block bounds,
// decide_block below): each workgroup decides for its block of CULL_BLOCK slots whether
// this pass draws each (frustum, then optionally the Hi-Z occlusion test), and stores the
// decisions as bits and the block's survivor count, adds the count and the block's counters to
// its superblock's record, and each draw group's survivors to the group's count.
// `cull_compact.comp` then places the survivors and writes the commands.
//
// Subgroup operations only combine values (sums, ors), so nothing depends on the subgroup size
// or on how invocations map to subgroups.
//
// Variants (defines) select the phase and tests so that nothing branches on settings or binds
// unused resources. Phases: PHASE_ALL (every survivor), PHASE_EARLY (survivors among last
// frame's visible), PHASE_LATE (survivors that were not visible last frame; writes this frame's
// visibility bits), PHASE_OCCLUDERS (chosen occluders, frustum only), PHASE_REST (survivors
// that are not occluders). ATOMIC_APPEND is the thesis's atomic append, measured only.
// VISIBLE_OUT (late phase): also counts each block's and each draw group's visible slots, from
// which the compact step writes the list that the next frame's early phase draws.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
// The hiz_build pass stores chain levels from HIZ_FIRST_LEVEL (1) on: never test below it.
#define CULL_HIZ_MIN_LEVEL 1u

#include "../common/scene.glsl"
#include "../common/hiz.glsl"
#include "cull_common.glsl"
#include "../common/line_dispatch.glsl"

layout(local_size_x = 256) in;

// The records as 16-byte words, so each is read with two aligned vector loads.
layout(set = 0, binding = 0) readonly buffer Records { uvec4 record_words[]; };
CullRecord load_record(uint slot) {
    uvec4 a = record_words[2u * slot];
    uvec4 b = record_words[2u * slot + 1u];
    CullRecord r;
    r.center_hi = uintBitsToFloat(a.xyz);
    r.group_flags = a.w;
    r.lo_xy = b.x;
    r.lo_z_radius = b.y;
    r.half_xy = b.z;
    r.half_z = b.w;
    return r;
}
#ifdef MULTI_VIEW
#include "cull_views.glsl"
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 10, scalar) readonly buffer ViewTable { ViewBuffers view_table[]; };
// What deciding reads of each view's constants (ViewCull in src/passes/instance_cull/views.rs),
// as a uniform buffer: the views' loop index is the same in every invocation, so implementations
// can read these through their constant caches instead of once per invocation (the field names
// are FrameConstants', so `frame.x` below is the selected view's).
struct ViewCull {
    CullView cull_view;
    CullView prev_cull_view;
    vec4 eye_hi;
    vec4 eye_lo;
    vec4 prev_eye_hi;
    vec4 prev_eye_lo;
    CullView lod_view;
    vec4 lod_eye_offset;
};
layout(set = 0, binding = 11, scalar) uniform ViewCulls { ViewCull view_culls[MAX_CULL_VIEWS]; };
#define frame view_culls[g_view]
#ifdef LOD
layout(set = 0, binding = 12, scalar) readonly buffer LodLevels { LodLevel lod_levels[]; };
#endif
#ifdef HAS_HIZ
layout(set = 0, binding = 9) uniform sampler2D hiz_views[MAX_CULL_VIEWS];
// Each view's pyramid, indexed by constants (sampled-image arrays may not be indexed
// dynamically everywhere, lavapipe included).
#define HIZ_CASE(i) if (g_view == uint(i)) return texelFetch(hiz_views[i], t, mip).r;
float hiz_load(uint level, uvec2 texel) {
    ivec2 t = ivec2(texel);
    int mip = int(hiz_stored_mip(level));
    HIZ_CASE(0) HIZ_CASE(1) HIZ_CASE(2) HIZ_CASE(3) HIZ_CASE(4) HIZ_CASE(5) HIZ_CASE(6) HIZ_CASE(7)
    HIZ_CASE(8) HIZ_CASE(9) HIZ_CASE(10) HIZ_CASE(11) HIZ_CASE(12) HIZ_CASE(13) HIZ_CASE(14) HIZ_CASE(15)
    return 0.0;
}
#endif
#else
layout(set = 0, binding = 1, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
#ifdef ATOMIC_APPEND
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 5, scalar) buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 6, scalar) buffer Stats { CullStats stats; };
#else
layout(set = 0, binding = 4) buffer GroupCounts { uint group_counts[]; };
layout(set = 0, binding = 5) buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 6) writeonly buffer DrawBits { uint draw_bits[]; };
#endif
#ifdef HAS_VIS_PREV
layout(set = 0, binding = 7) readonly buffer VisPrev { uint vis_prev[]; };
#endif
#ifdef WRITE_VIS
layout(set = 0, binding = 8) writeonly buffer Vis { uint vis_now[]; };
#endif
#ifdef HAS_HIZ
layout(set = 0, binding = 9) uniform sampler2D hiz_tex;
float hiz_load(uint level, uvec2 texel) { return texelFetch(hiz_tex, ivec2(texel), int(hiz_stored_mip(level))).r; }
#endif
#ifdef LOD
layout(set = 0, binding = 12, scalar) readonly buffer LodLevels { LodLevel lod_levels[]; };
// Each slot's level of detail as LOD_PLANES bit planes of ceil(slots / 256) * 8 words each.
layout(set = 0, binding = 13) writeonly buffer LevelBits { uint level_bits[]; };
#endif
#ifdef BLOCK_BOUNDS
// One bound per block around all its slots' bounds (src/passes/shared/cull_blocks.rs), three
// 16-byte words: (center hi, slots with an instance), (center lo, flags), (half extents, 0).
layout(set = 0, binding = 14) readonly buffer BlockBounds { uvec4 block_words[]; };
// The blocks the block step leaves to the test step: [0..3) the test step's dispatch size (their
// number, 1, 1; the compact step zeroes the number for the next run), [3] unused, then the
// blocks, in no particular order, a word for every block of the scene.
layout(set = 0, binding = 15) buffer BlockList { uint block_list[]; };
#define BLOCK_LIST_FIRST 4u
#endif

#endif

layout(push_constant) uniform Push {
    uint slot_count;
    uint superblocks;          // ceil(blocks / CULL_SUPERBLOCK)
    uint group_count;          // VISIBLE_OUT: visible counts follow the survivor counts
    float occluder_distance;   // PHASE_OCCLUDERS/REST: farthest occluder center distance
    float occluder_size;       // smallest projected radius / view height
    uint occluder_triangles;   // meshes this cheap are candidates unflagged (0: flagged only)
    uint view_count;           // MULTI_VIEW: views in the table
    float lod_threshold;       // LOD: the largest error a level may show, in pixels
    uint block_test;           // BLOCK_BOUNDS: 1 where the scene has block bounds
} pc;

#ifdef MULTI_VIEW
// Each slot's decisions for every view, one bit per view: [0] drawn | visible now << 16,
// [1] evaluated | frustum-culled << 16, [2] occlusion-culled; and the slot's draw group.
shared uint mv_bits[3][CULL_BLOCK];
shared uint mv_group[CULL_BLOCK];
// Last frame's visibility words of the block, per view.
shared uint mv_prev[MAX_CULL_VIEWS][CULL_WORDS_PER_BLOCK];
// Per view and word: the set bits of drawn, visible now, evaluated, frustum-culled and
// occlusion-culled, a byte each (the last in .y).
shared uvec2 mv_pop[MAX_CULL_VIEWS][CULL_WORDS_PER_BLOCK];
#ifdef LOD
// Each slot's level for every view, four bits per view (views 8 apart share a bit position).
shared uint mv_levels[MAX_CULL_VIEWS / 8u][CULL_BLOCK];
// Per view, list (0: drawn, 1: visible) and level, the block's slots.
shared uint mv_level_counts[MAX_CULL_VIEWS][2][LOD_LEVELS];
#endif
#endif
shared uint sh_draw[CULL_WORDS_PER_BLOCK];
shared uint sh_vis[CULL_WORDS_PER_BLOCK];
shared uint sh_counts[4];
#ifdef LOD
shared uint sh_planes[LOD_PLANES][CULL_WORDS_PER_BLOCK];
// Per list (0: drawn, 1: visible) and level, the block's slots.
shared uint sh_level_counts[2][LOD_LEVELS];
#endif

// ORs `bits` into the shared word `arr[word]`: one atomic per subgroup when the subgroup's
// invocations share the word, one per invocation with bits otherwise (correct for any subgroup
// size and layout). Call in subgroup-uniform control flow.
#define OR_INTO_SHARED(arr, word, bits)                                   \
    if (subgroupAllEqual(word)) {                                         \
        uint or_bits_ = subgroupOr(bits);                                 \
        if (subgroupElect() && or_bits_ != 0u) atomicOr(arr[word], or_bits_); \
    } else if ((bits) != 0u) {                                            \
        atomicOr(arr[word], bits);                                        \
    }

#ifndef ATOMIC_APPEND
// Adds one survivor of `group` to its count, one atomic per distinct group in the subgroup:
// each round, the invocations whose group is the first remaining one count themselves from one
// ballot and the lowest of them adds the count. Exact however the implementation groups the
// invocations that run a round together (each invocation is counted by exactly one ballot).
// `counts` is the offset of the counts array in group_counts.
void count_group_survivor(uint group, uint counts) {
    for (;;) {
        uint first = subgroupBroadcastFirst(group);
        if (first == group) {
            uvec4 same = subgroupBallot(true);
            if (gl_SubgroupInvocationID == subgroupBallotFindLSB(same)) {
                atomicAdd(group_counts[counts + group], subgroupBallotBitCount(same));
            }
            break;
        }
    }
}
#endif

bool in_frustum(CullView view, vec3 c, float radius, vec3 half_extent) {
#ifdef NO_FRUSTUM
    return true;
#elif defined(BOUND_SPHERE)
    return cull_sphere_in_frustum(view, c, radius);
#else
    return cull_aabb_in_frustum(view, c - half_extent, c + half_extent);
#endif
}

// The bound's screen rectangle in `view` (see cull_project_*); `covers`: whether it may cover a
// sample position.
uint project_bound(CullView view, vec3 c, float radius, vec3 half_extent, out uvec4 rect, out float nearest,
                   out bool covers) {
#ifdef BOUND_SPHERE
    return cull_project_sphere(view, c, radius, rect, nearest, covers);
#else
    return cull_project_aabb(view, c - half_extent, c + half_extent, rect, nearest, covers);
#endif
}

#ifdef SMALL_OBJECTS
// Whether the bound is surely 4 pixels or more across on screen, so that it covers a sample
// position without being projected: its inscribed sphere (radius `inner`, centre at distance
// |c|) spans at least 2 * inner / |c| in tangent, and the projected rectangle contains that.
bool surely_large(CullView view, vec3 c, float inner) {
    float pixels = 0.5 * min(view.scale.x * float(view.viewport.x), view.scale.y * float(view.viewport.y));
    float across = view.orthographic != 0u ? 2.0 * inner : 2.0 * inner / length(c);
    return across * pixels >= 4.0;
}
#endif

#ifdef HAS_HIZ
// The Hi-Z test of a projected rectangle (`status` as cull_project_* returned it).
bool occluded_at(uint status, uvec4 rect, float nearest, CullView view) {
    // Crossing the near plane, or off screen in the view the pyramid was made with: visible.
    if (status != CULL_ON_SCREEN) return false;
#ifdef HIZ_FINER
    return cull_hiz_occluded(rect, nearest, view.viewport, true);
#else
    return cull_hiz_occluded(rect, nearest, view.viewport, false);
#endif
}

#ifdef HIZ_PREV_VIEW
// Against last frame's pyramid, in last frame's view.
bool occluded_prev(CullRecord r, float radius, vec3 half_extent) {
    CullView view = frame.prev_cull_view;
    vec3 c = rel_eye(r.center_hi, record_center_lo(r), frame.prev_eye_hi.xyz, frame.prev_eye_lo.xyz);
    uvec4 rect;
    float nearest;
    bool covers;
    uint status = project_bound(view, c, radius, half_extent, rect, nearest, covers);
    return occluded_at(status, rect, nearest, view);
}
#endif
#endif

#if defined(PHASE_OCCLUDERS) || defined(PHASE_REST)
// The thesis's local occluder choice: cheap (flagged as an occluder by the scene, or a mesh of
// at most occluder_triangles triangles), near, and large on screen. Deterministic, so
// PHASE_REST excludes exactly what PHASE_OCCLUDERS drew.
bool is_occluder(CullRecord r, vec3 c, float radius) {
    bool flagged = ((r.group_flags >> 24) & FLAG_OCCLUDER) != 0u;
    if (!flagged && groups[record_group(r)].index_count / 3u > pc.occluder_triangles) return false;
    float d = length(c);
    if (d > pc.occluder_distance + radius) return false;
    float size = radius / max(d, frame.cull_view.near) * frame.cull_view.scale.y * 0.5;
    return d <= radius || size >= pc.occluder_size;
}
#endif

#ifdef LOD
// The most pixels that one world unit of displacement anywhere in the bound's visible part can
// move on screen. Perspective: a displacement e at view depth z moves the projection by at most
// |(e.x + t.x e.z, e.y + t.y e.z)| * pixels / z, where t is the projected point's tangent
// (x/z, y/z); the matrix [1 0 t.x; 0 1 t.y] stretches by at most sqrt(1 + t.x^2 + t.y^2). Depth
// is at least the bound's nearest depth, and at least the near plane for any point that is
// drawn. The tangent's size is bounded twice, and the smaller bound holds: by the frustum (a
// visible point), and by the bound itself (its points are at most |center.xy| + radius off the
// view axis, at that least depth), which is what keeps a bound near the middle of the view from
// taking the corners' stretch.
float lod_pixels_per_unit(CullView view, vec3 c, float radius) {
    float pixels = 0.5 * max(view.scale.x * float(view.viewport.x), view.scale.y * float(view.viewport.y));
    if (view.orthographic != 0u) return pixels;
    vec3 v = cull_to_view(view.rotation, c);
    float depth = max(-v.z - radius, view.near);
    vec2 t = min((vec2(1.0) + abs(view.offset)) / view.scale, (abs(v.xy) + radius) / depth);
    return pixels * sqrt(1.0 + dot(t, t)) / depth;
}

// The coarsest level of `group`'s mesh whose error, projected conservatively, stays within the
// threshold (0: the full mesh). Levels' errors never decrease along the chain.
uint choose_level(CullView view, vec3 c, float radius, uint group) {
    DrawGroup g = groups[group];
    // Threshold 0 (set live on a pass built with levels): every mesh whole, as without levels.
    if (g.lod_count == 0u || pc.lod_threshold <= 0.0) return 0u;
    float per_error = radius * lod_pixels_per_unit(view, c, radius);
    uint level = 0u;
    for (uint l = 0u; l < min(g.lod_count, LOD_LEVELS - 1u); ++l) {
        // Not finite (a huge bound): false, so the full mesh.
        if (!(lod_levels[g.lod_first + l].relative_error * per_error <= pc.lod_threshold)) break;
        level = l + 1u;
    }
    return level;
}
#endif

// What the pass decided for one slot.
struct Decision {
    bool evaluated;
    bool frustum_culled;
    bool occlusion_culled;
    bool draw;
    bool visible_now;
    uint group;
    uint level;           // LOD: the level of detail it is drawn (or listed) at
};

Decision decide(CullRecord r, bool evaluated, bool was_visible) {
    Decision d;
    d.evaluated = evaluated;
    d.frustum_culled = false;
    d.occlusion_culled = false;
    d.draw = false;
    d.visible_now = false;
    d.group = 0u;
    d.level = 0u;
    if (!evaluated) return d;
    d.group = record_group(r);
    float radius = record_radius(r);
    vec3 half_extent = record_half_extent(r);
    vec3 c = rel_eye(r.center_hi, record_center_lo(r), frame.eye_hi.xyz, frame.eye_lo.xyz);
    bool huge = (r.group_flags & CULL_HUGE) != 0u;
    bool inside = huge || in_frustum(frame.cull_view, c, radius, half_extent);
    bool hidden = false;
#if defined(HAS_HIZ) && !defined(PHASE_OCCLUDERS) && !defined(HIZ_PREV_VIEW)
    // One projection in this frame's view serves the small-object and the Hi-Z tests.
    if (inside && !huge) {
        uvec4 rect;
        float nearest;
        bool covers;
        uint status = project_bound(frame.cull_view, c, radius, half_extent, rect, nearest, covers);
#ifdef SMALL_OBJECTS
        // A bound that covers no sample position makes no fragment: outside for every purpose.
        inside = status != CULL_ON_SCREEN || covers;
#endif
        hidden = inside && occluded_at(status, rect, nearest, frame.cull_view);
    }
#else
#ifdef SMALL_OBJECTS
#ifdef BOUND_SPHERE
    float inner = radius;
#else
    float inner = min(half_extent.x, min(half_extent.y, half_extent.z));
#endif
    if (inside && !huge && !surely_large(frame.cull_view, c, inner)) {
        uvec4 rect;
        float nearest;
        bool covers;
        uint status = project_bound(frame.cull_view, c, radius, half_extent, rect, nearest, covers);
        inside = status != CULL_ON_SCREEN || covers;
    }
#endif
#if defined(HAS_HIZ) && !defined(PHASE_OCCLUDERS)
    if (inside && !huge) hidden = occluded_prev(r, radius, half_extent);
#endif
#endif
    d.frustum_culled = !inside;
    d.occlusion_culled = inside && hidden;
    bool visible = inside && !hidden;
#if defined(PHASE_LATE)
    d.draw = visible && !was_visible;
    d.visible_now = visible;
#elif defined(PHASE_OCCLUDERS)
    d.draw = inside && is_occluder(r, c, radius);
#elif defined(PHASE_REST)
    d.draw = visible && !(inside && is_occluder(r, c, radius));
#else
    d.draw = visible;
#endif
#ifdef LOD
    if (d.draw || d.visible_now) d.level = choose_level(frame.lod_view, c + frame.lod_eye_offset.xyz, radius, d.group);
#endif
    return d;
}

#if defined(BLOCK_BOUNDS) && !defined(MULTI_VIEW)
// What a block's bound decides for all its slots at once.
#define BLOCK_TESTED 0u    // nothing: each slot is tested on its own
#define BLOCK_OUTSIDE 1u   // every slot is outside the frustum
#define BLOCK_OCCLUDED 2u  // every slot is inside the frustum and occluded
// How much stricter than a slot's frustum test the block's is, relative to the size of its
// coordinates (as CULL_REL_EPS is): far above the rounding of either test, so that a block
// decided here has every slot decided alike by its own test. The block's box already contains
// its slots' with room to spare; this keeps the plane tests' rounding out of it as well.
#define BLOCK_EXTRA (1.0 / 16384.0)

// Lowest n.p + w over the box (center, half).
float block_low(vec3 n, float w, vec3 center, vec3 half_extent) {
    precise float s = (cull_dot(n, center) - cull_dot(abs(n), half_extent)) + w;
    return s;
}

// Where the eye-relative box lies against the frustum's planes (those of
// cull_aabb_in_frustum): -1 wholly outside one of them, 1 wholly inside all of them, by
// BLOCK_EXTRA more than a slot's test allows either way; 0 otherwise.
int block_against_frustum(CullView view, vec3 center, vec3 half_extent) {
    precise float m = (CULL_REL_EPS + BLOCK_EXTRA) * (cull_l1(center) + cull_l1(half_extent));
    mat3 r = view.rotation;
    vec3 row0 = vec3(r[0].x, r[1].x, r[2].x);
    vec3 row1 = vec3(r[0].y, r[1].y, r[2].y);
    vec3 row2 = vec3(r[0].z, r[1].z, r[2].z);
    precise float sx = view.scale.x;
    precise float sy = view.scale.y;
    precise float cx = view.offset.x;
    precise float cy = view.offset.y;
    precise vec3 ax = row0 * sx;
    precise vec3 ay = row1 * sy;
    precise float wl = 1.0 - cx;
    precise float wr = 1.0 + cx;
    precise float wb = 1.0 - cy;
    precise float wt = 1.0 + cy;
    // Each plane's normal, offset and allowance: near, far, left, right, bottom, top.
    vec3 n[6];
    float w[6];
    float allow[6];
    n[0] = -row2; w[0] = -view.near; allow[0] = m;
    n[1] = row2; w[1] = view.far; allow[1] = m;
    if (view.orthographic == 0u) {
        n[2] = ax - row2 * wl; n[3] = -ax - row2 * wr; n[4] = ay - row2 * wb; n[5] = -ay - row2 * wt;
        w[2] = 0.0; w[3] = 0.0; w[4] = 0.0; w[5] = 0.0;
        allow[2] = m * sqrt(sx * sx + wl * wl);
        allow[3] = m * sqrt(sx * sx + wr * wr);
        allow[4] = m * sqrt(sy * sy + wb * wb);
        allow[5] = m * sqrt(sy * sy + wt * wt);
    } else {
        n[2] = ax; n[3] = -ax; n[4] = ay; n[5] = -ay;
        w[2] = wl; w[3] = wr; w[4] = wb; w[5] = wt;
        allow[2] = m * sx + CULL_REL_EPS * abs(cx);
        allow[3] = allow[2];
        allow[4] = m * sy + CULL_REL_EPS * abs(cy);
        allow[5] = allow[4];
    }
    bool inside = true;
    for (uint i = 0u; i < 6u; ++i) {
        if (cull_reach(n[i], w[i], center, half_extent) < -allow[i]) return -1;
        inside = inside && block_low(n[i], w[i], center, half_extent) > allow[i];
    }
    return inside ? 1 : 0;
}

// What block `block`'s bound decides for all its slots (BLOCK_*), in this frame's view.
uint block_outcome(uint block) {
    if (pc.block_test == 0u) return BLOCK_TESTED;
    uvec4 a = block_words[3u * block];
    uvec4 b = block_words[3u * block + 1u];
    uvec4 e = block_words[3u * block + 2u];
    // A block with a slot kept untested goes first: whatever else its bound says, that slot is
    // drawn. Then a block without an instance, with nothing to test or count.
    if ((b.w & BLOCK_TESTS_EVERY_SLOT) != 0u) return BLOCK_TESTED;
    if (a.w == 0u) return BLOCK_OUTSIDE;
    vec3 c = rel_eye(uintBitsToFloat(a.xyz), uintBitsToFloat(b.xyz), frame.eye_hi.xyz, frame.eye_lo.xyz);
    vec3 h = uintBitsToFloat(e.xyz);
    if (!cull_finite3(c - h) || !cull_finite3(c + h)) return BLOCK_TESTED;
    int against = block_against_frustum(frame.cull_view, c, h);
    if (against < 0) return BLOCK_OUTSIDE;
#if defined(HAS_HIZ) && !defined(PHASE_OCCLUDERS) && !defined(HIZ_PREV_VIEW) && !defined(SMALL_OBJECTS)
    // Wholly inside, every slot is projected and tested against the Hi-Z on its own; its
    // rectangle lies within the block's and its nearest depth is no nearer, so the texels it
    // reads (at the block's level or finer) are no nearer than those the block reads.
    if (against > 0) {
        uvec4 rect;
        float nearest;
        bool covers;
        uint status = cull_project_aabb(frame.cull_view, c - h, c + h, rect, nearest, covers);
        if (occluded_at(status, rect, nearest, frame.cull_view)) return BLOCK_OCCLUDED;
    }
#endif
    return BLOCK_TESTED;
}
#endif

#ifdef BLOCK_STEP
// The block step (before the test step, one invocation per block): a block whose bound decides
// all its slots gets what the test step would have written for it (no slot drawn or visible;
// its slots with an instance tested, and outside the frustum or occluded), and every other
// block is listed for the test step. Call in subgroup-uniform control flow.
void decide_block(uint block, uint run) {
    uint blocks = cull_blocks(pc.slot_count);
    bool listed = false;
    if (block < blocks) {
        uint outcome = block_outcome(block);
        listed = outcome == BLOCK_TESTED;
        if (!listed) {
            uint first_word = block * CULL_WORDS_PER_BLOCK;
            for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) draw_bits[first_word + w] = 0u;
#ifdef WRITE_VIS
            // The visibility buffer holds ceil(slots / 32) words; the last block may run past it.
            for (uint w = first_word; w < min(first_word + CULL_WORDS_PER_BLOCK, (pc.slot_count + 31u) / 32u); ++w) {
                vis_now[w] = 0u;
            }
#endif
#ifdef LOD
            for (uint p = 0u; p < LOD_PLANES; ++p) {
                for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) {
                    level_bits[p * blocks * CULL_WORDS_PER_BLOCK + first_word + w] = 0u;
                }
            }
            for (uint list = 0u; list < 2u; ++list) {
                for (uint level = 0u; level < LOD_LEVELS; ++level) {
                    scratch[scratch_level_block(pc.superblocks, pc.slot_count, list, block, level)] = 0u;
                }
            }
#endif
            scratch[scratch_block(pc.superblocks, block)] = 0u;
#ifdef VISIBLE_OUT
            scratch[scratch_visible_block(pc.superblocks, pc.slot_count, block)] = 0u;
#endif
            uint n = block_words[3u * block].w;
            if (n != 0u) {
                uint at = scratch_super(pc.superblocks, run, block / CULL_SUPERBLOCK);
                atomicAdd(scratch[at + SUPER_TESTED], n);
                atomicAdd(scratch[at + (outcome == BLOCK_OUTSIDE ? SUPER_FRUSTUM : SUPER_OCCLUSION)], n);
            }
        }
    }
    // One atomic per subgroup for the blocks it lists.
    uvec4 ballot = subgroupBallot(listed);
    uint count = subgroupBallotBitCount(ballot);
    uint first = 0u;
    if (subgroupElect() && count != 0u) first = atomicAdd(block_list[0], count);
    first = subgroupBroadcastFirst(first);
    if (listed) block_list[BLOCK_LIST_FIRST + first + subgroupBallotExclusiveBitCount(ballot)] = block;
}
#endif

#ifndef ATOMIC_APPEND
// Where a group's count at a level is in group_counts, for list 0 (drawn) or 1 (visible).
uint group_count_at(uint list, uint group, uint level) {
    return (list * LOD_LEVELS + level) * pc.group_count + group;
}
#endif

// Decides and records one block of slots for the one view (MULTI_VIEW: cull_views).
void cull_block(uint lane, uint block, uint slot) {
    if (lane < CULL_WORDS_PER_BLOCK) {
        sh_draw[lane] = 0u;
        sh_vis[lane] = 0u;
    }
    if (lane < 4u) sh_counts[lane] = 0u;
#ifdef LOD
    if (lane < LOD_PLANES * CULL_WORDS_PER_BLOCK) sh_planes[lane / CULL_WORDS_PER_BLOCK][lane % CULL_WORDS_PER_BLOCK] = 0u;
    if (lane < 2u * LOD_LEVELS) sh_level_counts[lane / LOD_LEVELS][lane % LOD_LEVELS] = 0u;
#endif
#ifndef ATOMIC_APPEND
    uint run = scratch[SCRATCH_TEST_RUN];
#endif

    // The loads and the decision come before the first barrier (it only orders the zeroing above
    // before the shared atomics below), so they start as early as they can.
    bool in_range = slot < pc.slot_count;
#ifdef HAS_VIS_PREV
    bool was_visible = in_range && ((vis_prev[slot >> 5] >> (slot & 31u)) & 1u) != 0u;
#else
    bool was_visible = false;
#endif
#ifdef PHASE_EARLY
    bool evaluated = was_visible;
#else
    bool evaluated = in_range;
#endif
    CullRecord r = CullRecord(vec3(0.0), 0u, 0u, 0u, 0u, 0u);
    if (evaluated) r = load_record(slot);
    // An empty slot is not tested: its visibility bit is written 0, so an instance that takes
    // the slot later inherits nothing.
    if (evaluated && record_empty(r)) evaluated = false;
    Decision d = decide(r, evaluated, was_visible);
    barrier();

    // Decision bits and counters: one shared atomic per subgroup and word or counter.
    uint word = lane >> 5u;
    uint bit = 1u << (lane & 31u);
#ifndef ATOMIC_APPEND
    OR_INTO_SHARED(sh_draw, word, d.draw ? bit : 0u)
    if (d.draw) count_group_survivor(group_count_at(0u, d.group, d.level), 0u);
#endif
#ifdef VISIBLE_OUT
    if (d.visible_now) count_group_survivor(group_count_at(1u, d.group, d.level), 0u);
#endif
#ifdef LOD
    for (uint p = 0u; p < LOD_PLANES; ++p) {
        OR_INTO_SHARED(sh_planes[p], word, ((d.level >> p) & 1u) != 0u ? bit : 0u)
    }
    if (d.draw) atomicAdd(sh_level_counts[0][d.level], 1u);
    if (d.visible_now) atomicAdd(sh_level_counts[1][d.level], 1u);
#endif
#ifdef WRITE_VIS
    OR_INTO_SHARED(sh_vis, word, d.visible_now ? bit : 0u)
#endif
    uvec4 counts = subgroupAdd(uvec4(d.evaluated, d.frustum_culled, d.occlusion_culled, d.visible_now));
    if (subgroupElect()) {
        for (uint i = 0u; i < 4u; ++i) {
            if (counts[i] != 0u) atomicAdd(sh_counts[i], counts[i]);
        }
    }
    barrier();

#ifdef WRITE_VIS
    if (lane < CULL_WORDS_PER_BLOCK) {
        // The visibility buffer holds ceil(slots / 32) words; the last block may run past it.
        uint vis_word = block * CULL_WORDS_PER_BLOCK + lane;
        if (vis_word < (pc.slot_count + 31u) / 32u) vis_now[vis_word] = sh_vis[lane];
    }
#endif

#ifdef ATOMIC_APPEND
    if (d.draw) {
        DrawGroup g = groups[d.group];
        uint index = atomicAdd(commands[d.group].instance_count, 1u);
        draw_ids[g.first_slot + index] = slot_instances[slot];
        uint tris = g.index_count / 3u;
        uint old = atomicAdd(stats.triangles_lo, tris);
        if (old + tris < old) atomicAdd(stats.triangles_hi, 1u);
        atomicAdd(stats.drawn, 1u);
    }
    if (lane == 0u) {
        if (sh_counts[0] != 0u) atomicAdd(stats.tested, sh_counts[0]);
        if (sh_counts[1] != 0u) atomicAdd(stats.frustum_culled, sh_counts[1]);
        if (sh_counts[2] != 0u) atomicAdd(stats.occlusion_culled, sh_counts[2]);
        if (sh_counts[3] != 0u) atomicAdd(stats.survivors, sh_counts[3]);
    }
#else
    if (lane < CULL_WORDS_PER_BLOCK) draw_bits[block * CULL_WORDS_PER_BLOCK + lane] = sh_draw[lane];
#ifdef LOD
    uint blocks = cull_blocks(pc.slot_count);
    if (lane < LOD_PLANES * CULL_WORDS_PER_BLOCK) {
        uint p = lane / CULL_WORDS_PER_BLOCK, w = lane % CULL_WORDS_PER_BLOCK;
        level_bits[p * blocks * CULL_WORDS_PER_BLOCK + block * CULL_WORDS_PER_BLOCK + w] = sh_planes[p][w];
    }
    if (lane < 2u * LOD_LEVELS) {
        uint list = lane / LOD_LEVELS, level = lane % LOD_LEVELS;
        uint n = sh_level_counts[list][level];
        scratch[scratch_level_block(pc.superblocks, pc.slot_count, list, block, level)] = n;
        uint at = scratch_super(pc.superblocks, run, block / CULL_SUPERBLOCK);
        if (n != 0u) atomicAdd(scratch[at + SUPER_LEVEL(list, level)], n);
    }
#endif
    if (lane == 0u) {
        uint count = 0u;
        for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) count += bitCount(sh_draw[w]);
        scratch[scratch_block(pc.superblocks, block)] = count;
#ifdef VISIBLE_OUT
        uint visible = 0u;
        for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) visible += bitCount(sh_vis[w]);
        scratch[scratch_visible_block(pc.superblocks, pc.slot_count, block)] = visible;
#endif
        uint at = scratch_super(pc.superblocks, run, block / CULL_SUPERBLOCK);
        if (count != 0u) atomicAdd(scratch[at + SUPER_SURVIVORS], count);
        if (sh_counts[0] != 0u) atomicAdd(scratch[at + SUPER_TESTED], sh_counts[0]);
        if (sh_counts[1] != 0u) atomicAdd(scratch[at + SUPER_FRUSTUM], sh_counts[1]);
        if (sh_counts[2] != 0u) atomicAdd(scratch[at + SUPER_OCCLUSION], sh_counts[2]);
        if (sh_counts[3] != 0u) atomicAdd(scratch[at + SUPER_VISIBLE], sh_counts[3]);
        // Nothing reads this word in this dispatch: the compact step's copy of the run number.
        if (block == 0u) scratch[SCRATCH_PLACE_RUN] = run;
    }
#endif
}

#ifdef MULTI_VIEW
// The group of a lane past the last slot.
#define NO_GROUP 0xFFFFFFFFu

// Adds the set bits of `bits` (word `w` of the block) to their draw groups' counts at
// `counts`: one atomic per group the word holds (slots are sorted by group, so usually one).
void count_word_groups(uint w, uint bits, uint counts) {
    uint first = mv_group[w * 32u];
    if (first == mv_group[w * 32u + 31u]) {
        atomicAdd(group_counts[counts + first], bitCount(bits));
        return;
    }
    while (bits != 0u) {
        uint j = findLSB(bits);
        uint g = mv_group[w * 32u + j];
        uint same = 0u;
        for (uint k = j; k < 32u && mv_group[w * 32u + k] == g; ++k) same |= 1u << k;
        atomicAdd(group_counts[counts + g], bitCount(bits & same));
        bits &= ~same;
    }
}

// Tests the block's slots against every view. Each record is read once; every invocation keeps its slot's decisions as one bit per view,
// and after one barrier the views' words are gathered from those bits, 8 invocations per view
// (no per-view subgroup operations, whatever the view decided), then one invocation per view
// writes its block record.
void cull_views(uint lane, uint block, uint slot) {
    uint n = pc.view_count;
#ifdef HAS_VIS_PREV
    if (lane < n * CULL_WORDS_PER_BLOCK) {
        uint v = lane / CULL_WORDS_PER_BLOCK;
        uint w = lane % CULL_WORDS_PER_BLOCK;
        select_view_buffers(view_table[v], v);
        uint word = block * CULL_WORDS_PER_BLOCK + w;
        mv_prev[v][w] = word < (pc.slot_count + 31u) / 32u ? vis_prev[word] : 0u;
    }
#endif
#ifdef LOD
    if (lane < n * 2u * LOD_LEVELS) mv_level_counts[lane / (2u * LOD_LEVELS)][(lane / LOD_LEVELS) % 2u][lane % LOD_LEVELS] = 0u;
    uint levels[MAX_CULL_VIEWS / 8u];
    for (uint i = 0u; i < MAX_CULL_VIEWS / 8u; ++i) levels[i] = 0u;
#endif
    bool in_range = slot < pc.slot_count;
    CullRecord r = CullRecord(vec3(0.0), 0u, 0u, 0u, 0u, 0u);
    if (in_range) r = load_record(slot);
    bool empty = in_range && record_empty(r);
    barrier();

    uint drawn_visible = 0u, evaluated_frustum = 0u, occlusion = 0u;
    for (uint v = 0u; v < n; ++v) {
        g_view = v;
#ifdef HAS_VIS_PREV
        bool was_visible = in_range && ((mv_prev[v][lane >> 5u] >> (lane & 31u)) & 1u) != 0u;
#else
        bool was_visible = false;
#endif
#ifdef PHASE_EARLY
        bool evaluated = was_visible && !empty;
#else
        bool evaluated = in_range && !empty;
#endif
        Decision d = decide(r, evaluated, was_visible);
        drawn_visible |= (d.draw ? 1u << v : 0u) | (d.visible_now ? 0x10000u << v : 0u);
        evaluated_frustum |= (d.evaluated ? 1u << v : 0u) | (d.frustum_culled ? 0x10000u << v : 0u);
        occlusion |= d.occlusion_culled ? 1u << v : 0u;
#ifdef LOD
        levels[v / 8u] |= d.level << (4u * (v % 8u));
#endif
    }
#ifdef LOD
    for (uint i = 0u; i < MAX_CULL_VIEWS / 8u; ++i) mv_levels[i][lane] = levels[i];
#endif
    mv_bits[0][lane] = drawn_visible;
    mv_bits[1][lane] = evaluated_frustum;
    mv_bits[2][lane] = occlusion;
    // Past the last slot, no group: a word that ends the scene is then never taken for one
    // group's word (`count_word_groups`) because its first slot's group is group 0.
    mv_group[lane] = in_range ? record_group(r) : NO_GROUP;
    barrier();

    // Word w of view v, gathered from the 32 slots' bits (the start rotated by w so that the
    // invocations of one view read different banks).
    if (lane < n * CULL_WORDS_PER_BLOCK) {
        uint v = lane / CULL_WORDS_PER_BLOCK;
        uint w = lane % CULL_WORDS_PER_BLOCK;
        uint draw = 0u, visible = 0u, evaluated = 0u, frustum = 0u, occluded = 0u;
#ifdef LOD
        uint planes[LOD_PLANES];
        for (uint p = 0u; p < LOD_PLANES; ++p) planes[p] = 0u;
#endif
        for (uint i = 0u; i < 32u; ++i) {
            uint j = (i + w) & 31u;
            uint k = w * 32u + j;
            uint a = mv_bits[0][k], b = mv_bits[1][k], c = mv_bits[2][k];
            draw |= ((a >> v) & 1u) << j;
            visible |= ((a >> (16u + v)) & 1u) << j;
            evaluated |= ((b >> v) & 1u) << j;
            frustum |= ((b >> (16u + v)) & 1u) << j;
            occluded |= ((c >> v) & 1u) << j;
#ifdef LOD
            uint level = (mv_levels[v / 8u][k] >> (4u * (v % 8u))) & 0xFu;
            for (uint p = 0u; p < LOD_PLANES; ++p) planes[p] |= ((level >> p) & 1u) << j;
#endif
        }
        select_view_buffers(view_table[v], v);
        draw_bits[block * CULL_WORDS_PER_BLOCK + w] = draw;
#ifdef WRITE_VIS
        // The visibility buffer holds ceil(slots / 32) words; the last block may run past it.
        uint vis_word = block * CULL_WORDS_PER_BLOCK + w;
        if (vis_word < (pc.slot_count + 31u) / 32u) vis_now[vis_word] = visible;
#endif
#ifdef LOD
        uint blocks = cull_blocks(pc.slot_count);
        for (uint p = 0u; p < LOD_PLANES; ++p) {
            level_bits[p * blocks * CULL_WORDS_PER_BLOCK + block * CULL_WORDS_PER_BLOCK + w] = planes[p];
        }
        // Each level's slots of the word, counted per group and per level as the single view's
        // test counts them.
        for (uint level = 0u; level < LOD_LEVELS; ++level) {
            uint mask = ~0u;
            for (uint p = 0u; p < LOD_PLANES; ++p) mask &= ((level >> p) & 1u) != 0u ? planes[p] : ~planes[p];
            uint drawn_at = draw & mask, visible_at = visible & mask;
            if (drawn_at != 0u) {
                count_word_groups(w, drawn_at, level * pc.group_count);
                atomicAdd(mv_level_counts[v][0][level], bitCount(drawn_at));
            }
            if (visible_at != 0u) {
#ifdef VISIBLE_OUT
                count_word_groups(w, visible_at, (LOD_LEVELS + level) * pc.group_count);
#endif
                atomicAdd(mv_level_counts[v][1][level], bitCount(visible_at));
            }
        }
#else
        if (draw != 0u) count_word_groups(w, draw, 0u);
#ifdef VISIBLE_OUT
        if (visible != 0u) count_word_groups(w, visible, pc.group_count);
#endif
#endif
        mv_pop[v][w] = uvec2(bitCount(draw) | bitCount(visible) << 8u | bitCount(evaluated) << 16u
                                 | bitCount(frustum) << 24u,
                             bitCount(occluded));
    }
    barrier();

    // The views' block records, one invocation per view.
    if (lane < n) {
        uint v = lane;
        select_view_buffers(view_table[v], v);
        uvec4 sums = uvec4(0u);
        uint occluded = 0u;
        for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) {
            uvec2 p = mv_pop[v][w];
            sums += (uvec4(p.x) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu;
            occluded += p.y;
        }
        uint count = sums.x;
        uint run = scratch[SCRATCH_TEST_RUN];
        scratch[scratch_block(pc.superblocks, block)] = count;
#ifdef VISIBLE_OUT
        scratch[scratch_visible_block(pc.superblocks, pc.slot_count, block)] = sums.y;
#endif
        uint at = scratch_super(pc.superblocks, run, block / CULL_SUPERBLOCK);
        if (count != 0u) atomicAdd(scratch[at + SUPER_SURVIVORS], count);
        if (sums.z != 0u) atomicAdd(scratch[at + SUPER_TESTED], sums.z);
        if (sums.w != 0u) atomicAdd(scratch[at + SUPER_FRUSTUM], sums.w);
        if (occluded != 0u) atomicAdd(scratch[at + SUPER_OCCLUSION], occluded);
        if (sums.y != 0u) atomicAdd(scratch[at + SUPER_VISIBLE], sums.y);
        // Nothing reads this word in this dispatch: the compact step's copy of the run number.
        if (block == 0u) scratch[SCRATCH_PLACE_RUN] = run;
    }
#ifdef LOD
    // The views' per-level counts of the block, one invocation per view, list and level.
    if (lane < n * 2u * LOD_LEVELS) {
        uint v = lane / (2u * LOD_LEVELS);
        uint list = (lane / LOD_LEVELS) % 2u, level = lane % LOD_LEVELS;
        select_view_buffers(view_table[v], v);
        uint count = mv_level_counts[v][list][level];
        scratch[scratch_level_block(pc.superblocks, pc.slot_count, list, block, level)] = count;
        uint at = scratch_super(pc.superblocks, scratch[SCRATCH_TEST_RUN], block / CULL_SUPERBLOCK);
        if (count != 0u) atomicAdd(scratch[at + SUPER_LEVEL(list, level)], count);
    }
#endif
}
#endif

void main() {
    uint lane = gl_LocalInvocationIndex;
#ifdef BLOCK_STEP
    uint run = scratch[SCRATCH_TEST_RUN];
    uint block = line_workgroup() * gl_WorkGroupSize.x + lane;
    // The test step may not run block 0 to hand the run number on.
    if (block == 0u) scratch[SCRATCH_PLACE_RUN] = run;
    decide_block(block, run);
#else
    uint block = line_workgroup();
#if defined(BLOCK_BOUNDS) && !defined(MULTI_VIEW)
    // Where the scene has block bounds, workgroup w tests the w-th block the block step listed.
    // Dispatched with the listed number where there are many blocks, else with a workgroup per
    // block (`listed_dispatch` in src/passes/instance_cull/mod.rs); the entry and the number
    // are loaded at once.
    if (pc.block_test != 0u) {
        uint entry = block < cull_blocks(pc.slot_count) ? block_list[BLOCK_LIST_FIRST + block] : 0u;
        if (block >= block_list[0]) return;
        block = entry;
    }
#endif
    // Past the last block of the line (the whole workgroup, before any barrier).
    if (block >= cull_blocks(pc.slot_count)) return;
    uint slot = block * CULL_BLOCK + lane;
#ifdef MULTI_VIEW
    cull_views(lane, block, slot);
#else
    cull_block(lane, block, slot);
#endif
#endif
}
