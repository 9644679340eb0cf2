// A material's surface at a fragment of a geometry pass: its factors times its five textures
// (base colour and alpha, metallic-roughness, normal map, occlusion, emissive), and the alpha test of masked
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
    float occlusion; // ambient occlusion, 1 = none
    vec3 emissive;   // linear
};

// Base colour alpha at `uv` (with screen derivatives).
float material_alpha(GpuMaterial m, vec2 uv, vec2 dx, vec2 dy) {
    return m.alpha * sample_material(m.textures[TEX_BASE_COLOR], true, uv, dx, dy).a;
}

#ifndef MSAA_SAMPLES
#define MSAA_SAMPLES 1
#endif

// The samples of a fragment of `m` at `uv` that its alpha keeps (bit s: sample s), at
// MSAA_SAMPLES samples per pixel. Opaque and blended materials keep every sample. A masked
// material's alpha is sharpened around its cutoff over the pixel's change in alpha and turned
// into a share of the samples (alpha-to-coverage), rotated by the pixel's position so that
// layers of foliage do not all keep the same samples. The choice depends only on the fragment,
// so every pass that draws the geometry (depth, G-buffer, ids, the visibility oracle) keeps the
// same samples. With one sample, or with ALPHA_TEST_ONLY (the bench's `--alpha-test`, which
// measures what alpha-to-coverage costs), it is the alpha test. Call it where every invocation
// of the quad runs (it takes a screen derivative).
uint material_coverage(GpuMaterial m, vec2 uv, vec2 dx, vec2 dy) {
#ifdef NO_ALPHA_MASK
    return 0xFFFFFFFFu;
#endif
    if (m.alpha_mode != ALPHA_MASK) return 0xFFFFFFFFu;
    float a = material_alpha(m, uv, dx, dy);
#if MSAA_SAMPLES > 1 && !defined(ALPHA_TEST_ONLY)
    float width = max(fwidth(a), 1.0 / 256.0);
    float share = clamp((a - m.alpha_cutoff) / width + 0.5, 0.0, 1.0);
    uint n = uint(share * float(MSAA_SAMPLES) + 0.5);
    uint all_samples = (1u << MSAA_SAMPLES) - 1u;
    uint mask = (1u << n) - 1u;
    uint turn = (uint(gl_FragCoord.x) + 2u * uint(gl_FragCoord.y)) % uint(MSAA_SAMPLES);
    return ((mask << turn) | (mask >> (uint(MSAA_SAMPLES) - turn))) & all_samples;
#else
    return a < m.alpha_cutoff ? 0u : 0xFFFFFFFFu;
#endif
}

// Applies `material_coverage`: discards a fragment that keeps no sample, and limits the others
// to the samples they keep. With NO_ALPHA_MASK (a scene without masked materials) it does
// nothing, so the shader has no `discard` and the depth test runs before it.
#ifdef NO_ALPHA_MASK
#define APPLY_MATERIAL_COVERAGE(coverage)
#else
#define APPLY_MATERIAL_COVERAGE(coverage) \
    if ((coverage) == 0u) discard; \
    if (MSAA_SAMPLES > 1) gl_SampleMask[0] = int(coverage)
#endif

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
#ifdef NO_EMISSION_OCCLUSION
    // For scenes where no material has them (GpuScene::emission_or_occlusion).
    s.occlusion = 1.0;
    s.emissive = vec3(0.0);
#else
    float ao = sample_material(m.textures[TEX_OCCLUSION], false, uv, dx, dy).r;
    s.occlusion = clamp(1.0 + m.occlusion_strength * (ao - 1.0), 0.0, 1.0);
    s.emissive = m.emissive * sample_material(m.textures[TEX_EMISSIVE], true, uv, dx, dy).rgb;
#endif
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
