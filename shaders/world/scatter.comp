#version 460
// A changing world's slot updates (src/render/renderer/world_sync.rs): each thread writes one
// slot's new instance record, or for a move only its transform (60 bytes), and derives the
// slot's cull bound from it and its draw group's local bounds, so that a moved instance costs
// 64 bytes of upload. One dispatch replaces thousands of tiny copy regions, which cost the copy
// engine far more than the bytes they move.
//
// The bound is packed as src/passes/shared/cull_data.rs packs it (GpuCullRecord), from the
// instance's own hi/lo split of its translation: center = hi + (linear * local center + lo).
// The lo part is stored as half floats, and the radius and half extents grow by its rounding
// error and are rounded up, so the bound contains the exact one; a bound beyond half floats is
// flagged CULL_HUGE (never culled).
#extension GL_EXT_scalar_block_layout : require
#include "../cull/cull_common.glsl"

layout(local_size_x = 64) in;

#ifdef MOVES
// A transform only: the rows of the linear part with the translation's hi part in w, and its
// lo part. Material and flags stay.
struct Update {
    uint slot;
    vec4 rows[3];
    vec3 translation_lo;
};
#else
// The whole instance record.
struct Update {
    uint slot;
    uint instance[16];
};
#endif

// Local bounds of a draw group's mesh: box center and the radius of the sphere around it, box
// half extents.
struct GroupBounds {
    vec4 center_radius;
    vec4 half_extent;
};

layout(set = 0, binding = 0, scalar) readonly buffer Updates { Update updates[]; };
layout(set = 0, binding = 1) writeonly buffer Instances { uint instance_words[]; };
layout(set = 0, binding = 2) buffer Records { uint record_words[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Bounds { GroupBounds group_bounds[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Groups { DrawGroup groups[]; };

layout(push_constant) uniform Push { uint count; uint group_count; } pc;

// The draw group whose slot range holds `slot` (the ranges are in slot order): a search of a
// small, cached table instead of a read of the slot's old record.
uint group_of(uint slot) {
    uint lo = 0u, hi = pc.group_count;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (groups[mid].first_slot <= slot) lo = mid; else hi = mid;
    }
    return lo;
}

// The half float not below x (x >= 0), as bits.
uint half_up(float x) {
    uint h = packHalf2x16(vec2(x, 0.0)) & 0xFFFFu;
    if (unpackHalf2x16(h).x < x) h += 1u;
    return h;
}

const float HALF_MAX = 65504.0;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    uint slot = updates[i].slot;
    uint base = slot * 16u;
    vec4 rows[3];
    vec3 lo_t;
#ifdef MOVES
    rows = updates[i].rows;
    lo_t = updates[i].translation_lo;
    for (uint r = 0u; r < 3u; ++r) {
        for (uint c = 0u; c < 4u; ++c) instance_words[base + r * 4u + c] = floatBitsToUint(rows[r][c]);
    }
    for (uint c = 0u; c < 3u; ++c) instance_words[base + 12u + c] = floatBitsToUint(lo_t[c]);
#else
    uint words[16] = updates[i].instance;
    for (uint k = 0u; k < 16u; ++k) instance_words[base + k] = words[k];
    for (uint r = 0u; r < 3u; ++r) {
        rows[r] = vec4(uintBitsToFloat(words[r * 4u]), uintBitsToFloat(words[r * 4u + 1u]),
                       uintBitsToFloat(words[r * 4u + 2u]), uintBitsToFloat(words[r * 4u + 3u]));
    }
    lo_t = vec3(uintBitsToFloat(words[12]), uintBitsToFloat(words[13]), uintBitsToFloat(words[14]));
#endif
    uint rec = slot * 8u;
    uint group = group_of(slot);
    GroupBounds b = group_bounds[group];
    vec3 c = b.center_radius.xyz;
    vec3 h = b.half_extent.xyz;
    vec3 lo = vec3(dot(rows[0].xyz, c), dot(rows[1].xyz, c), dot(rows[2].xyz, c)) + lo_t;
    vec3 half_extent = vec3(dot(abs(rows[0].xyz), h), dot(abs(rows[1].xyz), h), dot(abs(rows[2].xyz), h))
                       * (1.0 + 1.0 / 1048576.0);
    vec3 col0 = vec3(rows[0].x, rows[1].x, rows[2].x);
    vec3 col1 = vec3(rows[0].y, rows[1].y, rows[2].y);
    vec3 col2 = vec3(rows[0].z, rows[1].z, rows[2].z);
    float radius = b.center_radius.w * max(length(col0), max(length(col1), length(col2)));

    uint lo_xy = packHalf2x16(lo.xy);
    uint lo_z = packHalf2x16(vec2(lo.z, 0.0)) & 0xFFFFu;
    vec3 stored = vec3(unpackHalf2x16(lo_xy), unpackHalf2x16(lo_z).x);
    // The stored center's error, and the float products' (a few units in the last place).
    vec3 d = abs(lo - stored);
    float err = max(d.x, max(d.y, d.z)) + max(abs(lo.x), max(abs(lo.y), abs(lo.z))) / 1048576.0;
    radius += err;
    half_extent += vec3(err);
    bool finite = !any(isnan(lo)) && !any(isinf(lo)) && !isnan(radius) && !isinf(radius)
                  && !any(isnan(half_extent)) && !any(isinf(half_extent));
    bool huge = !finite || any(greaterThan(abs(lo), vec3(HALF_MAX))) || radius > HALF_MAX
                || any(greaterThan(half_extent, vec3(HALF_MAX)));

    record_words[rec + 0u] = floatBitsToUint(rows[0].w);
    record_words[rec + 1u] = floatBitsToUint(rows[1].w);
    record_words[rec + 2u] = floatBitsToUint(rows[2].w);
#ifdef MOVES
    // A move keeps the group and flags: only the huge bit may change.
    if (huge) atomicOr(record_words[rec + 3u], CULL_HUGE); else atomicAnd(record_words[rec + 3u], ~CULL_HUGE);
#else
    uint flags = (words[15] >> 24) & 0x7Fu;
    record_words[rec + 3u] = group | (flags << 24) | (huge ? CULL_HUGE : 0u);
#endif
    if (huge) {
        record_words[rec + 4u] = 0u;
        record_words[rec + 5u] = 0u;
        record_words[rec + 6u] = 0u;
        record_words[rec + 7u] = 0u;
        return;
    }
    record_words[rec + 4u] = lo_xy;
    record_words[rec + 5u] = lo_z | (half_up(radius) << 16);
    record_words[rec + 6u] = half_up(half_extent.x) | (half_up(half_extent.y) << 16);
    record_words[rec + 7u] = half_up(half_extent.z);
}
