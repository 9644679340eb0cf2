#version 460
// out[i] = c[i] * 2 + history[i] (history = last frame's out)
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) readonly buffer C { uint c[]; };
layout(set = 0, binding = 1) readonly buffer Prev { uint prev[]; };
layout(set = 0, binding = 2) writeonly buffer Out { uint outv[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < outv.length()) outv[i] = c[i] * 2u + prev[i];
}
