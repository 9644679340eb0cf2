#version 460
// b[i] = a[i] * a[i]
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) readonly buffer A { uint a[]; };
layout(set = 0, binding = 1) writeonly buffer B { uint b[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < b.length()) b[i] = a[i] * a[i];
}
