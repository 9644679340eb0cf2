// The tone curve and display encoding: Narkowicz's ACES fit, its inverse, and sRGB.
//
// The lighting passes write linear HDR colour (scene radiance, before exposure) and the tonemap
// pass maps it to the display. Where a lighting pass resolves several surfaces of one pixel
// (MSAA edges) it averages their tone-mapped colours, as a display would show the edge, and
// stores the HDR colour whose tone-mapped value is that average (hdr_from_display): a linear
// average would let one bright sample dominate the edge.
#ifndef CULLGRAPH_TONEMAP_GLSL
#define CULLGRAPH_TONEMAP_GLSL

// Narkowicz's ACES fit.
vec3 tonemap_aces(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

// The inverse of tonemap_aces on [0, 1]: the non-negative root of
// (2.43 y - 2.51) x^2 + (0.59 y - 0.03) x + 0.14 y = 0. Its leading coefficient is negative
// and its constant term non-negative, so exactly one root is >= 0. y = 1 (the curve's clamp)
// maps to about 7.24, where the fit reaches 1.
vec3 tonemap_aces_inverse(vec3 y) {
    y = clamp(y, 0.0, 1.0);
    vec3 a = 2.51 - 2.43 * y;   // minus the leading coefficient, > 0
    vec3 b = 0.59 * y - 0.03;
    vec3 c = 0.14 * y;
    vec3 root = sqrt(b * b + 4.0 * a * c);
    // Two forms of the same root, each free of cancellation where it is used: b < 0 for dark
    // values, where b + root would subtract nearly equal numbers.
    vec3 dark = 2.0 * c / max(root - b, 1e-30);
    vec3 bright = (b + root) / (2.0 * a);
    return mix(bright, dark, lessThan(b, vec3(0.0)));
}

// The linear HDR colour that the tonemap pass, at `exposure`, shows as `display` (a tone-mapped
// colour in [0, 1]); black at exposure 0, which shows everything black.
vec3 hdr_from_display(vec3 display, float exposure) {
    return exposure > 0.0 ? tonemap_aces_inverse(display) / exposure : vec3(0.0);
}

vec3 linear_to_srgb(vec3 c) {
    vec3 lo = c * 12.92;
    vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(lo, hi, step(vec3(0.0031308), c));
}

#endif
