#version 460
// Overlay, step 2: one thread per pixel of the region it covers. View variants:
//   (none)      the panel only; dispatched over the panel's largest possible extent, and pixels
//               outside this frame's panel are not touched;
//   VIEW_HIZ    every pixel shows one mip of the Hi-Z pyramid in grey (nearest: the texel that
//               covers the pixel in the occlusion test), then the panel;
//   VIEW_CULLED every pixel inside the screen rectangle of an occlusion-culled instance is tinted
//               red (deeper where rectangles overlap) with a bright red edge, then the panel.
// The panel: a translucent dark box at the top left, glyphs of font8x8 (labels light grey, numbers
// yellow), time bars green.
#extension GL_GOOGLE_include_directive : require
#include "overlay_common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, rgba8) uniform image2D image;
layout(set = 0, binding = 1, scalar) readonly buffer Text { OverlayText text; };
// font8x8's BASIC_LEGACY: glyph c is words 2c (rows 0-3) and 2c + 1 (rows 4-7), a byte per row,
// bit x of a byte is column x.
layout(set = 0, binding = 2) readonly buffer Font { uint glyphs[256]; };
#ifdef VIEW_HIZ
layout(set = 0, binding = 3) uniform sampler2D hiz_tex;
#endif
#ifdef VIEW_CULLED
// Header of 4 words, then per row (width + 1) counts: the number of marked rectangles covering
// each pixel (after overlay_scan.comp).
layout(set = 0, binding = 4) readonly buffer Coverage { uint header[4]; int coverage[]; };
#endif

layout(push_constant) uniform Push {
    uvec2 size;        // image size
    uint scale;        // screen pixels per font pixel
    uint hiz_mip;      // VIEW_HIZ: mip of the pyramid image shown (already clamped)
    uint hiz_shift;    // its texel of pixel p is p >> hiz_shift (the occlusion test's rule, with
                       // the image as level 0); 0xFFFFFFFF: sizes unrelated, scale proportionally
} pc;

const vec3 PANEL = vec3(16.0, 18.0, 24.0) / 255.0;
const float PANEL_ALPHA = 0.72;
const vec3 LABEL = vec3(215.0, 215.0, 215.0) / 255.0;
const vec3 NUMBER = vec3(255.0, 224.0, 112.0) / 255.0;
const vec3 BAR = vec3(96.0, 200.0, 120.0) / 255.0;

#ifdef VIEW_CULLED
int coverage_at(ivec2 p) {
    if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(uvec2(p), pc.size))) return 0;
    return coverage[uint(p.y) * (pc.size.x + 1u) + uint(p.x)];
}
#endif

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, pc.size))) return;
    ivec2 p = ivec2(pixel);

    uint s = max(pc.scale, 1u);
    uvec2 origin = uvec2(OVERLAY_MARGIN);
    uvec2 panel = uvec2(text.cols * OVERLAY_GLYPH, text.rows * OVERLAY_LINE) * s + 2u * OVERLAY_PADDING * s;
    bool in_panel = text.rows > 0u && all(greaterThanEqual(pixel, origin)) && all(lessThan(pixel, origin + panel));

#if !defined(VIEW_HIZ) && !defined(VIEW_CULLED)
    if (!in_panel) return;
#endif
    vec4 color = imageLoad(image, p);

#ifdef VIEW_HIZ
    {
        int mip = int(pc.hiz_mip);
        uvec2 mip_size = uvec2(textureSize(hiz_tex, mip));
        uvec2 texel = pc.hiz_shift != 0xFFFFFFFFu ? pixel >> uvec2(pc.hiz_shift) : pixel * mip_size / pc.size;
        float depth = texelFetch(hiz_tex, ivec2(min(texel, mip_size - 1u)), mip).r;
        // Reversed-Z: 1 at the near plane, near / distance beyond. Grey linear in log distance,
        // from 1.0 at the near plane down to 0.15 at 1024 times its distance and beyond; black
        // where nothing was drawn (sky, depth 0).
        float grey = depth > 0.0 ? 0.15 + 0.85 * clamp(1.0 + log2(depth) / 10.0, 0.0, 1.0) : 0.0;
        color = vec4(vec3(grey), 1.0);
    }
#endif
#ifdef VIEW_CULLED
    {
        int here = coverage_at(p);
        if (here > 0) {
            int lowest = min(min(coverage_at(p + ivec2(1, 0)), coverage_at(p - ivec2(1, 0))),
                             min(coverage_at(p + ivec2(0, 1)), coverage_at(p - ivec2(0, 1))));
            bool edge = lowest < here;
            vec3 red = vec3(1.0, 0.16, 0.16);
            color.rgb = edge ? red : mix(color.rgb, red, min(0.2 + 0.1 * float(here), 0.6));
        }
    }
#endif

    if (in_panel) {
        color.rgb = mix(color.rgb, PANEL, PANEL_ALPHA);
        uvec2 local = (pixel - origin - uvec2(OVERLAY_PADDING * s)) / s;
        bool inside = all(greaterThanEqual(pixel, origin + uvec2(OVERLAY_PADDING * s)));
        uint row = local.y / OVERLAY_LINE;
        uint y = local.y % OVERLAY_LINE;
        uint col = local.x / OVERLAY_GLYPH;
        uint x = local.x % OVERLAY_GLYPH;
        if (inside && row < text.rows && col < OVERLAY_MAX_COLS) {
            uint cell = text.cells[row * OVERLAY_MAX_COLS + col];
            uint code = cell & 0x7Fu;
            if (cell != 0u && y < 8u) {
                uint bits = (glyphs[code * 2u + y / 4u] >> ((y % 4u) * 8u)) & 0xFFu;
                if (((bits >> x) & 1u) != 0u) color.rgb = (cell & CELL_NUMBER) != 0u ? NUMBER : LABEL;
            }
            float bar = text.bar[row];
            if (bar >= 0.0 && text.bar_chars > 0u) {
                // Bars start at the template's bar column; a font pixel of margin above and below.
                uint start = text.bar_col * OVERLAY_GLYPH;
                float length = max(bar * float(text.bar_chars * OVERLAY_GLYPH), 1.0);
                if (local.x >= start && float(local.x - start) < length && y >= 1u && y < 7u) color.rgb = BAR;
            }
        }
    }
    imageStore(image, p, color);
}
