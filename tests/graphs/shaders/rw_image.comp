#version 460
// Brightens an image in place (read and written through one storage image binding).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) uniform image2D img;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    imageStore(img, p, imageLoad(img, p) * 1.1);
}
