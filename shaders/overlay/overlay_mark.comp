#version 460
// Overlay, view "culled", step 1: one thread per slot (draw-list order, as the cull passes and
// their visibility bits use). An instance the late cull pass did not find visible although its
// box is inside the frustum (the cull's own test, same math) was occlusion-culled this frame:
// its screen rectangle (cull_project_aabb, as the Hi-Z test projects it, grown by a pixel) is
// added to a per-row difference array, +1 at its left column and -1 after its right one on each
// of its rows, which overlay_scan.comp turns into coverage counts. Integer atomics only, so the
// result does not depend on the order threads run in.
#extension GL_GOOGLE_include_directive : require
#include "../common/scene.glsl"
#include "../cull/cull_common.glsl"
#include "../common/line_dispatch.glsl"

layout(local_size_x = 256) in;

layout(set = 0, binding = 0, scalar) readonly buffer Records { CullRecord records[]; };
layout(set = 0, binding = 1, scalar) uniform Frame { FrameConstants frame; };
layout(set = 0, binding = 2) readonly buffer Visibility { uint visible[]; };
// Header (word 0: instances marked), then per row (width + 1) differences.
layout(set = 0, binding = 3) buffer Coverage { uint marked; uint pad[3]; int coverage[]; };

layout(push_constant) uniform Push {
    uint slot_count;
    uint width;
    uint height;
} pc;

void main() {
    uint slot = line_invocation();
    if (slot >= pc.slot_count) return;
    if (((visible[slot >> 5] >> (slot & 31u)) & 1u) != 0u) return;
    CullRecord r = records[slot];
    // Huge bounds are always visible; anything else not visible but inside the frustum (the
    // cull's box test) was behind the Hi-Z.
    if ((r.group_flags & CULL_HUGE) != 0u) return;
    vec3 c = rel_eye(r.center_hi, record_center_lo(r), frame.eye_hi.xyz, frame.eye_lo.xyz);
    vec3 half_extent = record_half_extent(r);
    vec3 lo = c - half_extent;
    vec3 hi = c + half_extent;
    if (!cull_aabb_in_frustum(frame.cull_view, lo, hi)) return;
    uvec4 rect;
    float nearest;
    // A bound crossing the near plane or off screen is never occlusion-culled.
    if (cull_project_aabb(frame.cull_view, lo, hi, rect, nearest) != CULL_ON_SCREEN) return;
    atomicAdd(marked, 1u);
    // One pixel wider on every side, so that distant instances a pixel across still show.
    uint stride = pc.width + 1u;
    uint x0 = rect.x > 0u ? rect.x - 1u : 0u;
    uint x1 = min(rect.z + 1u, pc.width - 1u) + 1u;
    uint y0 = rect.y > 0u ? rect.y - 1u : 0u;
    for (uint y = y0; y <= min(rect.w + 1u, pc.height - 1u); ++y) {
        atomicAdd(coverage[y * stride + x0], 1);
        atomicAdd(coverage[y * stride + x1], -1);
    }
}
