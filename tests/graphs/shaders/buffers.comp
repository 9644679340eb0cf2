#version 460
// A readonly input buffer, a written output buffer and a uniform block.
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, std430) readonly buffer Input { uint values[]; } input_values;
layout(set = 0, binding = 1, std430) buffer Output { uint results[]; } output_values;
layout(set = 0, binding = 2) uniform Params { uint count; } params;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < params.count) output_values.results[i] = input_values.values[i] * 2u;
}
