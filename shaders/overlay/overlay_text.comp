#version 460
// Overlay, step 1: formats the panel's text. One thread per row walks the row's template and
// writes its characters, numbers formatted here from this frame's counters (no readback), into
// the character grid; the rows' lengths give the panel width. Variant HAS_MARKS also reads the
// number of instances the culled view outlined, HAS_GBUFFER the compressed G-buffer's counters.
#extension GL_GOOGLE_include_directive : require
#include "../cull/cull_common.glsl"
#include "overlay_common.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, scalar) readonly buffer Stats0 { CullStats s0; };
layout(set = 0, binding = 1, scalar) readonly buffer Stats1 { CullStats s1; };
layout(set = 0, binding = 2, scalar) readonly buffer Stats2 { CullStats s2; };
layout(set = 0, binding = 3, scalar) readonly buffer Stats3 { CullStats s3; };
layout(set = 0, binding = 4, scalar) readonly buffer Template { OverlayTemplate tpl; };
layout(set = 0, binding = 5, scalar) readonly buffer Times { OverlayTimes times; };
layout(set = 0, binding = 6, scalar) writeonly buffer Text { OverlayText text; };
#ifdef HAS_MARKS
layout(set = 0, binding = 7) readonly buffer Marks { uint marked; };
#endif
#ifdef HAS_GBUFFER
// A lighting_compressed pass's counters (GbufferCounters in src/stats/gbuffer.rs), this frame's.
layout(set = 0, binding = 8) readonly buffer GbufferStats {
    uint allocated;
    uint overflow_fragments;
    uint overflow_samples;
    uint pool_blocks;
    uint pixels;
    uint pad[3];
    uint histogram[8];   // pixels with 2..8 surfaces in [1..7]
} gstats;
#endif

layout(push_constant) uniform Push {
    uint stats_count;      // bound stats slots (the first ones)
    uint instances;        // scene instances
    uint all_draws;        // without cull counters: every non-empty draw group
    uint all_triangles_lo; // without cull counters: every triangle
    uint all_triangles_hi;
} pc;

shared uint sh_cols;
shared uint sh_max_ms;   // bits of the largest time (non-negative floats order like their bits)

CullStats stats_of(uint k) {
    if (k == 0u) return s0;
    if (k == 1u) return s1;
    if (k == 2u) return s2;
    return s3;
}

uint line[OVERLAY_MAX_COLS];
uint len;

void put(uint c) {
    if (len < OVERLAY_MAX_COLS) line[len] = c;
    len += 1u;
}

void put_u32(uint v) {
    uint digits[10];
    uint n = 0u;
    do {
        digits[n++] = v % 10u;
        v /= 10u;
    } while (v != 0u && n < 10u);
    while (n > 0u) put((48u + digits[--n]) | CELL_NUMBER);
}

// A 64-bit value (lo, hi) in decimal: long division by 10 over 16-bit limbs.
void put_u64(uint lo, uint hi) {
    uint limbs[4] = uint[4](hi >> 16, hi & 0xFFFFu, lo >> 16, lo & 0xFFFFu);
    uint digits[20];
    uint n = 0u;
    do {
        uint rem = 0u;
        bool zero = true;
        for (uint i = 0u; i < 4u; ++i) {
            uint cur = (rem << 16) | limbs[i];
            limbs[i] = cur / 10u;
            rem = cur % 10u;
            zero = zero && limbs[i] == 0u;
        }
        digits[n++] = rem;
        if (zero) break;
    } while (n < 20u);
    while (n > 0u) put((48u + digits[--n]) | CELL_NUMBER);
}

// Milliseconds with three decimals, right-aligned in 8 characters; "-" when unknown.
void put_ms(float ms) {
    uint start = len;
    uint chars[8];
    uint n = 0u;
    if (!(ms >= 0.0)) {
        chars[n++] = 45u;
    } else {
        uint v = uint(round(min(ms, 9999.999) * 1000.0));
        for (uint i = 0u; i < 3u; ++i) {
            chars[n++] = 48u + v % 10u;
            v /= 10u;
        }
        chars[n++] = 46u;
        do {
            chars[n++] = 48u + v % 10u;
            v /= 10u;
        } while (v != 0u && n < 8u);
    }
    for (uint i = n; i < 8u; ++i) put(32u);
    while (n > 0u) put(chars[--n] | CELL_NUMBER);
}

void main() {
    uint row = gl_LocalInvocationIndex;
    if (row == 0u) {
        sh_cols = 0u;
        sh_max_ms = 0u;
    }
    barrier();

    // The frame's totals, as crate::stats::cull::totals makes them.
    uint tested = 0u, frustum = 0u, occlusion = 0u, drawn = 0u, draws = 0u;
    uint tri_lo = 0u, tri_hi = 0u;
    if (pc.stats_count == 0u) {
        tested = 0u;
        drawn = pc.instances;
        draws = pc.all_draws;
        tri_lo = pc.all_triangles_lo;
        tri_hi = pc.all_triangles_hi;
    }
    for (uint k = 0u; k < pc.stats_count; ++k) {
        CullStats s = stats_of(k);
        if (s.tested >= tested) {  // the last of equals, like Iterator::max_by_key
            tested = s.tested;
            frustum = s.frustum_culled;
            occlusion = s.occlusion_culled;
        }
        drawn += s.drawn;
        draws += s.draws;
        uint lo = tri_lo + s.triangles_lo;
        tri_hi += s.triangles_hi + (lo < tri_lo ? 1u : 0u);
        tri_lo = lo;
    }

    len = 0u;
    int bar = -1;
    if (row < tpl.rows) {
        bar = tpl.row_bar[row];
        for (uint t = 0u; t < OVERLAY_MAX_COLS; ++t) {
            uint token = tpl.tokens[row * OVERLAY_MAX_COLS + t];
            if (token == TOKEN_END) break;
            if ((token & TOKEN_FIELD) == 0u) {
                put(token);
                continue;
            }
            uint field = token & ~TOKEN_FIELD;
            if (field == FIELD_INSTANCES) put_u32(pc.instances);
            else if (field == FIELD_TESTED) put_u32(tested);
            else if (field == FIELD_FRUSTUM) put_u32(frustum);
            else if (field == FIELD_OCCLUSION) put_u32(occlusion);
            else if (field == FIELD_DRAWN) put_u32(drawn);
            else if (field == FIELD_DRAWS) put_u32(draws);
            else if (field == FIELD_TRIANGLES) put_u64(tri_lo, tri_hi);
            else if (field == FIELD_TOTAL_MS) put_ms(times.total_ms);
            else if (field == FIELD_TIMED_FRAME) {
                if (times.frame == 0xFFFFFFFFu) put(45u);
                else put_u32(times.frame);
            }
#ifdef HAS_MARKS
            else if (field == FIELD_MARKED) put_u32(marked);
#endif
#ifdef HAS_GBUFFER
            else if (field == FIELD_POOL_USED) put_u32(min(gstats.allocated, gstats.pool_blocks));
            else if (field == FIELD_POOL_BLOCKS) put_u32(gstats.pool_blocks);
            else if (field == FIELD_OVERFLOW) put_u32(gstats.overflow_samples);
            else if (field == FIELD_EDGE_PIXELS) {
                uint edges = 0u;
                for (uint k = 1u; k < 8u; ++k) edges += gstats.histogram[k];
                put_u32(edges);
            }
#endif
            else if (field >= FIELD_PASS_DRAWN && field < FIELD_PASS_DRAWN + OVERLAY_MAX_STATS) {
                uint k = field - FIELD_PASS_DRAWN;
                put_u32(k < pc.stats_count ? stats_of(k).drawn : 0u);
            } else if (field >= FIELD_PASS_MS && field < FIELD_PASS_MS + OVERLAY_MAX_TIMED) {
                uint k = field - FIELD_PASS_MS;
                put_ms(k < times.count ? times.ms[k] : -1.0);
            }
        }
        len = min(len, OVERLAY_MAX_COLS);
        for (uint c = 0u; c < OVERLAY_MAX_COLS; ++c) {
            text.cells[row * OVERLAY_MAX_COLS + c] = c < len ? line[c] : 0u;
        }
        uint width = len;
        if (bar >= 0 && tpl.bar_chars > 0u) {
            width = max(width, tpl.bar_col + tpl.bar_chars);
            float ms = uint(bar) < times.count ? times.ms[bar] : -1.0;
            if (ms > 0.0) atomicMax(sh_max_ms, floatBitsToUint(ms));
        }
        atomicMax(sh_cols, width);
    }
    barrier();
    if (row < OVERLAY_MAX_ROWS) {
        float largest = uintBitsToFloat(sh_max_ms);
        float ms = bar >= 0 && uint(bar) < times.count ? times.ms[bar] : -1.0;
        text.bar[row] = (row < tpl.rows && bar >= 0 && ms >= 0.0 && largest > 0.0) ? min(ms / largest, 1.0) : -1.0;
    }
    if (row == 0u) {
        text.rows = tpl.rows;
        text.cols = sh_cols;
        text.bar_col = tpl.bar_col;
        text.bar_chars = tpl.bar_chars;
    }
}
