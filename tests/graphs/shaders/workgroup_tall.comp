#version 460
// A workgroup of 1x1024 threads: within the thread count, taller than some devices allow.
layout(local_size_x = 1, local_size_y = 1024) in;
layout(set = 0, binding = 0, rgba8) uniform image2D img;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    imageStore(img, p, imageLoad(img, p) * 0.5);
}
