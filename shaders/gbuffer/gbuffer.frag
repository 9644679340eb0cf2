#version 460
// G-buffer geometry pass, fragment stage: albedo + metallic, normal + roughness (its two formats:
// ../common/gbuffer_normal.glsl).
#include "../common/scene.glsl"
#include "../common/gbuffer_normal.glsl"

layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

layout(location = 0) in vec3 in_normal;
layout(location = 1) flat in uint in_material;
layout(location = 2) flat in uint in_mirrored;

layout(location = 0) out vec4 out_albedo_metallic;
layout(location = 1) out NORMAL_TEXEL out_normal_roughness;

void main() {
    GpuMaterial m = materials[in_material];
    vec3 n = normalize(in_normal);
    // Seen from behind (open meshes): light the side that faces the eye. A mirrored instance
    // flips the winding, so its outside shows as a back face.
    bool front = gl_FrontFacing != (in_mirrored != 0u);
    if (!front) n = -n;
    out_albedo_metallic = vec4(m.albedo, m.metallic);
    out_normal_roughness = encode_normal_roughness(n, m.roughness);
}
