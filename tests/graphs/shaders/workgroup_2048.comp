#version 460
// 32x32x2 = 2048 threads a workgroup, more than devices allow (1024 at most, often).
layout(local_size_x = 32, local_size_y = 32, local_size_z = 2) in;
layout(set = 0, binding = 0, rgba8) uniform image2D img;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    imageStore(img, p, imageLoad(img, p) * 0.5);
}
