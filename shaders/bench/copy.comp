#version 460
// Bandwidth reference: a plain compute copy, 16 bytes per thread per iteration, grid-stride.
// vkCmdCopyBuffer alone under-reports what compute kernels reach on some devices.
layout(local_size_x = 256) in;

layout(set = 0, binding = 0) readonly buffer Src { uvec4 src[]; };
layout(set = 0, binding = 1) writeonly buffer Dst { uvec4 dst[]; };

layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < pc.count; i += stride) dst[i] = src[i];
}
