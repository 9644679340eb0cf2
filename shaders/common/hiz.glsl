// Hi-Z pyramid geometry for any size (non-power-of-two and odd levels): level sizes, offsets in a
// flat buffer, reduction footprints, and which texel of a level covers a level-0 pixel. GPU twin
// of src/cull/hiz.rs (same names without the `hiz_` prefix). Integer addressing only.
//
// Level k+1 is max(1, size_k >> 1) per axis. Texel x of level k+1 reduces (min, reversed-Z) the
// source texels 2x .. 2x+1, plus 2x+2 when x is the last texel and size_k is odd (the dropped
// column is folded into the edge: footprints 2x2, 2x3, 3x2, 3x3), or just texel 0 when size_k is
// 1. Hence pixel p of level 0 is covered at level k by texel min(p >> k, size_k - 1).
#ifndef CULLGRAPH_HIZ_GLSL
#define CULLGRAPH_HIZ_GLSL

// Size of `level` for a pyramid whose level 0 is `base`: max(1, base >> level) per axis.
uvec2 hiz_level_size(uvec2 base, uint level) {
    return max(base >> uvec2(min(level, 31u)), uvec2(1u));
}

// Number of levels down to 1x1: floor(log2(max(w, h))) + 1.
uint hiz_level_count(uvec2 base) {
    return uint(findMSB(max(max(base.x, base.y), 1u))) + 1u;
}

// First texel of `level` in a flat, row-major buffer holding all levels one after another.
uint hiz_level_offset(uvec2 base, uint level) {
    uint offset = 0u;
    for (uint k = 0u; k < level; ++k) {
        uvec2 s = hiz_level_size(base, k);
        offset += s.x * s.y;
    }
    return offset;
}

// The texel of a level of size `size` that covers level-0 pixel `pixel`.
uvec2 hiz_texel_of_pixel(uvec2 pixel, uint level, uvec2 size) {
    return min(pixel >> uvec2(min(level, 31u)), size - 1u);
}

// Number of source texels along one axis that destination texel `dst` reduces, for a source
// level `src` texels long: 1 (src == 1), 3 (last texel of an odd source) or 2.
uint hiz_footprint_count(uint dst, uint src) {
    if (src <= 1u) return 1u;
    uint dst_size = src >> 1u;
    return (dst == dst_size - 1u && (src & 1u) == 1u) ? 3u : 2u;
}

// Footprint of destination texel `dst` in a source level of size `src_size`: the source texels
// first .. first + count - 1 per axis.
void hiz_footprint(uvec2 dst, uvec2 src_size, out uvec2 first, out uvec2 count) {
    first = dst * 2u;
    count = uvec2(hiz_footprint_count(dst.x, src_size.x), hiz_footprint_count(dst.y, src_size.y));
}

// The stored pyramid (the `hiz` image the hiz_build pass writes) starts at chain level
// HIZ_FIRST_LEVEL = 1, half the depth's size: stored mip m holds chain level m + 1, whose size is
// hiz_level_size(depth_size, m + 1) and whose texels follow the rules above with level 0 = the
// depth (min over samples). Level 0 itself is never stored (reading it would cost as much as the
// depth). A 1x1 depth has no level 1: its pyramid is one 1x1 texel, the min of the depth (the
// same rule: the last texel of a level covers everything to the edge, so "level 1" of a 1x1
// depth is its single pixel). So a chain level L >= 1 lives in stored mip L - 1, and the usable
// chain levels are 1 ..= hiz_stored_last_level(depth_size).
#define HIZ_FIRST_LEVEL 1u

// Stored mips of a full pyramid over a depth of size `base`: hiz_level_count(base) - 1, at least 1.
uint hiz_stored_mip_count(uvec2 base) {
    return max(hiz_level_count(base) - HIZ_FIRST_LEVEL, 1u);
}

// The last chain level a full stored pyramid holds: hiz_level_count(base) - 1, at least 1.
uint hiz_stored_last_level(uvec2 base) {
    return hiz_stored_mip_count(base) + HIZ_FIRST_LEVEL - 1u;
}

// The stored mip that holds chain level `level` (>= HIZ_FIRST_LEVEL).
uint hiz_stored_mip(uint level) {
    return level - HIZ_FIRST_LEVEL;
}

// Reads one texel of chain level `level` of the pyramid; defined by the shader that includes this
// header (a stored image pyramid: mip hiz_stored_mip(level) with imageLoad/texelFetch; or a flat
// buffer with hiz_level_offset). Needed by cull_hiz_occluded in cull_math.glsl.
float hiz_load(uint level, uvec2 texel);

#endif
