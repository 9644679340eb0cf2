// Scene data shared by every pass. Layouts mirror src/passes/shared/gpu_types.rs (scalar block layout).
#ifndef CULLGRAPH_SCENE_GLSL
#define CULLGRAPH_SCENE_GLSL

#extension GL_EXT_scalar_block_layout : require

// One instance, 64 bytes. The translation is split into hi + lo floats so that
// (hi - eye_hi) + (lo - eye_lo) keeps full precision 10^7 units from the origin.
struct GpuInstance {
    vec4 row0;            // xyz: first row of the 3x3 linear part, w: translation.x hi
    vec4 row1;            // xyz: second row, w: translation.y hi
    vec4 row2;            // xyz: third row, w: translation.z hi
    vec3 translation_lo;  // translation - hi
    uint material_flags;  // material index (low 24 bits) | flags << 24
};

// A vertex's texture coordinates and tangent in the pool's surface stream
// (src/passes/shared/vertex_streams.rs SurfaceVertex), for passes that read the pool as buffers
// rather than through vertex input; its position and octahedral normal (two snorm16) are in
// streams of their own.
struct SurfaceVertex {
    vec2 uv;
    uint tangent_xy;   // snorm16 x, y
    uint tangent_zw;   // snorm16 z, handedness sign
};

// One texture of a material (src/passes/shared/gpu_types.rs GpuMaterialTexture).
struct MaterialTexture {
    vec4 row0;        // u' = dot(row0.xy, uv) + row0.z
    vec4 row1;        // v' = dot(row1.xy, uv) + row1.z
    uint placement;   // class << 16 | layer, NO_TEXTURE for none
    uint sampling;    // wrap u (bits 0-1), wrap v (2-3), nearest mag (4), nearest min (5)
    uint pad0;
    uint pad1;
};

#define NO_TEXTURE 0xFFFFFFFFu
#define ALPHA_OPAQUE 0u
#define ALPHA_MASK 1u
#define ALPHA_BLEND 2u
// GpuMaterial flags (src/passes/shared/gpu_types.rs).
#define MATERIAL_DOUBLE_SIDED 1u

// Texture slots, in the order of GpuMaterial::textures (src/scene/texture.rs TextureSlot).
#define TEX_BASE_COLOR 0
#define TEX_METALLIC_ROUGHNESS 1
#define TEX_NORMAL 2
#define TEX_OCCLUSION 3
#define TEX_EMISSIVE 4

struct GpuMaterial {
    vec3 albedo;
    float roughness;
    float metallic;
    float alpha;
    float alpha_cutoff;
    uint alpha_mode;
    vec3 emissive;
    float normal_scale;
    float occlusion_strength;
    uint flags;           // MATERIAL_* bits
    float pad1;
    float pad2;
    MaterialTexture textures[5];
};

#include "cull_math.glsl"

// The sun's shadow cascades of a view (shadows.glsl samples them).
struct SunShadows {
    mat4 cascades[4];   // eye-relative world -> the cascade's clip space (orthographic)
    vec4 texel;         // world size of a texel of each cascade's map
    uvec4 info;         // x: cascades (0: no shadows), y: map size in texels
};

// The shadow maps of a view's spot and point lights (shadows.glsl samples them): face k is
// layer k of the local shadow-map array.
#define MAX_LOCAL_FACES 24
struct LocalShadows {
    mat4 faces[MAX_LOCAL_FACES];   // eye-relative world -> the face's clip space (perspective)
};

// Per-frame constants, relative to the eye. Every shader binds them as a uniform buffer: every
// invocation reads the same values, which implementations then serve from their constant
// caches instead of loading them into each invocation's registers (in the culling tests and the
// lighting, whose registers bound how many workgroups run at once, that is measurably faster).
struct FrameConstants {
    mat4 view_proj;        // eye-relative world -> clip (rotation and projection only)
    mat4 inv_view_proj;    // clip -> eye-relative world
    vec4 eye_hi;           // xyz
    vec4 eye_lo;           // xyz
    vec4 sun_direction;    // xyz: direction light travels
    vec4 sun_color;        // rgb: radiance
    uvec4 size_lights;     // x: width, y: height, z: point light count, w: unused
    vec4 ambient;          // rgb: sky ambient, a: unused
    CullView cull_view;    // this frame's culling view
    CullView prev_cull_view; // last frame's (tests against last frame's Hi-Z)
    vec4 prev_eye_hi;      // last frame's eye, xyz
    vec4 prev_eye_lo;
    mat4 view_proj_unjittered;      // view_proj without the sub-pixel jitter (for motion vectors)
    mat4 prev_view_proj_unjittered; // last frame's, relative to last frame's eye
    vec4 jitter;                    // xy: this frame's jitter, zw: last frame's, in NDC units
    SunShadows sun_shadows;
    LocalShadows local_shadows;
    // The view whose pixels levels of detail are chosen for (a shadow view: its camera view's;
    // any other: `cull_view`), and this view's eye less that view's eye (xyz), which turns
    // positions relative to this eye into positions relative to that one.
    CullView lod_view;
    vec4 lod_eye_offset;
};

// What the lighting pass shows (its `debug_view` setting).
#define DEBUG_VIEW_NONE 0u
#define DEBUG_VIEW_NORMALS 1u
#define DEBUG_VIEW_ALBEDO 2u
#define DEBUG_VIEW_DEPTH 3u
#define DEBUG_VIEW_SAMPLES 4u   // distinct surfaces (or shaded samples) per pixel, as a heatmap
#define DEBUG_VIEW_CASCADES 5u  // the lit image tinted by the shadow cascade that shades each pixel

// Point light relative to the eye: xyz position, w range; rgb color.
struct GpuPointLight {
    vec4 position_range;
    vec4 color;   // rgb: color, w: spot angle scale 1 / (cos inner - cos outer)
    vec4 spot;    // xyz: spot direction (travel), w: cos outer angle (< -1: a point light)
    uvec4 shadow; // x: first shadow face (NO_SHADOW: none), y: faces (1 or 6), z: texel size at 1 unit (float bits)
};
#define NO_SHADOW 0xFFFFFFFFu

// A split world position (hi + lo) relative to the split eye. The hi parts are whole numbers
// (split_hi_lo in src/passes/shared/gpu_types.rs), so their difference is exact, and `precise` keeps
// the compiler from regrouping the sum: the same relative position at any whole offset.
vec3 rel_eye(vec3 hi, vec3 lo, vec3 eye_hi, vec3 eye_lo) {
    precise vec3 t = (hi - eye_hi) + (lo - eye_lo);
    return t;
}

// Eye-relative position of a local-space point. Subtracting the eye before adding the
// local offset keeps the big numbers out of the sum.
vec3 instance_rel_eye(GpuInstance inst, vec3 local, vec3 eye_hi, vec3 eye_lo) {
    vec3 t = rel_eye(vec3(inst.row0.w, inst.row1.w, inst.row2.w), inst.translation_lo, eye_hi, eye_lo);
    mat3 m = transpose(mat3(inst.row0.xyz, inst.row1.xyz, inst.row2.xyz));
    return m * local + t;
}

// Normal transform: the cofactor matrix (det * inverse-transpose) times the sign of the
// determinant, so mirrored instances keep outward normals without a division.
vec3 instance_normal(GpuInstance inst, vec3 n) {
    vec3 r0 = inst.row0.xyz, r1 = inst.row1.xyz, r2 = inst.row2.xyz;
    mat3 m = transpose(mat3(r0, r1, r2));
    mat3 cof = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    float det = dot(m[0], cross(m[1], m[2]));
    return cof * n * (det < 0.0 ? -1.0 : 1.0);
}

bool instance_is_mirrored(GpuInstance inst) {
    return dot(inst.row0.xyz, cross(inst.row1.xyz, inst.row2.xyz)) < 0.0;
}

uint instance_material(GpuInstance inst) { return inst.material_flags & 0xFFFFFFu; }
uint instance_flags(GpuInstance inst) { return inst.material_flags >> 24; }

// Instance flag: selective AA keeps this instance at one sample (src/scene/mod.rs FLAG_NO_AA).
#define FLAG_NO_AA 2u

#endif
