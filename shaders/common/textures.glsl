// A scene's textures as src/passes/shared/textures.rs lays them out: one sampler2DArray per
// size class (16 to 2048 texels square), each bound twice, through an sRGB view and a linear
// one, from binding TEXTURE_BINDING on (16 bindings). A class is chosen by a switch over
// constant indices, not by indexing an array of samplers: lavapipe cannot index sampled-image
// arrays dynamically, and NVIDIA takes the same path, so both give the same image.
//
// Wrap modes are applied here (the sampler repeats); sampling takes explicit derivatives of the
// coordinates before wrapping, so that mip selection does not jump at the wrap.
#ifndef CULLGRAPH_TEXTURES_GLSL
#define CULLGRAPH_TEXTURES_GLSL

#include "scene.glsl"

#define TEXTURE_BINDING 16

layout(set = 0, binding = TEXTURE_BINDING + 0) uniform sampler2DArray tex_srgb_0;
layout(set = 0, binding = TEXTURE_BINDING + 1) uniform sampler2DArray tex_linear_0;
layout(set = 0, binding = TEXTURE_BINDING + 2) uniform sampler2DArray tex_srgb_1;
layout(set = 0, binding = TEXTURE_BINDING + 3) uniform sampler2DArray tex_linear_1;
layout(set = 0, binding = TEXTURE_BINDING + 4) uniform sampler2DArray tex_srgb_2;
layout(set = 0, binding = TEXTURE_BINDING + 5) uniform sampler2DArray tex_linear_2;
layout(set = 0, binding = TEXTURE_BINDING + 6) uniform sampler2DArray tex_srgb_3;
layout(set = 0, binding = TEXTURE_BINDING + 7) uniform sampler2DArray tex_linear_3;
layout(set = 0, binding = TEXTURE_BINDING + 8) uniform sampler2DArray tex_srgb_4;
layout(set = 0, binding = TEXTURE_BINDING + 9) uniform sampler2DArray tex_linear_4;
layout(set = 0, binding = TEXTURE_BINDING + 10) uniform sampler2DArray tex_srgb_5;
layout(set = 0, binding = TEXTURE_BINDING + 11) uniform sampler2DArray tex_linear_5;
layout(set = 0, binding = TEXTURE_BINDING + 12) uniform sampler2DArray tex_srgb_6;
layout(set = 0, binding = TEXTURE_BINDING + 13) uniform sampler2DArray tex_linear_6;
layout(set = 0, binding = TEXTURE_BINDING + 14) uniform sampler2DArray tex_srgb_7;
layout(set = 0, binding = TEXTURE_BINDING + 15) uniform sampler2DArray tex_linear_7;

vec4 sample_class(uint cls, bool srgb, vec3 uvl, vec2 dx, vec2 dy) {
    if (srgb) {
        switch (cls) {
        case 0u: return textureGrad(tex_srgb_0, uvl, dx, dy);
        case 1u: return textureGrad(tex_srgb_1, uvl, dx, dy);
        case 2u: return textureGrad(tex_srgb_2, uvl, dx, dy);
        case 3u: return textureGrad(tex_srgb_3, uvl, dx, dy);
        case 4u: return textureGrad(tex_srgb_4, uvl, dx, dy);
        case 5u: return textureGrad(tex_srgb_5, uvl, dx, dy);
        case 6u: return textureGrad(tex_srgb_6, uvl, dx, dy);
        case 7u: return textureGrad(tex_srgb_7, uvl, dx, dy);
        }
    } else {
        switch (cls) {
        case 0u: return textureGrad(tex_linear_0, uvl, dx, dy);
        case 1u: return textureGrad(tex_linear_1, uvl, dx, dy);
        case 2u: return textureGrad(tex_linear_2, uvl, dx, dy);
        case 3u: return textureGrad(tex_linear_3, uvl, dx, dy);
        case 4u: return textureGrad(tex_linear_4, uvl, dx, dy);
        case 5u: return textureGrad(tex_linear_5, uvl, dx, dy);
        case 6u: return textureGrad(tex_linear_6, uvl, dx, dy);
        case 7u: return textureGrad(tex_linear_7, uvl, dx, dy);
        }
    }
    return vec4(1.0);
}

vec4 sample_class_lod(uint cls, bool srgb, vec3 uvl, float lod) {
    if (srgb) {
        switch (cls) {
        case 0u: return textureLod(tex_srgb_0, uvl, lod);
        case 1u: return textureLod(tex_srgb_1, uvl, lod);
        case 2u: return textureLod(tex_srgb_2, uvl, lod);
        case 3u: return textureLod(tex_srgb_3, uvl, lod);
        case 4u: return textureLod(tex_srgb_4, uvl, lod);
        case 5u: return textureLod(tex_srgb_5, uvl, lod);
        case 6u: return textureLod(tex_srgb_6, uvl, lod);
        case 7u: return textureLod(tex_srgb_7, uvl, lod);
        }
    } else {
        switch (cls) {
        case 0u: return textureLod(tex_linear_0, uvl, lod);
        case 1u: return textureLod(tex_linear_1, uvl, lod);
        case 2u: return textureLod(tex_linear_2, uvl, lod);
        case 3u: return textureLod(tex_linear_3, uvl, lod);
        case 4u: return textureLod(tex_linear_4, uvl, lod);
        case 5u: return textureLod(tex_linear_5, uvl, lod);
        case 6u: return textureLod(tex_linear_6, uvl, lod);
        case 7u: return textureLod(tex_linear_7, uvl, lod);
        }
    }
    return vec4(1.0);
}

// Wrap of one coordinate: 0 repeat (left to the sampler), 1 mirrored repeat, 2 clamp to edge.
float wrap_coord(float x, uint mode, float size) {
    if (mode == 1u) {
        float m = mod(x, 2.0);
        return m > 1.0 ? 2.0 - m : m;
    }
    if (mode == 2u) return clamp(x, 0.5 / size, 1.0 - 0.5 / size);
    return x;
}

// Texture `t` of a material at texture coordinates `uv` with screen derivatives `duv_dx`,
// `duv_dy`; white where the material has no such texture.
vec4 sample_material(MaterialTexture t, bool srgb, vec2 uv, vec2 duv_dx, vec2 duv_dy) {
#ifdef NO_TEXTURES
    // No material of the scene has a texture (GpuScene::textured): none of this is compiled.
    return vec4(1.0);
#endif
    if (t.placement == NO_TEXTURE) return vec4(1.0);
    mat2 linear = mat2(t.row0.x, t.row1.x, t.row0.y, t.row1.y);
    vec2 st = linear * uv + vec2(t.row0.z, t.row1.z);
    vec2 dx = linear * duv_dx;
    vec2 dy = linear * duv_dy;
    uint cls = t.placement >> 16;
    float layer = float(t.placement & 0xFFFFu);
    float size = float(16u << cls);
    st = vec2(wrap_coord(st.x, t.sampling & 3u, size), wrap_coord(st.y, (t.sampling >> 2) & 3u, size));
    float footprint = max(length(dx), length(dy)) * size;
    bool magnified = footprint <= 1.0;
    bool nearest = magnified ? (t.sampling & 16u) != 0u : (t.sampling & 32u) != 0u;
    if (nearest) {
        // The texel under the coordinate, at the nearest mip.
        float lod = max(round(log2(max(footprint, 1e-8))), 0.0);
        float level_size = max(size / exp2(lod), 1.0);
        st = (floor(st * level_size) + 0.5) / level_size;
        return sample_class_lod(cls, srgb, vec3(st, layer), lod);
    }
    return sample_class(cls, srgb, vec3(st, layer), dx, dy);
}

#endif
