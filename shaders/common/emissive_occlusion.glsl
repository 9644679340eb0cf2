// How the geometry passes store a surface's emissive colour and ambient occlusion for the
// lighting passes (../common/material_surface.glsl computes them):
// - G-buffer images: an R8G8B8A8_SRGB texel, emissive rgb (sRGB-encoded by the format, so dark
//   emissive keeps its steps), occlusion a;
// - compressed G-buffer: one word per block with roughness and occlusion in a byte each and
//   emissive as sRGB-encoded 5:6:5, the block's own word so that no two fragments share it.
// The visibility buffer, which shades the material directly, rounds them like the G-buffer
// images so that both methods light the same inputs.
#ifndef CULLGRAPH_EMISSIVE_OCCLUSION_GLSL
#define CULLGRAPH_EMISSIVE_OCCLUSION_GLSL

vec3 encode_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

vec3 decode_srgb(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}

// `emissive` and `occlusion` as an R8G8B8A8_SRGB texel stores them.
void round_like_gbuffer(inout vec3 emissive, inout float occlusion) {
    emissive = decode_srgb(round(encode_srgb(emissive) * 255.0) / 255.0);
    occlusion = round(clamp(occlusion, 0.0, 1.0) * 255.0) / 255.0;
}

// Roughness (bits 0-7), occlusion (8-15) and emissive (16-31: sRGB 5:6:5) in one word.
uint pack_surface_word(float roughness, float occlusion, vec3 emissive) {
    vec3 e = round(encode_srgb(emissive) * vec3(31.0, 63.0, 31.0));
    uint r = uint(round(clamp(roughness, 0.0, 1.0) * 255.0));
    uint o = uint(round(clamp(occlusion, 0.0, 1.0) * 255.0));
    return r | (o << 8) | (uint(e.r) << 16) | (uint(e.g) << 21) | (uint(e.b) << 27);
}

float surface_word_roughness(uint w) { return float(w & 0xFFu) / 255.0; }
float surface_word_occlusion(uint w) { return float((w >> 8) & 0xFFu) / 255.0; }
vec3 surface_word_emissive(uint w) {
    vec3 e = vec3(float((w >> 16) & 31u), float((w >> 21) & 63u), float(w >> 27)) / vec3(31.0, 63.0, 31.0);
    return decode_srgb(e);
}

#endif
