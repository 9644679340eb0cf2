#version 460
// G-buffer geometry pass, fragment stage: albedo + metallic, normal + roughness (its two formats:
// ../common/gbuffer_normal.glsl) and, with EMISSIVE_OCCLUSION, emissive + occlusion, from the
// material's factors and textures. Masked materials' fragments below their alpha cutoff are
// discarded. With MOTION, the motion vector at MOTION_LOCATION (src/passes/gbuffer.rs): in
// pixels, from this frame's position to last frame's, x right, y down. With OBJECT_ID, the
// instance id plus one at OBJECT_ID_LOCATION.
#include "../common/material_surface.glsl"
#include "../common/gbuffer_normal.glsl"

layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

layout(location = 0) in vec3 in_normal;
layout(location = 1) flat in uint in_material;
layout(location = 2) flat in uint in_mirrored;
layout(location = 5) in vec2 in_uv;
layout(location = 6) in vec4 in_tangent;

layout(location = 0) out vec4 out_albedo_metallic;
layout(location = 1) out NORMAL_TEXEL out_normal_roughness;
#ifdef EMISSIVE_OCCLUSION
layout(location = 2) out vec4 out_emissive_occlusion;   // R8G8B8A8_SRGB
#endif
#ifdef MOTION
#include "motion.glsl"
#endif
#ifdef OBJECT_ID
// The drawn instance's id plus one (0: the background), for picking.
layout(location = 4) flat in uint in_instance;
layout(location = OBJECT_ID_LOCATION) out uint out_object_id;
#endif

void main() {
    GpuMaterial m = materials[in_material];
    vec2 dx = dFdx(in_uv), dy = dFdy(in_uv);
    uint coverage = material_coverage(m, in_uv, dx, dy);
    APPLY_MATERIAL_COVERAGE(coverage);
    vec3 n = normalize(in_normal);
    // Seen from behind (open meshes, double-sided materials): light the side that faces the
    // eye. A mirrored instance flips the winding, so its outside shows as a back face.
    bool front = gl_FrontFacing != (in_mirrored != 0u);
    if (!front) n = -n;
    MaterialSurface s = material_surface(m, in_uv, dx, dy, n, in_tangent, front);
    out_albedo_metallic = vec4(s.albedo, s.metallic);
    out_normal_roughness = encode_normal_roughness(s.normal, s.roughness);
#ifdef EMISSIVE_OCCLUSION
    out_emissive_occlusion = vec4(s.emissive, s.occlusion);
#endif
#ifdef MOTION
    write_motion();
#endif
#ifdef OBJECT_ID
    out_object_id = in_instance + 1u;
#endif
}
