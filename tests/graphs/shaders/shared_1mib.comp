#version 460
// 1 MiB of shared memory (devices give 16 KiB to 64 KiB).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) uniform image2D img;
shared vec4 staging[65536];
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    staging[gl_LocalInvocationIndex * 1024u] = imageLoad(img, p);
    barrier();
    imageStore(img, p, staging[(gl_LocalInvocationIndex * 1024u + 1024u) % 65536u]);
}
