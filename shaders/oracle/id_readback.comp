#version 460
// Copies every sample of the (multisampled) id image into a buffer: (y * width + x) * samples + s.
layout(local_size_x = 8, local_size_y = 8) in;
#ifdef MULTISAMPLED
layout(set = 0, binding = 0) uniform usampler2DMS ids;
#define FETCH(p, s) texelFetch(ids, p, s)
#else
layout(set = 0, binding = 0) uniform usampler2D ids;
#define FETCH(p, s) texelFetch(ids, p, 0)
#endif
layout(set = 0, binding = 1) writeonly buffer Out { uint samples_out[]; };
layout(push_constant) uniform Push { uint width; uint height; uint samples; } pc;
void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.width || p.y >= pc.height) return;
    for (uint s = 0u; s < pc.samples; ++s) {
        samples_out[(p.y * pc.width + p.x) * pc.samples + s] = FETCH(ivec2(p), int(s)).r;
    }
}
