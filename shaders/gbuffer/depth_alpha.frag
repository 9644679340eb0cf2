#version 460
// Depth-only geometry passes: no colour, only the alpha test of masked materials, so that depth
// (and the Hi-Z built from it) has the holes the shading passes see.
#include "../common/material_surface.glsl"

layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

layout(location = 1) flat in uint in_material;
layout(location = 5) in vec2 in_uv;

void main() {
    uint coverage = material_coverage(materials[in_material], in_uv, dFdx(in_uv), dFdy(in_uv));
    APPLY_MATERIAL_COVERAGE(coverage);
}
