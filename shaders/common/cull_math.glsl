// Conservative culling math: frustum tests, screen rectangles with nearest depths, Hi-Z level
// choice and the Hi-Z occlusion test. GPU twin of src/cull/math.rs (and of
// `is_occluded` in src/cull/hiz.rs): the same names without the `cull_` prefix, the same f32
// operations in the same order. Every float temporary is `precise` so that no multiply-add is
// fused and the GPU makes the same decisions as the CPU oracle (tests/cull_math_gpu.rs): a fused
// multiply-add rounds once where the oracle rounds twice, which is enough to drift nearest depths
// by many ulps and to move a rectangle by a pixel. A GPU's division need not be correctly
// rounded, so nearest depths may still differ from the oracle's in the last bits.
//
// Conventions (see src/oracle/mod.rs): inputs are eye-relative (world minus eye, after the hi/lo
// subtraction); `rotation` is world->view, view looks down -Z, d = -z_view. Perspective:
// ndc = (sx*x/d - cx, cy - sy*y/d), depth = near / d (infinite far) or
// near*(far - d) / (d*(far - near)); orthographic: ndc = (sx*x - cx, cy - sy*y),
// depth = (far - d) / (far - near). (cx, cy) is the offset of an off-centre projection and of
// the sub-pixel jitter. Pixels: px = (ndc + 1) * size / 2, row 0 at the top.
// Rectangles are inclusive uvec4(x0, y0, x1, y1).
//
// Conservativeness: distances and extents are widened by CULL_REL_EPS * M (M bounds the length of
// the bound's points), perspective tangents by CULL_REL_EPS * (M / d_lo) * (1 + |t|), pixel
// coordinates by CULL_PIXEL_EPS * max(W, H); the derivation is in src/cull/math.rs.
//
// Plain GLSL 4.60, no subgroup operations. Before calling cull_hiz_occluded, define
//     float hiz_load(uint level, uvec2 texel)
// (declared in hiz.glsl) to read the pyramid (an image mip or a flat buffer).
#ifndef CULLGRAPH_CULL_MATH_GLSL
#define CULLGRAPH_CULL_MATH_GLSL

#include "hiz.glsl"

// Relative error allowance 32 * 2^-24.
#define CULL_REL_EPS (1.0 / 524288.0)
// Pixel allowance per pixel of max(W, H): 2^-18.
#define CULL_PIXEL_EPS (1.0 / 262144.0)
// Largest M / d_lo projected in perspective (2^15); beyond: treated as crossing the near plane.
#define CULL_MAX_CONDITION 32768.0
// Coordinates beyond this (in magnitude) are treated as visible (keeps squares finite).
#define CULL_MAX_COORD 1152921504606846976.0
#define CULL_BIG 1.0e30

// Small-object test: the rectangle is widened by this many pixels more (vertex snapping to a
// 4-bit sub-pixel grid moves an edge by 1/32 pixel; the vertex shader's own rounding stays below
// 1/16 while M / d_lo <= CULL_SMALL_CONDITION), and only bounds this well conditioned are tested.
#define CULL_SAMPLE_MARGIN 0.125
#define CULL_SMALL_CONDITION 4.0

// cull_project_* results.
#define CULL_CROSSES_NEAR 0u
#define CULL_OFF_SCREEN 1u
#define CULL_ON_SCREEN 2u

struct CullView {
    mat3 rotation;    // world -> view
    vec2 scale;       // (sx, sy)
    float near;       // near-plane distance (depth 1)
    float far;        // far-plane distance (depth 0); +infinity for a perspective without one
    uint orthographic;// 0: perspective, 1: orthographic
    uvec2 viewport;   // target size in pixels = Hi-Z level 0 size
    vec2 offset;      // (cx, cy): NDC offset (off-centre projection, jitter)
};

// rotation * p, summed as (r0*x + r1*y) + r2*z per row.
vec3 cull_to_view(mat3 r, vec3 p) {
    precise float x = (r[0].x * p.x + r[1].x * p.y) + r[2].x * p.z;
    precise float y = (r[0].y * p.x + r[1].y * p.y) + r[2].y * p.z;
    precise float z = (r[0].z * p.x + r[1].z * p.y) + r[2].z * p.z;
    return vec3(x, y, z);
}

float cull_l1(vec3 v) {
    precise float s = (abs(v.x) + abs(v.y)) + abs(v.z);
    return s;
}

float cull_dot(vec3 a, vec3 b) {
    precise float s = (a.x * b.x + a.y * b.y) + a.z * b.z;
    return s;
}

bool cull_finite3(vec3 v) {
    return !any(isnan(v)) && !any(isinf(v)) && all(lessThanEqual(abs(v), vec3(CULL_MAX_COORD)));
}

bool cull_finite1(float v) {
    return !isnan(v) && !isinf(v) && abs(v) <= CULL_MAX_COORD;
}

// Frustum test of a sphere: false only when it lies entirely outside one plane (4 sides, near,
// far) by more than its radius plus the allowance.
bool cull_sphere_in_frustum(CullView view, vec3 center, float radius) {
    if (!cull_finite3(center) || !cull_finite1(radius)) return true;
    precise vec3 c = cull_to_view(view.rotation, center);
    precise float d = -c.z;
    precise float rm = radius + CULL_REL_EPS * (cull_l1(center) + radius);
    precise float sx = view.scale.x;
    precise float sy = view.scale.y;
    precise float cx = view.offset.x;
    precise float cy = view.offset.y;
    if (d + rm < view.near || d - rm > view.far) return false;
    if (view.orthographic == 0u) {
        precise float wl = 1.0 - cx;
        precise float wr = 1.0 + cx;
        precise float wb = 1.0 - cy;
        precise float wt = 1.0 + cy;
        precise float ll = sqrt(sx * sx + wl * wl);
        precise float lr = sqrt(sx * sx + wr * wr);
        precise float lb = sqrt(sy * sy + wb * wb);
        precise float lt = sqrt(sy * sy + wt * wt);
        precise float sxx = sx * c.x;
        precise float syy = sy * c.y;
        precise float el = sxx + wl * d;
        precise float er = wr * d - sxx;
        precise float eb = syy + wb * d;
        precise float et = wt * d - syy;
        precise float bl = -(rm * ll);
        precise float br = -(rm * lr);
        precise float bb = -(rm * lb);
        precise float bt = -(rm * lt);
        if (el < bl || er < br) return false;
        if (eb < bb || et < bt) return false;
    } else {
        precise float ox = CULL_REL_EPS * abs(cx);
        precise float oy = CULL_REL_EPS * abs(cy);
        precise float xl = sx * (c.x - rm) - cx;
        precise float xh = sx * (c.x + rm) - cx;
        precise float yl = sy * (c.y - rm) - cy;
        precise float yh = sy * (c.y + rm) - cy;
        precise float bx = 1.0 + ox;
        precise float by = 1.0 + oy;
        if (xl > bx || xh < -bx) return false;
        if (yl > by || yh < -by) return false;
    }
    return true;
}

// Largest n.p + w over the box (center, half).
float cull_reach(vec3 n, float w, vec3 center, vec3 half_extent) {
    precise float s = (cull_dot(n, center) + cull_dot(abs(n), half_extent)) + w;
    return s;
}

// Frustum test of an eye-relative axis-aligned box.
bool cull_aabb_in_frustum(CullView view, vec3 bmin, vec3 bmax) {
    if (!cull_finite3(bmin) || !cull_finite3(bmax)) return true;
    precise vec3 center = (bmin + bmax) * 0.5;
    precise vec3 half_extent = abs(bmax - bmin) * 0.5;
    precise float m = CULL_REL_EPS * (cull_l1(center) + cull_l1(half_extent));
    mat3 r = view.rotation;
    vec3 row0 = vec3(r[0].x, r[1].x, r[2].x);
    vec3 row1 = vec3(r[0].y, r[1].y, r[2].y);
    vec3 row2 = vec3(r[0].z, r[1].z, r[2].z);
    precise float sx = view.scale.x;
    precise float sy = view.scale.y;
    precise float cx = view.offset.x;
    precise float cy = view.offset.y;
    if (cull_reach(-row2, -view.near, center, half_extent) < -m) return false;
    if (cull_reach(row2, view.far, center, half_extent) < -m) return false;
    precise vec3 ax = row0 * sx;
    precise vec3 ay = row1 * sy;
    precise float wl = 1.0 - cx;
    precise float wr = 1.0 + cx;
    precise float wb = 1.0 - cy;
    precise float wt = 1.0 + cy;
    if (view.orthographic == 0u) {
        precise float ll = sqrt(sx * sx + wl * wl);
        precise float lr = sqrt(sx * sx + wr * wr);
        precise float lb = sqrt(sy * sy + wb * wb);
        precise float lt = sqrt(sy * sy + wt * wt);
        precise vec3 nl = ax - row2 * wl;
        precise vec3 nr = -ax - row2 * wr;
        precise vec3 nb = ay - row2 * wb;
        precise vec3 nt = -ay - row2 * wt;
        if (cull_reach(nl, 0.0, center, half_extent) < -(m * ll) || cull_reach(nr, 0.0, center, half_extent) < -(m * lr)) return false;
        if (cull_reach(nb, 0.0, center, half_extent) < -(m * lb) || cull_reach(nt, 0.0, center, half_extent) < -(m * lt)) return false;
    } else {
        precise float ox = CULL_REL_EPS * abs(cx);
        precise float oy = CULL_REL_EPS * abs(cy);
        precise float bx = -(m * sx) - ox;
        precise float by = -(m * sy) - oy;
        if (cull_reach(ax, wl, center, half_extent) < bx || cull_reach(-ax, wr, center, half_extent) < bx) return false;
        if (cull_reach(ay, wb, center, half_extent) < by || cull_reach(-ay, wt, center, half_extent) < by) return false;
    }
    return true;
}

// Tangents x/d from the eye to the circle of radius r around (a, d) (Mara & McGuire 2013):
// vec2(lo, hi). czr2 = (d - r) * (d + r).
vec2 cull_tangents(float a, float d, float r, float czr2) {
    precise float v = sqrt(a * a + czr2);
    precise float num_lo = v * a - r * d;
    precise float den_lo = v * d + r * a;
    precise float num_hi = v * a + r * d;
    precise float den_hi = v * d - r * a;
    precise float lo = den_lo > 0.0 ? max(num_lo / den_lo, -CULL_BIG) : -CULL_BIG;
    precise float hi = den_hi > 0.0 ? min(num_hi / den_hi, CULL_BIG) : CULL_BIG;
    return vec2(lo, hi);
}

// The sample positions of Vulkan's standard 1, 2, 4 and 8-sample patterns together, in
// sixteenths of a pixel from its top-left corner (the 1-sample centre, then 2x, 4x, 8x).
const uvec2 CULL_SAMPLES[15] = uvec2[15](
    uvec2(8u, 8u), uvec2(12u, 12u), uvec2(4u, 4u), uvec2(6u, 2u), uvec2(14u, 6u), uvec2(2u, 10u), uvec2(10u, 14u),
    uvec2(9u, 5u), uvec2(7u, 11u), uvec2(13u, 9u), uvec2(5u, 3u), uvec2(3u, 13u), uvec2(1u, 7u), uvec2(11u, 15u),
    uvec2(15u, 1u));

// Whether the pixel-space box [x_lo, x_hi] x [y_lo, y_hi] (inclusive) holds a sample position
// of any standard pattern; boxes 2 pixels or more across always do.
bool cull_box_covers_sample(float x_lo, float x_hi, float y_lo, float y_hi) {
    if (!(x_hi - x_lo < 2.0) || !(y_hi - y_lo < 2.0)) return true;
    precise float px0 = floor(x_lo);
    precise float py0 = floor(y_lo);
    for (float py = py0; py <= y_hi; py += 1.0) {
        for (float px = px0; px <= x_hi; px += 1.0) {
            for (uint i = 0u; i < 15u; ++i) {
                precise float x = px + float(CULL_SAMPLES[i].x) * 0.0625;
                precise float y = py + float(CULL_SAMPLES[i].y) * 0.0625;
                if (x >= x_lo && x <= x_hi && y >= y_lo && y <= y_hi) return true;
            }
        }
    }
    return false;
}

// NDC extents (widened) -> inclusive pixel rectangle; false when off screen. `covers_sample`:
// whether the extents, widened by CULL_SAMPLE_MARGIN pixels, may hold a sample position (always
// when `testable` is false).
bool cull_pixel_rect(CullView view, vec2 lo, vec2 hi, bool testable, out uvec4 rect, out bool covers_sample) {
    precise float w = float(view.viewport.x);
    precise float h = float(view.viewport.y);
    precise float pe = max(w, h) * CULL_PIXEL_EPS;
    precise float fx_lo = (clamp(lo.x, -2.0, 2.0) + 1.0) * (0.5 * w) - pe;
    precise float fx_hi = (clamp(hi.x, -2.0, 2.0) + 1.0) * (0.5 * w) + pe;
    precise float fy_lo = (clamp(lo.y, -2.0, 2.0) + 1.0) * (0.5 * h) - pe;
    precise float fy_hi = (clamp(hi.y, -2.0, 2.0) + 1.0) * (0.5 * h) + pe;
    covers_sample = !testable ||
        cull_box_covers_sample(fx_lo - CULL_SAMPLE_MARGIN, fx_hi + CULL_SAMPLE_MARGIN, fy_lo - CULL_SAMPLE_MARGIN,
                               fy_hi + CULL_SAMPLE_MARGIN);
    precise float x_lo = floor(fx_lo);
    precise float x_hi = floor(fx_hi);
    precise float y_lo = floor(fy_lo);
    precise float y_hi = floor(fy_hi);
    rect = uvec4(0u);
    if (x_hi < 0.0 || y_hi < 0.0 || x_lo >= w || y_lo >= h) return false;
    rect = uvec4(uint(max(x_lo, 0.0)), uint(max(y_lo, 0.0)), uint(min(x_hi, w - 1.0)), uint(min(y_hi, h - 1.0)));
    return true;
}

// Extents t = (lo, hi) in x and u in y (y up) with outward allowances et, eu = (lo, hi).
// `testable`: the bound is conditioned well enough for the small-object test.
uint cull_finish(CullView view, vec2 t, vec2 et, vec2 u, vec2 eu, float d_lo, bool testable, out uvec4 rect,
                 out float nearest_depth, out bool covers_sample) {
    precise float sx = view.scale.x;
    precise float sy = view.scale.y;
    precise float cx = view.offset.x;
    precise float cy = view.offset.y;
    precise float ox = CULL_REL_EPS * abs(cx);
    precise float oy = CULL_REL_EPS * abs(cy);
    precise vec2 lo = vec2((sx * (t.x - et.x) - cx) - ox, (cy - sy * (u.y + eu.y)) - oy);
    precise vec2 hi = vec2((sx * (t.y + et.y) - cx) + ox, (cy - sy * (u.x - eu.x)) + oy);
    precise float depth;
    if (view.orthographic != 0u) {
        depth = (view.far - (d_lo - CULL_REL_EPS * view.far)) / (view.far - view.near);
    } else if (view.far <= CULL_MAX_COORD) {
        // Finite far: near*far/(d*(far - near)) - near/(far - near), the first term raised.
        precise float k = (view.near / d_lo) * (view.far / (view.far - view.near));
        depth = max((k + CULL_REL_EPS * k) - view.near / (view.far - view.near), 0.0);
    } else {
        depth = view.near / d_lo;
    }
    nearest_depth = depth;
    return cull_pixel_rect(view, lo, hi, testable, rect, covers_sample) ? CULL_ON_SCREEN : CULL_OFF_SCREEN;
}

// Screen rectangle and nearest reversed-Z depth of an eye-relative sphere. Returns
// CULL_CROSSES_NEAR (visible, not projected), CULL_OFF_SCREEN or CULL_ON_SCREEN.
// `covers_sample` (CULL_ON_SCREEN only): false when the bound covers no sample position of any
// standard pattern, so that nothing inside it can make a fragment.
uint cull_project_sphere(CullView view, vec3 center, float radius, out uvec4 rect, out float nearest_depth,
                         out bool covers_sample) {
    rect = uvec4(0u);
    nearest_depth = 1.0;
    covers_sample = true;
    if (!cull_finite3(center) || !cull_finite1(radius) || radius < 0.0) return CULL_CROSSES_NEAR;
    precise vec3 c = cull_to_view(view.rotation, center);
    precise float d = -c.z;
    precise float m = cull_l1(center) + radius;
    precise float margin = CULL_REL_EPS * m;
    precise float d_lo = (d - radius) - margin;
    if (!(d_lo >= view.near)) return CULL_CROSSES_NEAR;
    if (view.orthographic != 0u) {
        bool testable = m * view.scale.y <= 2.0 * CULL_SMALL_CONDITION;
        return cull_finish(view, vec2(c.x - radius, c.x + radius), vec2(margin), vec2(c.y - radius, c.y + radius),
                           vec2(margin), d_lo, testable, rect, nearest_depth, covers_sample);
    }
    if (m > d_lo * CULL_MAX_CONDITION) return CULL_CROSSES_NEAR;
    precise float q = margin / d_lo;
    precise float czr2 = (d - radius) * (d + radius);
    precise vec2 tx = cull_tangents(c.x, d, radius, czr2);
    precise vec2 ty = cull_tangents(c.y, d, radius, czr2);
    precise vec2 ex = vec2(q * (1.0 + abs(tx.x)), q * (1.0 + abs(tx.y)));
    precise vec2 ey = vec2(q * (1.0 + abs(ty.x)), q * (1.0 + abs(ty.y)));
    return cull_finish(view, tx, ex, ty, ey, d_lo, m <= d_lo * CULL_SMALL_CONDITION, rect, nearest_depth, covers_sample);
}

uint cull_project_sphere(CullView view, vec3 center, float radius, out uvec4 rect, out float nearest_depth) {
    bool covers_sample;
    return cull_project_sphere(view, center, radius, rect, nearest_depth, covers_sample);
}

// Screen rectangle and nearest reversed-Z depth of an eye-relative axis-aligned box (8 corners).
uint cull_project_aabb(CullView view, vec3 bmin, vec3 bmax, out uvec4 rect, out float nearest_depth,
                       out bool covers_sample) {
    rect = uvec4(0u);
    nearest_depth = 1.0;
    covers_sample = true;
    if (!cull_finite3(bmin) || !cull_finite3(bmax)) return CULL_CROSSES_NEAR;
    precise float m = (max(abs(bmin.x), abs(bmax.x)) + max(abs(bmin.y), abs(bmax.y))) + max(abs(bmin.z), abs(bmax.z));
    precise float margin = CULL_REL_EPS * m;
    vec3 corners[8];
    precise float d_min = CULL_BIG;
    for (uint i = 0u; i < 8u; ++i) {
        vec3 p = vec3((i & 1u) == 0u ? bmin.x : bmax.x, (i & 2u) == 0u ? bmin.y : bmax.y,
                      (i & 4u) == 0u ? bmin.z : bmax.z);
        corners[i] = cull_to_view(view.rotation, p);
        d_min = min(d_min, -corners[i].z);
    }
    precise float d_lo = d_min - margin;
    if (!(d_lo >= view.near)) return CULL_CROSSES_NEAR;
    precise vec2 t = vec2(CULL_BIG, -CULL_BIG);
    precise vec2 u = vec2(CULL_BIG, -CULL_BIG);
    if (view.orthographic != 0u) {
        for (uint i = 0u; i < 8u; ++i) {
            t = vec2(min(t.x, corners[i].x), max(t.y, corners[i].x));
            u = vec2(min(u.x, corners[i].y), max(u.y, corners[i].y));
        }
        bool testable = m * view.scale.y <= 2.0 * CULL_SMALL_CONDITION;
        return cull_finish(view, t, vec2(margin), u, vec2(margin), d_lo, testable, rect, nearest_depth, covers_sample);
    }
    if (m > d_lo * CULL_MAX_CONDITION) return CULL_CROSSES_NEAR;
    for (uint i = 0u; i < 8u; ++i) {
        precise float d = -corners[i].z;
        precise float tc = corners[i].x / d;
        precise float uc = corners[i].y / d;
        t = vec2(min(t.x, tc), max(t.y, tc));
        u = vec2(min(u.x, uc), max(u.y, uc));
    }
    precise float q = margin / d_lo;
    precise vec2 et = vec2(q * (1.0 + abs(t.x)), q * (1.0 + abs(t.y)));
    precise vec2 eu = vec2(q * (1.0 + abs(u.x)), q * (1.0 + abs(u.y)));
    return cull_finish(view, t, et, u, eu, d_lo, m <= d_lo * CULL_SMALL_CONDITION, rect, nearest_depth, covers_sample);
}

uint cull_project_aabb(CullView view, vec3 bmin, vec3 bmax, out uvec4 rect, out float nearest_depth) {
    bool covers_sample;
    return cull_project_aabb(view, bmin, bmax, rect, nearest_depth, covers_sample);
}

// ceil(log2(n)) for n >= 1 (0 for n <= 1).
uint cull_ceil_log2(uint n) {
    return n <= 1u ? 0u : uint(findMSB(n - 1u) + 1);
}

// Hi-Z level whose texels the rectangle touches at most 2x2 of: ceil(log2(max(w, h))) (proof in
// src/cull/math.rs, `hiz_level`). The caller clamps it to the pyramid's last level.
uint cull_hiz_level(uvec4 rect) {
    uint w = rect.z - rect.x + 1u;
    uint h = rect.w - rect.y + 1u;
    return cull_ceil_log2(max(w, h));
}

// The finest chain level the pyramid holds. 0 for a full pyramid; the hiz_build pass stores
// levels from HIZ_FIRST_LEVEL (hiz.glsl), and a shader reading that pyramid defines this to it.
// A coarser level than the rectangle needs is still conservative: its texels cover more.
#ifndef CULL_HIZ_MIN_LEVEL
#define CULL_HIZ_MIN_LEVEL 0u
#endif

// Hi-Z occlusion test of a projected bound against a min (reversed-Z) pyramid whose level 0 is
// `base_size`: occluded iff nearest_depth < every texel covering the rectangle. `finer` reads
// level max(L - 1, 0) (at most 3x3 texels, culls at least as much) instead of L (at most 2x2);
// neither goes below CULL_HIZ_MIN_LEVEL.
bool cull_hiz_occluded(uvec4 rect, float nearest_depth, uvec2 base_size, bool finer) {
    uint last = max(hiz_level_count(base_size) - 1u, CULL_HIZ_MIN_LEVEL);
    uint level = min(cull_hiz_level(rect), last);
    if (finer && level > 0u) level -= 1u;
    level = max(level, CULL_HIZ_MIN_LEVEL);
    uvec2 size = hiz_level_size(base_size, level);
    uvec2 lo = hiz_texel_of_pixel(rect.xy, level, size);
    uvec2 hi = hiz_texel_of_pixel(rect.zw, level, size);
    // At most 2x2 texels (the coarse footprint): the four loads at once, not one after another
    // (a smaller footprint loads some texel twice).
    if (hi.x - lo.x <= 1u && hi.y - lo.y <= 1u) {
        float d00 = hiz_load(level, lo);
        float d10 = hiz_load(level, uvec2(hi.x, lo.y));
        float d01 = hiz_load(level, uvec2(lo.x, hi.y));
        float d11 = hiz_load(level, hi);
        bool behind = nearest_depth < d00;
        behind = behind && nearest_depth < d10;
        behind = behind && nearest_depth < d01;
        return behind && nearest_depth < d11;
    }
    for (uint ty = lo.y; ty <= hi.y; ++ty) {
        for (uint tx = lo.x; tx <= hi.x; ++tx) {
            if (!(nearest_depth < hiz_load(level, uvec2(tx, ty)))) return false;
        }
    }
    return true;
}

#endif
