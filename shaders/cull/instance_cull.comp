#version 460
// Instance cull, step 1 of 3: one thread per slot decides whether its instance is drawn by this
// pass (frustum, then optionally the Hi-Z occlusion test), and each block of CULL_BLOCK slots
// stores its decisions as bits plus their count. Variants (defines) select the phase and tests
// so that no pipeline branches on settings or binds unused resources.
//
// Phases: PHASE_ALL (every survivor), PHASE_EARLY (survivors among last frame's visible),
// PHASE_LATE (survivors that were not visible last frame; writes this frame's visibility bits),
// PHASE_OCCLUDERS (chosen occluders, frustum only), PHASE_REST (survivors that are not occluders).
#extension GL_GOOGLE_include_directive : require
#include "../common/scene.glsl"
#include "../common/hiz.glsl"
#include "cull_common.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) readonly buffer Records { CullRecord records[]; };
layout(set = 0, binding = 1, scalar) readonly buffer Frame { FrameConstants frame; };
#ifdef ATOMIC_APPEND
// The thesis's "ideal implementation": each survivor bumps its group's instanceCount with an
// atomic and writes itself at the returned index. Order within a group varies run to run.
layout(set = 0, binding = 2, scalar) buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 3) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 4, scalar) buffer Stats { CullStats stats; };
layout(set = 0, binding = 8, scalar) readonly buffer Groups { DrawGroup groups[]; };
#else
layout(set = 0, binding = 2) writeonly buffer Flags { uint draw_bits[]; };
// Per block: survivors, tested, frustum culled, occlusion culled, visible now, unused x3.
layout(set = 0, binding = 3) writeonly buffer BlockInfo { uvec4 block_info[]; };
#endif
#ifdef HAS_VIS_PREV
layout(set = 0, binding = 5) readonly buffer VisPrev { uint vis_prev[]; };
#endif
#ifdef WRITE_VIS
layout(set = 0, binding = 6) writeonly buffer Vis { uint vis_now[]; };
#endif
#ifdef HAS_HIZ
layout(set = 0, binding = 7) uniform sampler2D hiz_tex;
float hiz_load(uint level, uvec2 texel) { return texelFetch(hiz_tex, ivec2(texel), int(level)).r; }
#endif

layout(push_constant) uniform Push {
    uint slot_count;
    float occluder_distance;   // PHASE_OCCLUDERS/REST: farthest occluder center distance
    float occluder_size;       // smallest projected radius / view height
} pc;

shared uint sh_draw[CULL_WORDS_PER_BLOCK];
shared uint sh_vis[CULL_WORDS_PER_BLOCK];
shared uint sh_counts[4];

bool bit_of(uint word, uint bit) { return ((word >> bit) & 1u) != 0u; }

bool in_frustum(CullView view, vec3 c, CullRecord r) {
#ifdef NO_FRUSTUM
    return true;
#elif defined(BOUND_SPHERE)
    return cull_sphere_in_frustum(view, c, r.radius);
#else
    return cull_aabb_in_frustum(view, c - r.half_extent, c + r.half_extent);
#endif
}

#ifdef HAS_HIZ
bool occluded(CullRecord r) {
#ifdef HIZ_PREV_VIEW
    CullView view = frame.prev_cull_view;
    vec3 c = (r.center_hi - frame.prev_eye_hi.xyz) + (r.center_lo - frame.prev_eye_lo.xyz);
#else
    CullView view = frame.cull_view;
    vec3 c = (r.center_hi - frame.eye_hi.xyz) + (r.center_lo - frame.eye_lo.xyz);
#endif
    uvec4 rect;
    float nearest;
#ifdef BOUND_SPHERE
    uint status = cull_project_sphere(view, c, r.radius, rect, nearest);
#else
    uint status = cull_project_aabb(view, c - r.half_extent, c + r.half_extent, rect, nearest);
#endif
    // Crossing the near plane, or off screen in the view the pyramid was made with: visible.
    if (status != CULL_ON_SCREEN) return false;
#ifdef HIZ_FINER
    return cull_hiz_occluded(rect, nearest, view.viewport, true);
#else
    return cull_hiz_occluded(rect, nearest, view.viewport, false);
#endif
}
#endif

#if defined(PHASE_OCCLUDERS) || defined(PHASE_REST)
// The thesis's local occluder choice: flagged as an occluder (large and cheap), near, and
// large on screen. Deterministic, so PHASE_REST excludes exactly what PHASE_OCCLUDERS drew.
bool is_occluder(CullRecord r, vec3 c) {
    if (((r.group_flags >> 24) & FLAG_OCCLUDER) == 0u) return false;
    float d = length(c);
    if (d > pc.occluder_distance + r.radius) return false;
    float size = r.radius / max(d, frame.cull_view.near) * frame.cull_view.scale.y * 0.5;
    return d <= r.radius || size >= pc.occluder_size;
}
#endif

void main() {
    uint slot = gl_GlobalInvocationID.x;
    uint lane = gl_LocalInvocationIndex;
    if (lane < CULL_WORDS_PER_BLOCK) {
        sh_draw[lane] = 0u;
        sh_vis[lane] = 0u;
    }
    if (lane < 4u) sh_counts[lane] = 0u;
    barrier();

    bool evaluated = false;
    bool frustum_culled = false;
    bool occlusion_culled = false;
    bool draw = false;
    bool visible_now = false;
    if (slot < pc.slot_count) {
#ifdef HAS_VIS_PREV
        bool was_visible = bit_of(vis_prev[slot >> 5], slot & 31u);
#else
        bool was_visible = false;
#endif
#ifdef PHASE_EARLY
        evaluated = was_visible;
#else
        evaluated = true;
#endif
        if (evaluated) {
            CullRecord r = records[slot];
            vec3 c = (r.center_hi - frame.eye_hi.xyz) + (r.center_lo - frame.eye_lo.xyz);
            bool inside = in_frustum(frame.cull_view, c, r);
            bool hidden = false;
#if defined(HAS_HIZ) && !defined(PHASE_OCCLUDERS)
            if (inside) hidden = occluded(r);
#endif
            frustum_culled = !inside;
            occlusion_culled = inside && hidden;
            bool visible = inside && !hidden;
#if defined(PHASE_LATE)
            draw = visible && !was_visible;
            visible_now = visible;
#elif defined(PHASE_OCCLUDERS)
            draw = inside && is_occluder(r, c);
#elif defined(PHASE_REST)
            draw = visible && !(inside && is_occluder(r, c));
#else
            draw = visible;
#endif
        }
    }
#ifdef ATOMIC_APPEND
    if (draw) {
        CullRecord r = records[slot];
        uint g = r.group_flags & 0xFFFFFFu;
        uint index = atomicAdd(commands[g].instance_count, 1u);
        draw_ids[groups[g].first_slot + index] = r.instance;
        uint tris = groups[g].index_count / 3u;
        uint old = atomicAdd(stats.triangles_lo, tris);
        if (old + tris < old) atomicAdd(stats.triangles_hi, 1u);
        atomicAdd(stats.drawn, 1u);
    }
#endif
    if (draw) atomicOr(sh_draw[lane >> 5], 1u << (lane & 31u));
    if (visible_now) atomicOr(sh_vis[lane >> 5], 1u << (lane & 31u));
    if (evaluated) atomicAdd(sh_counts[0], 1u);
    if (frustum_culled) atomicAdd(sh_counts[1], 1u);
    if (occlusion_culled) atomicAdd(sh_counts[2], 1u);
    if (visible_now) atomicAdd(sh_counts[3], 1u);
    barrier();

    uint block = gl_WorkGroupID.x;
    if (lane < CULL_WORDS_PER_BLOCK) {
        uint word = block * CULL_WORDS_PER_BLOCK + lane;
#ifndef ATOMIC_APPEND
        draw_bits[word] = sh_draw[lane];
#endif
#ifdef WRITE_VIS
        // The visibility buffer holds ceil(slots / 32) words; the last block may run past it.
        if (word < (pc.slot_count + 31u) / 32u) vis_now[word] = sh_vis[lane];
#endif
    }
    if (lane == 0u) {
        uint count = 0u;
        for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) count += bitCount(sh_draw[w]);
#ifdef ATOMIC_APPEND
        if (sh_counts[0] != 0u) atomicAdd(stats.tested, sh_counts[0]);
        if (sh_counts[1] != 0u) atomicAdd(stats.frustum_culled, sh_counts[1]);
        if (sh_counts[2] != 0u) atomicAdd(stats.occlusion_culled, sh_counts[2]);
        if (sh_counts[3] != 0u) atomicAdd(stats.survivors, sh_counts[3]);
#else
        // The scan sums these into the pass's counters with plain stores: no clearing, no atomics.
        block_info[block * 2u] = uvec4(count, sh_counts[0], sh_counts[1], sh_counts[2]);
        block_info[block * 2u + 1u] = uvec4(sh_counts[3], 0u, 0u, 0u);
#endif
    }
}
