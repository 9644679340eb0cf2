#version 460
// Instance cull, step 1 of 3: each workgroup decides for its block of CULL_BLOCK slots whether
// this pass draws each (frustum, then optionally the Hi-Z occlusion test), and stores the
// decisions as bits, the block's survivor count, and adds it to its superblock's count.
// `cull_scatter.comp` then places the survivors, `cull_commands.comp` writes the commands.
//
// Variants (defines) select the phase and tests so that nothing branches on settings or binds
// unused resources. Phases: PHASE_ALL (every survivor), PHASE_EARLY (survivors among last
// frame's visible), PHASE_LATE (survivors that were not visible last frame; writes this frame's
// visibility bits), PHASE_OCCLUDERS (chosen occluders, frustum only), PHASE_REST (survivors
// that are not occluders). ATOMIC_APPEND is the thesis's atomic append, measured only.
#extension GL_GOOGLE_include_directive : require
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

layout(push_constant) uniform Push {
    uint slot_count;
    uint superblocks;          // ceil(blocks / CULL_SUPERBLOCK)
    float occluder_distance;   // PHASE_OCCLUDERS/REST: farthest occluder center distance
    float occluder_size;       // smallest projected radius / view height
} pc;

shared uint sh_draw[CULL_WORDS_PER_BLOCK];
shared uint sh_vis[CULL_WORDS_PER_BLOCK];
shared uint sh_counts[4];

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
    return cull_hiz_occluded(rect, nearest, view.viewport, true);
#else
    return cull_hiz_occluded(rect, nearest, view.viewport, false);
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

void main() {
    uint lane = gl_LocalInvocationIndex;
    if (lane < CULL_WORDS_PER_BLOCK) {
        sh_draw[lane] = 0u;
        sh_vis[lane] = 0u;
    }
    if (lane < 4u) sh_counts[lane] = 0u;
    barrier();
    uint block = gl_WorkGroupID.x;
    uint slot = block * CULL_BLOCK + lane;

    bool evaluated = false;
    bool frustum_culled = false;
    bool occlusion_culled = false;
    bool draw = false;
    bool visible_now = false;
    uint group = 0u;
    if (slot < pc.slot_count) {
#ifdef HAS_VIS_PREV
        bool was_visible = ((vis_prev[slot >> 5] >> (slot & 31u)) & 1u) != 0u;
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
            group = record_group(r);
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
    }
    if (draw) atomicOr(sh_draw[lane >> 5], 1u << (lane & 31u));
    if (visible_now) atomicOr(sh_vis[lane >> 5], 1u << (lane & 31u));
    if (evaluated) atomicAdd(sh_counts[0], 1u);
    if (frustum_culled) atomicAdd(sh_counts[1], 1u);
    if (occlusion_culled) atomicAdd(sh_counts[2], 1u);
    if (visible_now) atomicAdd(sh_counts[3], 1u);
    barrier();

#ifdef WRITE_VIS
    if (lane < CULL_WORDS_PER_BLOCK) {
        // The visibility buffer holds ceil(slots / 32) words; the last block may run past it.
        uint word = block * CULL_WORDS_PER_BLOCK + lane;
        if (word < (pc.slot_count + 31u) / 32u) vis_now[word] = sh_vis[lane];
    }
#endif

#ifdef ATOMIC_APPEND
    if (draw) {
        DrawGroup g = groups[group];
        uint index = atomicAdd(commands[group].instance_count, 1u);
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
    if (lane == 0u) {
        uint count = 0u;
        for (uint w = 0u; w < CULL_WORDS_PER_BLOCK; ++w) count += bitCount(sh_draw[w]);
        scratch[scratch_block(pc.superblocks, block)] = count;
        if (count != 0u) atomicAdd(scratch[scratch_superblock(block / CULL_SUPERBLOCK)], count);
        if (sh_counts[0] != 0u) atomicAdd(scratch[SCRATCH_TESTED], sh_counts[0]);
        if (sh_counts[1] != 0u) atomicAdd(scratch[SCRATCH_FRUSTUM], sh_counts[1]);
        if (sh_counts[2] != 0u) atomicAdd(scratch[SCRATCH_OCCLUSION], sh_counts[2]);
        if (sh_counts[3] != 0u) atomicAdd(scratch[SCRATCH_VISIBLE], sh_counts[3]);
    }
#endif
}
