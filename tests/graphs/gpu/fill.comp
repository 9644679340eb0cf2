#version 460
// a[i] = i + 1
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) writeonly buffer A { uint a[]; };
layout(push_constant) uniform Frame { uint width; uint height; uint frame; uint pad; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < a.length()) a[i] = i + 1u;
}
