#version 460
// Writes the instance id + 1 (0 stays "nothing") and the triangle at every covered sample, but where a masked
// material's alpha test cuts the fragment away (the same test as the geometry passes').
#include "../common/material_surface.glsl"

layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

layout(location = 0) flat in uint in_instance;
layout(location = 1) flat in uint in_material;
layout(location = 2) in vec2 in_uv;
layout(location = 0) out uint out_id;
// The triangle within its instance's draw (the full mesh: its index in the mesh), from which the
// cluster check finds the cluster it belongs to.
layout(location = 1) out uint out_triangle;

void main() {
    uint coverage = material_coverage(materials[in_material], in_uv, dFdx(in_uv), dFdy(in_uv));
    APPLY_MATERIAL_COVERAGE(coverage);
    out_id = in_instance + 1u;
    out_triangle = uint(gl_PrimitiveID);
}
