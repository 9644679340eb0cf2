#version 460
// A changing world's slot updates (src/render/renderer/world_sync.rs): each thread writes one
// slot's new instance record and derives the slot's cull bound from it and its draw group's
// local bounds. An update carries the whole record with the slot and its group (72 bytes), so
// that it reads nothing of the slot's old records, a move as any other change. One dispatch
// replaces thousands of tiny copy regions, which cost the copy engine far more than the bytes
// they move.
//
// The bound is packed as src/passes/shared/cull_data.rs packs it (GpuCullRecord), from the
// instance's own hi/lo split of its translation: center = hi + (linear * local center + lo).
// The lo part is stored as half floats, and the radius and half extents grow by its rounding
// error and are rounded up, so the bound contains the exact one; a bound beyond half floats is
// flagged CULL_HUGE (never culled).
#extension GL_EXT_scalar_block_layout : require
#include "../cull/cull_common.glsl"
#include "../common/line_dispatch.glsl"

layout(local_size_x = 64) in;

// The rows of the linear part with the translation's hi part in w, then its lo part and the
// slot; the slot's draw group, and the material and flags (the instance record's last word).
// The host writes these straight into the buffer this reads.
struct Update {
    uvec4 words[4];
    uint group;
    uint material_flags;
};

layout(set = 0, binding = 0, scalar) readonly buffer Updates { Update updates[]; };

// Local bounds of a draw group's mesh: box center and the radius of the sphere around it, box
// half extents.
struct GroupBounds {
    vec4 center_radius;
    vec4 half_extent;
};

// Instance records are 64 bytes and cull records 32: whole 16-byte words are written, so that
// a thread's scattered writes take a few vector stores rather than a store per word.
#define INSTANCE_WORDS_BINDING 1
#include "../common/scene.glsl"
#include "../common/instance_ranges.glsl"
layout(set = 0, binding = 2) buffer Records { uvec4 record_vec[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Bounds { GroupBounds group_bounds[]; };

// The scene's bounds per block of slots (BLOCK_BOUND_WORDS each), if it has them
// (`marks_blocks`): a block whose slot changes is marked to be tested slot by slot, since its
// bound no longer holds what its slots hold.
layout(set = 0, binding = 4) buffer BlockWords { uint block_words[]; };

layout(push_constant) uniform Push {
    uint count;
    uint marks_blocks;
} pc;

// The half float not below x (x >= 0), as bits.
uint half_up(float x) {
    uint h = packHalf2x16(vec2(x, 0.0)) & 0xFFFFu;
    if (unpackHalf2x16(h).x < x) h += 1u;
    return h;
}

const float HALF_MAX = 65504.0;

void main() {
    uint i = line_invocation();
    if (i >= pc.count) return;
    uvec4 w[4] = updates[i].words;
    uint slot = w[3].w;
    // An update superseded before its frame (src/render/renderer/update_ring.rs, DROPPED).
    if (slot == 0xFFFFFFFFu) return;
    uint material_flags = updates[i].material_flags;
    // Every update's threads write the same flag, so no atomics are needed.
    if (pc.marks_blocks != 0u) block_words[(slot / CULL_BLOCK) * BLOCK_BOUND_WORDS + BLOCK_BOUND_FLAGS_WORD] = BLOCK_TESTS_EVERY_SLOT;
    vec4 rows[3];
    for (uint r = 0u; r < 3u; ++r) {
        rows[r] = uintBitsToFloat(w[r]);
        set_instance_word(slot, r, w[r]);
    }
    set_instance_word(slot, 3u, uvec4(w[3].xyz, material_flags));
    vec3 lo_t = uintBitsToFloat(w[3].xyz);
    uint group = updates[i].group;
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

    uint flags = (material_flags >> 24) & 0x7Fu;
    uint group_flags = group | (flags << 24) | (huge ? CULL_HUGE : 0u);
    record_vec[slot * 2u] = uvec4(floatBitsToUint(rows[0].w), floatBitsToUint(rows[1].w),
                                  floatBitsToUint(rows[2].w), group_flags);
    record_vec[slot * 2u + 1u] = huge ? uvec4(0u)
        : uvec4(lo_xy, lo_z | (half_up(radius) << 16), half_up(half_extent.x) | (half_up(half_extent.y) << 16),
                half_up(half_extent.z));
}
