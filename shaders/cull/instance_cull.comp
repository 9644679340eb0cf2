#version 460
// Instance cull, step 1 of 2: each workgroup decides for its block of CULL_BLOCK slots whether
// this pass draws each (frustum, then optionally the Hi-Z occlusion test), and stores the
// decisions as bits and the block's survivor count. The last workgroup to finish (an atomic
// done-counter; nobody waits for it) then does the pass's serial tail: the exclusive prefix sum
// of the block counts, each draw group's base (survivors before its first slot), the draw
// commands compacted in group order, the draw count and the counters. `cull_scatter.comp` then
// places the survivors. One dispatch and one barrier fewer than a separate commands step, which
// on a fast GPU costs more than the work itself.
//
// Memory model (GL_KHR_memory_scope_semantics): thread 0 of each workgroup stores the block's
// bits and count to coherent buffers and then bumps the counter with an acquire-release atomic
// at device scope; the last workgroup acquires through the same atomic and a device-scope
// control barrier before reading what the others stored, and puts the counter back to 0 for the
// pass's next run (the pass orders runs with a barrier).
//
// Variants (defines) select the phase and tests so that nothing branches on settings or binds
// unused resources. Phases: PHASE_ALL (every survivor), PHASE_EARLY (survivors among last
// frame's visible), PHASE_LATE (survivors that were not visible last frame; writes this frame's
// visibility bits), PHASE_OCCLUDERS (chosen occluders, frustum only), PHASE_REST (survivors
// that are not occluders). ATOMIC_APPEND is the thesis's atomic append, measured only.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_memory_scope_semantics : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// The hiz_build pass stores chain levels from HIZ_FIRST_LEVEL (1) on: never test below it.
#define CULL_HIZ_MIN_LEVEL 1u
#include "../common/scene.glsl"
#include "../common/hiz.glsl"
#include "cull_common.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) readonly buffer Records { CullRecord records[]; };
layout(set = 0, binding = 1, scalar) readonly buffer Frame { FrameConstants frame; };
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
#ifdef ATOMIC_APPEND
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 5, scalar) buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 6, scalar) buffer Stats { CullStats stats; };
#else
layout(set = 0, binding = 5) coherent buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 6) coherent buffer DrawBits { uint draw_bits[]; };
layout(set = 0, binding = 10) writeonly buffer GroupBase { uint group_base[]; };
layout(set = 0, binding = 11, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 12) writeonly buffer DrawCount { uint draw_count; };
layout(set = 0, binding = 13, scalar) writeonly buffer Stats { CullStats stats; };
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

layout(push_constant) uniform Push {
    uint slot_count;
    uint group_count;
    float occluder_distance;   // PHASE_OCCLUDERS/REST: farthest occluder center distance
    float occluder_size;       // smallest projected radius / view height
} pc;

shared uint sh_draw[CULL_TEST_BLOCKS * CULL_WORDS_PER_BLOCK];
shared uint sh_vis[CULL_TEST_BLOCKS * CULL_WORDS_PER_BLOCK];
shared uint sh_counts[4];
shared uint sh_group[CULL_TEST_BLOCKS];  // per block, the draw group of its first survivor

bool in_frustum(CullView view, vec3 c, float radius, vec3 half_extent) {
#ifdef NO_FRUSTUM
    return true;
#elif defined(BOUND_SPHERE)
    return cull_sphere_in_frustum(view, c, radius);
#else
    return cull_aabb_in_frustum(view, c - half_extent, c + half_extent);
#endif
}

#ifdef HAS_HIZ
// cull_hiz_occluded (common/cull_math.glsl) with every texel fetch issued at once: the same level
// and texels, but no early exit between fetches, which made each one wait for the one before.
// Rectangles that span more than 2x2 texels (3x3 with `finer`) fall back to the loop.
#ifdef HIZ_FINER
#define HIZ_SPAN 3u
#else
#define HIZ_SPAN 2u
#endif
bool hiz_occluded_at_once(uvec4 rect, float nearest_depth, uvec2 base_size, bool finer) {
    uint last = max(hiz_level_count(base_size) - 1u, CULL_HIZ_MIN_LEVEL);
    uint level = min(cull_hiz_level(rect), last);
    if (finer && level > 0u) level -= 1u;
    level = max(level, CULL_HIZ_MIN_LEVEL);
    uvec2 size = hiz_level_size(base_size, level);
    uvec2 lo = hiz_texel_of_pixel(rect.xy, level, size);
    uvec2 hi = hiz_texel_of_pixel(rect.zw, level, size);
    if (any(greaterThanEqual(hi - lo, uvec2(HIZ_SPAN)))) return cull_hiz_occluded(rect, nearest_depth, base_size, finer);
    float texels[HIZ_SPAN * HIZ_SPAN];
    [[unroll]] for (uint i = 0u; i < HIZ_SPAN * HIZ_SPAN; ++i) {
        // Repeats of the last texel (clamped) change nothing.
        texels[i] = hiz_load(level, min(lo + uvec2(i % HIZ_SPAN, i / HIZ_SPAN), hi));
    }
    bool occ = true;
    [[unroll]] for (uint i = 0u; i < HIZ_SPAN * HIZ_SPAN; ++i) occ = occ && nearest_depth < texels[i];
    return occ;
}

bool occluded(CullRecord r, float radius, vec3 half_extent) {
#ifdef HIZ_PREV_VIEW
    CullView view = frame.prev_cull_view;
    vec3 c = (r.center_hi - frame.prev_eye_hi.xyz) + (record_center_lo(r) - frame.prev_eye_lo.xyz);
#else
    CullView view = frame.cull_view;
    vec3 c = (r.center_hi - frame.eye_hi.xyz) + (record_center_lo(r) - frame.eye_lo.xyz);
#endif
    uvec4 rect;
    float nearest;
#ifdef BOUND_SPHERE
    uint status = cull_project_sphere(view, c, radius, rect, nearest);
#else
    uint status = cull_project_aabb(view, c - half_extent, c + half_extent, rect, nearest);
#endif
    // Crossing the near plane, or off screen in the view the pyramid was made with: visible.
    if (status != CULL_ON_SCREEN) return false;
#ifdef HIZ_FINER
    return hiz_occluded_at_once(rect, nearest, view.viewport, true);
#else
    return hiz_occluded_at_once(rect, nearest, view.viewport, false);
#endif
}
#endif

#if defined(PHASE_OCCLUDERS) || defined(PHASE_REST)
// The thesis's local occluder choice: flagged as an occluder (large and cheap), near, and
// large on screen. Deterministic, so PHASE_REST excludes exactly what PHASE_OCCLUDERS drew.
bool is_occluder(CullRecord r, vec3 c, float radius) {
    if (((r.group_flags >> 24) & FLAG_OCCLUDER) == 0u) return false;
    float d = length(c);
    if (d > pc.occluder_distance + radius) return false;
    float size = radius / max(d, frame.cull_view.near) * frame.cull_view.scale.y * 0.5;
    return d <= radius || size >= pc.occluder_size;
}
#endif

#ifndef ATOMIC_APPEND
#define THREADS 256u
shared bool sh_last;
shared uint sh_stats[4];
shared uint sh_scan[THREADS];
shared uint sh_total;
shared uint64_t sh_triangles[THREADS];

// Exclusive scan of one value per thread; returns the thread's prefix, leaves the sum in sh_total.
uint workgroup_exclusive_scan(uint value) {
    uint lane = gl_LocalInvocationIndex;
    sh_scan[lane] = value;
    barrier();
    for (uint offset = 1u; offset < THREADS; offset <<= 1u) {
        uint add = lane >= offset ? sh_scan[lane - offset] : 0u;
        barrier();
        sh_scan[lane] += add;
        barrier();
    }
    uint inclusive = sh_scan[lane];
    if (lane == THREADS - 1u) sh_total = inclusive;
    barrier();
    return inclusive - value;
}

// Survivors before draw group g's first slot, once the scratch holds the block prefix sums:
// its block's prefix plus the bits before it in the block. `total` past the last group.
uint group_start_base(uint g, uint total) {
    if (g >= pc.group_count) return total;
    uint first = groups[g].first_slot;
    if (first >= pc.slot_count) return total;
    uint b = first / CULL_BLOCK;
    uint k = first % CULL_BLOCK;
    uint count = scratch[scratch_block(b)];
    for (uint w = 0u; w < (k >> 5u); ++w) count += bitCount(draw_bits[b * CULL_WORDS_PER_BLOCK + w]);
    if ((k & 31u) != 0u) count += bitCount(draw_bits[b * CULL_WORDS_PER_BLOCK + (k >> 5u)] & ((1u << (k & 31u)) - 1u));
    return count;
}

// The tail, by the last workgroup to finish the test (every block's bits and count are final).
void finish_pass(uint blocks) {
    uint lane = gl_LocalInvocationIndex;
    // 1. Block counts -> exclusive prefix sums, in place. Thread t owns a contiguous run of
    // blocks, loaded 16 at a time so the loads are in flight together (one round up to 4096
    // blocks, i.e. ~10^6 slots).
    uint per = (blocks + THREADS - 1u) / THREADS;
    uint start = min(lane * per, blocks);
    uint end = min(start + per, blocks);
    // The statistics, one set per counter lane, loaded in the same round.
    uvec4 lane_stats = uvec4(0u);
    if (lane < CULL_LANES) {
        lane_stats = uvec4(scratch[scratch_lane(lane, LANE_TESTED)], scratch[scratch_lane(lane, LANE_FRUSTUM)],
                           scratch[scratch_lane(lane, LANE_OCCLUSION)], scratch[scratch_lane(lane, LANE_VISIBLE)]);
    }
    uint first_run[16];
    uint sum = 0u;
    [[unroll]] for (uint i = 0u; i < 16u; ++i) {
        first_run[i] = start + i < end ? scratch[scratch_block(start + i)] : 0u;
    }
    [[unroll]] for (uint i = 0u; i < 16u; ++i) sum += first_run[i];
    for (uint b0 = start + 16u; b0 < end; b0 += 16u) {
        uint run[16];
        [[unroll]] for (uint i = 0u; i < 16u; ++i) run[i] = b0 + i < end ? scratch[scratch_block(b0 + i)] : 0u;
        [[unroll]] for (uint i = 0u; i < 16u; ++i) sum += run[i];
    }
    uint offset = workgroup_exclusive_scan(sum);
    uint total = sh_total;
    [[unroll]] for (uint i = 0u; i < 16u; ++i) {
        if (start + i < end) scratch[scratch_block(start + i)] = offset;
        offset += first_run[i];
    }
    for (uint b0 = start + 16u; b0 < end; b0 += 16u) {
        uint run[16];
        [[unroll]] for (uint i = 0u; i < 16u; ++i) run[i] = b0 + i < end ? scratch[scratch_block(b0 + i)] : 0u;
        [[unroll]] for (uint i = 0u; i < 16u; ++i) {
            if (b0 + i < end) scratch[scratch_block(b0 + i)] = offset;
            offset += run[i];
        }
    }
    // Statistics summed; then every counter goes back to 0 for the pass's next run (block words
    // are overwritten by every run).
    if (lane < 4u) sh_stats[lane] = 0u;
    barrier();
    [[unroll]] for (uint i = 0u; i < 4u; ++i) {
        if (lane_stats[i] != 0u) atomicAdd(sh_stats[i], lane_stats[i]);
    }
    // The prefixes other threads stored, visible to this workgroup's reads below (and every read
    // of the header done before the reset).
    controlBarrier(gl_ScopeWorkgroup, gl_ScopeWorkgroup, gl_StorageSemanticsBuffer | gl_StorageSemanticsShared,
                   gl_SemanticsAcquireRelease);
    for (uint i = lane; i < SCRATCH_HEADER; i += THREADS) scratch[i] = 0u;

    // 2. Per group: its base (for the scatter step) and survivor count; one command per non-empty
    // group, compacted in group order so the command list is the same every run.
    uint written = 0u;
    uint64_t triangles = 0ul;
    for (uint chunk = 0u; chunk < pc.group_count; chunk += THREADS) {
        uint g = chunk + lane;
        uint count = 0u;
        DrawGroup group;
        if (g < pc.group_count) {
            group = groups[g];
            uint base = group_start_base(g, total);
            count = group_start_base(g + 1u, total) - base;
            group_base[g] = base;
        }
        uint index = written + workgroup_exclusive_scan(count != 0u ? 1u : 0u);
        if (count != 0u) {
            DrawCommand cmd;
            cmd.index_count = group.index_count;
            cmd.instance_count = count;
            cmd.first_index = group.first_index;
            cmd.vertex_offset = group.vertex_offset;
            cmd.first_instance = group.first_slot;
            commands[index] = cmd;
            triangles += uint64_t(group.index_count / 3u) * uint64_t(count);
        }
        written += sh_total;
        barrier();
    }
    // 3. Counters (a tree sum: one thread summing 256 values would be the slowest part).
    sh_triangles[lane] = triangles;
    barrier();
    for (uint half_ = THREADS / 2u; half_ > 0u; half_ >>= 1u) {
        if (lane < half_) sh_triangles[lane] += sh_triangles[lane + half_];
        barrier();
    }
    if (lane == 0u) {
        uint64_t sum64 = sh_triangles[0];
        draw_count = written;
        CullStats s;
        s.tested = sh_stats[0];
        s.frustum_culled = sh_stats[1];
        s.occlusion_culled = sh_stats[2];
        s.drawn = total;
        s.draws = written;
        s.triangles_lo = uint(sum64);
        s.triangles_hi = uint(sum64 >> 32);
        s.survivors = sh_stats[3];
        for (uint i = 0u; i < 8u; ++i) s.pad[i] = 0u;
        stats = s;
    }
}
#endif

// Decides one evaluated slot: whether this pass draws it, whether it is visible this frame, and
// why it was culled.
void decide(CullRecord r, bool was_visible, out bool draw, out bool visible_now, out bool frustum_culled,
            out bool occlusion_culled) {
    float radius = record_radius(r);
    vec3 half_extent = record_half_extent(r);
    vec3 c = (r.center_hi - frame.eye_hi.xyz) + (record_center_lo(r) - frame.eye_lo.xyz);
    bool huge = (r.group_flags & CULL_HUGE) != 0u;
    bool inside = huge || in_frustum(frame.cull_view, c, radius, half_extent);
    bool hidden = false;
#if defined(HAS_HIZ) && !defined(PHASE_OCCLUDERS)
    if (inside && !huge) hidden = occluded(r, radius, half_extent);
#endif
    frustum_culled = !inside;
    occlusion_culled = inside && hidden;
    bool visible = inside && !hidden;
    visible_now = false;
#if defined(PHASE_LATE)
    draw = visible && !was_visible;
    visible_now = visible;
#elif defined(PHASE_OCCLUDERS)
    draw = inside && is_occluder(r, c, radius);
#elif defined(PHASE_REST)
    draw = visible && !(inside && is_occluder(r, c, radius));
#else
    draw = visible;
#endif
}

void main() {
    uint lane = gl_LocalInvocationIndex;
    if (lane < CULL_TEST_BLOCKS * CULL_WORDS_PER_BLOCK) {
        sh_draw[lane] = 0u;
        sh_vis[lane] = 0u;
    }
    if (lane < 4u) sh_counts[lane] = 0u;
    if (lane < CULL_TEST_BLOCKS) sh_group[lane] = 0xFFFFFFFFu;
    barrier();
    uint first_block = gl_WorkGroupID.x * CULL_TEST_BLOCKS;
    uint blocks = (pc.slot_count + CULL_BLOCK - 1u) / CULL_BLOCK;

    // Every load of the thread's slots first, so that they are in flight together.
    bool was_visible[CULL_TEST_BLOCKS];
    bool evaluated[CULL_TEST_BLOCKS];
    CullRecord rec[CULL_TEST_BLOCKS];
    [[unroll]] for (uint j = 0u; j < CULL_TEST_BLOCKS; ++j) {
        uint slot = (first_block + j) * CULL_BLOCK + lane;
        bool in_range = slot < pc.slot_count;
#ifdef HAS_VIS_PREV
        was_visible[j] = in_range && ((vis_prev[slot >> 5] >> (slot & 31u)) & 1u) != 0u;
#else
        was_visible[j] = false;
#endif
#ifdef PHASE_EARLY
        evaluated[j] = was_visible[j];
#else
        evaluated[j] = in_range;
#endif
    }
    [[unroll]] for (uint j = 0u; j < CULL_TEST_BLOCKS; ++j) {
        if (evaluated[j]) rec[j] = records[(first_block + j) * CULL_BLOCK + lane];
    }
    uvec4 counts = uvec4(0u);  // evaluated, frustum-culled, occlusion-culled, visible now
    [[unroll]] for (uint j = 0u; j < CULL_TEST_BLOCKS; ++j) {
        if (!evaluated[j]) continue;
        bool draw, visible_now, frustum_culled, occlusion_culled;
        decide(rec[j], was_visible[j], draw, visible_now, frustum_culled, occlusion_culled);
        counts += uvec4(1u, uint(frustum_culled), uint(occlusion_culled), uint(visible_now));
        uint word = j * CULL_WORDS_PER_BLOCK + (lane >> 5);
        if (visible_now) atomicOr(sh_vis[word], 1u << (lane & 31u));
        if (draw) {
            atomicOr(sh_draw[word], 1u << (lane & 31u));
#ifdef ATOMIC_APPEND
            uint slot = (first_block + j) * CULL_BLOCK + lane;
            uint group = record_group(rec[j]);
            DrawGroup g = groups[group];
            uint index = atomicAdd(commands[group].instance_count, 1u);
            draw_ids[g.first_slot + index] = slot_instances[slot];
            uint tris = g.index_count / 3u;
            uint old = atomicAdd(stats.triangles_lo, tris);
            if (old + tris < old) atomicAdd(stats.triangles_hi, 1u);
            atomicAdd(stats.drawn, 1u);
#else
            // Groups are sorted by slot: the block's first survivor has its smallest group.
            atomicMin(sh_group[j], record_group(rec[j]));
#endif
        }
    }
    [[unroll]] for (uint i = 0u; i < 4u; ++i) {
        if (counts[i] != 0u) atomicAdd(sh_counts[i], counts[i]);
    }
    barrier();

#ifdef WRITE_VIS
    if (lane < CULL_TEST_BLOCKS * CULL_WORDS_PER_BLOCK) {
        // The visibility buffer holds ceil(slots / 32) words; the last blocks may run past it.
        uint word = first_block * CULL_WORDS_PER_BLOCK + lane;
        if (word < (pc.slot_count + 31u) / 32u) vis_now[word] = sh_vis[lane];
    }
#endif

#ifdef ATOMIC_APPEND
    if (lane == 0u) {
        if (sh_counts[0] != 0u) atomicAdd(stats.tested, sh_counts[0]);
        if (sh_counts[1] != 0u) atomicAdd(stats.frustum_culled, sh_counts[1]);
        if (sh_counts[2] != 0u) atomicAdd(stats.occlusion_culled, sh_counts[2]);
        if (sh_counts[3] != 0u) atomicAdd(stats.survivors, sh_counts[3]);
    }
#else
    if (lane == 0u) {
        // Thread 0 stores everything the last workgroup and the scatter step read, then releases
        // it with its atomic.
        [[unroll]] for (uint j = 0u; j < CULL_TEST_BLOCKS; ++j) {
            uint b = first_block + j;
            if (b >= blocks) break;
            uint count = 0u;
            [[unroll]] for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) {
                uint bits = sh_draw[j * CULL_WORDS_PER_BLOCK + w];
                draw_bits[b * CULL_WORDS_PER_BLOCK + w] = bits;
                count += bitCount(bits);
            }
            scratch[scratch_block(b)] = count;
            scratch[scratch_block_group(blocks, b)] = sh_group[j];
        }
        uint wg = gl_WorkGroupID.x;
        uint wgs = gl_NumWorkGroups.x;
        uint l = wg % CULL_LANES;
        if (sh_counts[0] != 0u) atomicAdd(scratch[scratch_lane(l, LANE_TESTED)], sh_counts[0]);
        if (sh_counts[1] != 0u) atomicAdd(scratch[scratch_lane(l, LANE_FRUSTUM)], sh_counts[1]);
        if (sh_counts[2] != 0u) atomicAdd(scratch[scratch_lane(l, LANE_OCCLUSION)], sh_counts[2]);
        if (sh_counts[3] != 0u) atomicAdd(scratch[scratch_lane(l, LANE_VISIBLE)], sh_counts[3]);
        // Last of its lane (the lane's workgroups are known), then last of the lanes. Each
        // acquire-release atomic passes on everything released to the counter before it.
        uint lane_size = (wgs - l + CULL_LANES - 1u) / CULL_LANES;  // workgroups l, l + CULL_LANES, ...
        uint before = atomicAdd(scratch[scratch_lane(l, LANE_DONE)], 1u, gl_ScopeDevice, gl_StorageSemanticsBuffer,
                                gl_SemanticsAcquireRelease);
        bool last = false;
        if (before == lane_size - 1u) {
            uint lanes = min(wgs, CULL_LANES);
            last = atomicAdd(scratch[SCRATCH_DONE_TOP], 1u, gl_ScopeDevice, gl_StorageSemanticsBuffer,
                             gl_SemanticsAcquireRelease) == lanes - 1u;
        }
        sh_last = last;
    }
    barrier();
    if (!sh_last) return;
    // Everything the other workgroups released, visible to every thread of this one.
    controlBarrier(gl_ScopeWorkgroup, gl_ScopeDevice, gl_StorageSemanticsBuffer | gl_StorageSemanticsShared,
                   gl_SemanticsAcquireRelease);
    finish_pass(blocks);
#endif
}
