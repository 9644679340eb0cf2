#version 460
// Visibility-buffer geometry pass (seed 003): only the instance id and the triangle id (the
// primitive's index within its mesh) are stored; the shading pass rebuilds the rest.
layout(location = 4) flat in uint in_instance;
layout(location = 0) out uvec2 out_id;

void main() {
    out_id = uvec2(in_instance, uint(gl_PrimitiveID));
}
