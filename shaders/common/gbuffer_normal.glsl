// The G-buffer's normal/roughness texel in its two formats (`NORMAL_PACKED` picks one):
// - R32_UINT (packed, the built-in graphs' default): octahedral normal in 12 + 12 bits, roughness
//   in 8 bits (the compressed G-buffer's block keeps roughness in 8 bits too). Half the bytes of
//   the float format, and on GPUs whose few graphics units export pixels slowly (the H100), the
//   cheaper export is most of the G-buffer pass's time.
// - R16G16B16A16_SFLOAT: normal xyz, roughness a (the thesis's per-sample MSAA baseline layout).
#ifndef CULLGRAPH_GBUFFER_NORMAL_GLSL
#define CULLGRAPH_GBUFFER_NORMAL_GLSL

#include "octahedral.glsl"

#ifdef NORMAL_PACKED
#define NORMAL_TEXEL uint
#define NORMAL_TEXEL4 uvec4
#define NORMAL_SAMPLER_2D usampler2D
#define NORMAL_SAMPLER_2DMS usampler2DMS
#else
#define NORMAL_TEXEL vec4
#define NORMAL_TEXEL4 vec4
#define NORMAL_SAMPLER_2D sampler2D
#define NORMAL_SAMPLER_2DMS sampler2DMS
#endif

// Octahedral coordinates in [-1, 1] are stored as 2047 +- 2047, so 0 (an axis-aligned normal)
// is exact.
const float NORMAL_OCT_SCALE = 2047.0;

NORMAL_TEXEL encode_normal_roughness(vec3 n, float roughness) {
#ifdef NORMAL_PACKED
    uvec2 q = uvec2(round(clamp(oct_encode(n), -1.0, 1.0) * NORMAL_OCT_SCALE) + NORMAL_OCT_SCALE);
    uint r = uint(round(clamp(roughness, 0.0, 1.0) * 255.0));
    return q.x | (q.y << 12) | (r << 24);
#else
    return vec4(n, roughness);
#endif
}

// The texel as fetched (a sampler's vec4, or a usampler's uvec4 whose x holds the word), back
// to normal xyz and roughness w.
vec4 decode_normal_roughness(NORMAL_TEXEL4 texel) {
#ifdef NORMAL_PACKED
    uint p = texel.x;
    vec2 oct = (vec2(p & 0xfffu, (p >> 12) & 0xfffu) - NORMAL_OCT_SCALE) / NORMAL_OCT_SCALE;
    return vec4(oct_decode(oct), float(p >> 24) / 255.0);
#else
    return vec4(normalize(texel.xyz), texel.w);
#endif
}

#endif
