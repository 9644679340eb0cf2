#version 460
// Includes a header that includes this shader again.
#include "include_pair.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba8) uniform image2D img;
void main() {}
