#version 460
// Visibility-buffer geometry pass (seed 003): only the instance id and the triangle id (the
// primitive's index within its mesh) are stored; the shading pass rebuilds the rest. PACKED_IDS:
// one 32-bit word, the triangle in the low `triangle_bits` (src/passes/visibility_ids.rs).
layout(location = 4) flat in uint in_instance;
#ifdef PACKED_IDS
layout(push_constant) uniform Push { uint triangle_bits; } pc;
layout(location = 0) out uint out_id;

void main() {
    out_id = (in_instance << pc.triangle_bits) | uint(gl_PrimitiveID);
}
#else
layout(location = 0) out uvec2 out_id;

void main() {
    out_id = uvec2(in_instance, uint(gl_PrimitiveID));
}
#endif
