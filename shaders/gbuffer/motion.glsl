// Per-pixel motion vectors of the geometry passes (MOTION): gbuffer.vert's unjittered clip
// positions of this frame and the last, projected per pixel. The vector is in pixels, from this
// frame's position to last frame's (FSR's convention: previous = current + motion), x right,
// y down; the projection's y already points down the framebuffer.
#ifndef CULLGRAPH_MOTION_GLSL
#define CULLGRAPH_MOTION_GLSL

#include "../common/scene.glsl"

layout(set = 0, binding = 2, scalar) uniform MotionFrame { FrameConstants motion_frame; };
layout(location = 7) in vec4 in_clip;
layout(location = 8) in vec4 in_prev_clip;
layout(location = MOTION_LOCATION) out vec2 out_motion;   // R16G16_SFLOAT

void write_motion() {
    // A point that was behind last frame's eye has no position on last frame's screen: it is
    // kept just in front of the eye plane, which gives a long vector pointing off screen.
    const float min_w = 1.0e-6;
    vec2 now = in_clip.xy / max(in_clip.w, min_w);
    vec2 before = in_prev_clip.xy / max(in_prev_clip.w, min_w);
    vec2 size = vec2(motion_frame.size_lights.xy);
    // Halves hold up to 65504: beyond, a vector would read as infinite.
    out_motion = clamp((before - now) * 0.5 * size, vec2(-65504.0), vec2(65504.0));
}

#endif
