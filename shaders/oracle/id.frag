#version 460
// Writes the instance id + 1 (0 stays "nothing") at every covered sample, but where a masked
// material's alpha test cuts the fragment away (the same test as the geometry passes').
#include "../common/material_surface.glsl"

layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

layout(location = 0) flat in uint in_instance;
layout(location = 1) flat in uint in_material;
layout(location = 2) in vec2 in_uv;
layout(location = 0) out uint out_id;

void main() {
    uint coverage = material_coverage(materials[in_material], in_uv, dFdx(in_uv), dFdy(in_uv));
    APPLY_MATERIAL_COVERAGE(coverage);
    out_id = in_instance + 1u;
}
