#version 460
// FXAA 3.11, the PC "quality" algorithm (Timothy Lottes, NVIDIA), as a compute pass over the lit
// image: local contrast test, horizontal/vertical edge choice, search along the edge in both
// directions with bilinear taps placed between the two rows (or columns) of the edge, blend
// toward the neighbour across the edge by the pixel's position on the span, and a subpixel blend
// for isolated features. Luma is computed from the sRGB-encoded value the lighting wrote
// (Rec. 601 weights), as FXAA expects of a gamma-space input.
//
// PRESET selects FXAA's search schedule (10, 12, 15, 23, 29 or 39; 39 is "extreme quality").

layout(local_size_x = 16, local_size_y = 16) in;

layout(set = 0, binding = 0) uniform sampler2D in_color;  // bilinear, clamp to edge
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D out_color;

layout(push_constant) uniform Settings {
    // Amount of subpixel aliasing removal (1.0 upper limit softer, 0.75 default, 0.0 off).
    float subpix;
    // Minimum local contrast, relative to the local maximum, to apply the algorithm (0.166 default).
    float edge_threshold;
    // Minimum local contrast in absolute luma, trims the algorithm from dark areas (0.0833 default).
    float edge_threshold_min;
} settings;

#ifndef PRESET
#define PRESET 39
#endif

#if PRESET == 10
const int STEPS = 3;
const float STEP[STEPS] = float[](1.5, 3.0, 12.0);
#elif PRESET == 12
const int STEPS = 5;
const float STEP[STEPS] = float[](1.0, 1.5, 2.0, 4.0, 12.0);
#elif PRESET == 15
const int STEPS = 8;
const float STEP[STEPS] = float[](1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 12.0);
#elif PRESET == 23
const int STEPS = 6;
const float STEP[STEPS] = float[](1.0, 1.5, 2.0, 2.0, 2.0, 8.0);
#elif PRESET == 29
const int STEPS = 12;
const float STEP[STEPS] = float[](1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0);
#else
const int STEPS = 12;
const float STEP[STEPS] = float[](1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0);
#endif

float luma(vec4 c) { return dot(c.rgb, vec3(0.299, 0.587, 0.114)); }
float luma_at(vec2 uv) { return luma(textureLod(in_color, uv, 0.0)); }
#define LUMA_OFF(uv, x, y) luma(textureLodOffset(in_color, uv, 0.0, ivec2(x, y)))

void main() {
    ivec2 size = imageSize(out_color);
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, size))) return;
    vec2 rcp_frame = 1.0 / vec2(size);
    vec2 pos_m = (vec2(pixel) + 0.5) * rcp_frame;

    // Local contrast over the cross; low-contrast pixels are left as they are.
    vec4 rgby_m = textureLod(in_color, pos_m, 0.0);
    float luma_m = luma(rgby_m);
    float luma_s = LUMA_OFF(pos_m, 0, 1);
    float luma_e = LUMA_OFF(pos_m, 1, 0);
    float luma_n = LUMA_OFF(pos_m, 0, -1);
    float luma_w = LUMA_OFF(pos_m, -1, 0);
    float range_max = max(max(luma_n, luma_w), max(luma_e, max(luma_s, luma_m)));
    float range_min = min(min(luma_n, luma_w), min(luma_e, min(luma_s, luma_m)));
    float range = range_max - range_min;
    if (range < max(settings.edge_threshold_min, range_max * settings.edge_threshold)) {
        imageStore(out_color, pixel, rgby_m);
        return;
    }

    // Diagonals; edge orientation from the 3x3 second differences.
    float luma_nw = LUMA_OFF(pos_m, -1, -1);
    float luma_se = LUMA_OFF(pos_m, 1, 1);
    float luma_ne = LUMA_OFF(pos_m, 1, -1);
    float luma_sw = LUMA_OFF(pos_m, -1, 1);
    float luma_ns = luma_n + luma_s;
    float luma_we = luma_w + luma_e;
    float edge_horz1 = -2.0 * luma_m + luma_ns;
    float edge_vert1 = -2.0 * luma_m + luma_we;
    float luma_nese = luma_ne + luma_se;
    float luma_nwne = luma_nw + luma_ne;
    float edge_horz2 = -2.0 * luma_e + luma_nese;
    float edge_vert2 = -2.0 * luma_n + luma_nwne;
    float luma_nwsw = luma_nw + luma_sw;
    float luma_swse = luma_sw + luma_se;
    float edge_horz4 = abs(edge_horz1) * 2.0 + abs(edge_horz2);
    float edge_vert4 = abs(edge_vert1) * 2.0 + abs(edge_vert2);
    float edge_horz3 = -2.0 * luma_w + luma_nwsw;
    float edge_vert3 = -2.0 * luma_s + luma_swse;
    float edge_horz = abs(edge_horz3) + edge_horz4;
    float edge_vert = abs(edge_vert3) + edge_vert4;

    // Subpixel term: how far the pixel is from its 3x3 low-pass average, relative to the range.
    float subpix_a = (luma_ns + luma_we) * 2.0 + (luma_nwsw + luma_nese);
    float subpix_b = subpix_a * (1.0 / 12.0) - luma_m;
    float subpix_c = clamp(abs(subpix_b) / range, 0.0, 1.0);
    float subpix_f = (-2.0 * subpix_c + 3.0) * subpix_c * subpix_c;
    float subpix_h = subpix_f * subpix_f * settings.subpix;

    // A horizontal edge (luma changes vertically) is searched along x; pick the side (N or S,
    // W or E) with the steeper gradient.
    bool horz_span = edge_horz >= edge_vert;
    float length_sign = horz_span ? rcp_frame.y : rcp_frame.x;
    if (!horz_span) {
        luma_n = luma_w;
        luma_s = luma_e;
    }
    float gradient_n = luma_n - luma_m;
    float gradient_s = luma_s - luma_m;
    bool pair_n = abs(gradient_n) >= abs(gradient_s);
    float gradient = max(abs(gradient_n), abs(gradient_s));
    if (pair_n) length_sign = -length_sign;
    float luma_nn = (pair_n ? luma_n : luma_s) + luma_m;

    // Walk both ways along the edge, half a pixel toward the chosen side, until the average luma
    // of the pair of rows changes by a quarter of the gradient (the end of the edge).
    vec2 pos_b = pos_m;
    vec2 off_np = horz_span ? vec2(rcp_frame.x, 0.0) : vec2(0.0, rcp_frame.y);
    if (horz_span) {
        pos_b.y += length_sign * 0.5;
    } else {
        pos_b.x += length_sign * 0.5;
    }
    vec2 pos_n = pos_b - off_np * STEP[0];
    vec2 pos_p = pos_b + off_np * STEP[0];
    float gradient_scaled = gradient * 0.25;
    float luma_mm = luma_m - luma_nn * 0.5;
    bool luma_m_lt_zero = luma_mm < 0.0;
    float luma_end_n = luma_at(pos_n) - luma_nn * 0.5;
    float luma_end_p = luma_at(pos_p) - luma_nn * 0.5;
    bool done_n = abs(luma_end_n) >= gradient_scaled;
    bool done_p = abs(luma_end_p) >= gradient_scaled;
    if (!done_n) pos_n -= off_np * STEP[1];
    if (!done_p) pos_p += off_np * STEP[1];
    for (int i = 2; i < STEPS && !(done_n && done_p); ++i) {
        if (!done_n) luma_end_n = luma_at(pos_n) - luma_nn * 0.5;
        if (!done_p) luma_end_p = luma_at(pos_p) - luma_nn * 0.5;
        done_n = abs(luma_end_n) >= gradient_scaled;
        done_p = abs(luma_end_p) >= gradient_scaled;
        if (!done_n) pos_n -= off_np * STEP[i];
        if (!done_p) pos_p += off_np * STEP[i];
    }

    // Blend across the edge by where the pixel sits on the span, if the nearer end is one where
    // the edge really ends on this pixel's side; the subpixel term is the floor.
    float dst_n = horz_span ? pos_m.x - pos_n.x : pos_m.y - pos_n.y;
    float dst_p = horz_span ? pos_p.x - pos_m.x : pos_p.y - pos_m.y;
    bool good_span_n = (luma_end_n < 0.0) != luma_m_lt_zero;
    bool good_span_p = (luma_end_p < 0.0) != luma_m_lt_zero;
    bool direction_n = dst_n < dst_p;
    float dst = min(dst_n, dst_p);
    bool good_span = direction_n ? good_span_n : good_span_p;
    float pixel_offset = -dst / (dst_n + dst_p) + 0.5;
    float pixel_offset_subpix = max(good_span ? pixel_offset : 0.0, subpix_h);
    vec2 pos = pos_m;
    if (horz_span) {
        pos.y += pixel_offset_subpix * length_sign;
    } else {
        pos.x += pixel_offset_subpix * length_sign;
    }
    imageStore(out_color, pixel, vec4(textureLod(in_color, pos, 0.0).rgb, rgby_m.a));
}
