#version 460
// Visibility-buffer geometry pass (seed 003): only the instance id and the triangle id (the
// primitive's index within its mesh) are stored; the shading pass rebuilds the rest. PACKED_IDS:
// one 32-bit word, the triangle in the low `triangle_bits` (src/passes/visibility_ids.rs).
// Masked materials' fragments below their alpha cutoff are discarded.
#include "../common/material_surface.glsl"

layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

layout(location = 1) flat in uint in_material;
layout(location = 4) flat in uint in_instance;
layout(location = 5) in vec2 in_uv;

#ifdef PACKED_IDS
layout(push_constant) uniform Push { uint triangle_bits; } pc;
layout(location = 0) out uint out_id;
#else
layout(location = 0) out uvec2 out_id;
#endif

void main() {
    uint coverage = material_coverage(materials[in_material], in_uv, dFdx(in_uv), dFdy(in_uv));
    APPLY_MATERIAL_COVERAGE(coverage);
#ifdef PACKED_IDS
    out_id = (in_instance << pc.triangle_bits) | uint(gl_PrimitiveID);
#else
    out_id = uvec2(in_instance, uint(gl_PrimitiveID));
#endif
}
