// A material's surface at a fragment of a geometry pass: its factors times its textures
// (base colour and alpha, metallic-roughness, normal map), and the alpha test of masked
// materials. Shared by every pass that draws the scene's geometry, so that they agree on
// which fragments exist (the oracle, the Hi-Z and the G-buffer see the same holes).
#ifndef CULLGRAPH_MATERIAL_SURFACE_GLSL
#define CULLGRAPH_MATERIAL_SURFACE_GLSL

#include "textures.glsl"

struct MaterialSurface {
    vec3 albedo;
    float alpha;
    float roughness;
    float metallic;
    vec3 normal;     // unit, facing the eye's side
};

// Base colour alpha at `uv` (with screen derivatives).
float material_alpha(GpuMaterial m, vec2 uv, vec2 dx, vec2 dy) {
    return m.alpha * sample_material(m.textures[TEX_BASE_COLOR], true, uv, dx, dy).a;
}

// Whether a fragment of `m` at `uv` is cut away: alpha below a masked material's cutoff.
bool material_cuts(GpuMaterial m, vec2 uv, vec2 dx, vec2 dy) {
    return m.alpha_mode == ALPHA_MASK && material_alpha(m, uv, dx, dy) < m.alpha_cutoff;
}

// The surface of `m` at `uv`. `geometric` is the interpolated normal already turned to the
// side the eye sees, `tangent` the interpolated tangent (w: bitangent sign), `front` whether
// the eye sees the front face (a back face flips the tangent frame with the normal).
MaterialSurface material_surface(GpuMaterial m, vec2 uv, vec2 dx, vec2 dy, vec3 geometric, vec4 tangent, bool front) {
    MaterialSurface s;
    vec4 base = sample_material(m.textures[TEX_BASE_COLOR], true, uv, dx, dy);
    s.albedo = m.albedo * base.rgb;
    s.alpha = m.alpha * base.a;
    vec4 mr = sample_material(m.textures[TEX_METALLIC_ROUGHNESS], false, uv, dx, dy);
    s.roughness = clamp(m.roughness * mr.g, 0.0, 1.0);
    s.metallic = clamp(m.metallic * mr.b, 0.0, 1.0);
    s.normal = geometric;
    if (m.textures[TEX_NORMAL].placement != NO_TEXTURE) {
        vec3 t = tangent.xyz - geometric * dot(geometric, tangent.xyz);
        if (dot(t, t) > 1e-12) {
            t = normalize(t);
            vec3 b = cross(geometric, t) * tangent.w * (front ? 1.0 : -1.0);
            vec3 tn = sample_material(m.textures[TEX_NORMAL], false, uv, dx, dy).xyz * 2.0 - 1.0;
            tn.xy *= m.normal_scale;
            vec3 n = t * tn.x + b * tn.y + geometric * tn.z;
            if (dot(n, n) > 1e-12) s.normal = normalize(n);
        }
    }
    return s;
}

#endif
