#version 460
// Multiplies each pixel of the frame by the tint its instance carries as user data (one word
// an instance: RGBA8, red in the low byte); the background keeps its colour.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D color;
layout(set = 0, binding = 1) uniform usampler2D object_id;
layout(set = 0, binding = 2, std430) readonly buffer UserData { uint user_data[]; };
layout(set = 0, binding = 3, rgba8) uniform writeonly image2D tinted;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(tinted)))) return;
    vec4 c = texelFetch(color, p, 0);
    // The instance's slot plus one; 0 for the background.
    uint id = texelFetch(object_id, p, 0).r;
    vec4 tint = id == 0u ? vec4(1.0) : unpackUnorm4x8(user_data[id - 1u]);
    imageStore(tinted, p, vec4(c.rgb * tint.rgb, c.a));
}
