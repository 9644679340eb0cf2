#version 460
// c[i] = b[i] + 7
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) readonly buffer B { uint b[]; };
layout(set = 0, binding = 1) writeonly buffer C { uint c[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < c.length()) c[i] = b[i] + 7u;
}
