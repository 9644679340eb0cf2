#version 460
// Images that are not 2D with one layer, which graph images are.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler3D volume;
layout(set = 0, binding = 1) uniform samplerCube sky;
layout(set = 0, binding = 2) uniform usampler2DArray layers;
layout(set = 0, binding = 3, rgba8) uniform writeonly image2DArray slices;
layout(set = 0, binding = 4, rgba8) uniform writeonly image2D dst;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec4 c = texelFetch(volume, ivec3(p, 0), 0) + texture(sky, vec3(1.0, 0.0, 0.0))
        + vec4(texelFetch(layers, ivec3(p, 0), 0));
    imageStore(slices, ivec3(p, 0), c);
    imageStore(dst, p, c);
}
