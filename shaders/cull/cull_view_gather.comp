#version 460
// Views culled together (src/passes/instance_cull/views.rs): gathers what the test step reads
// of each view's frame constants (ViewCull) into the uniform buffer it reads them from, on the
// GPU, so that the recorded commands hold nothing of the cameras and a frame can be replayed.
// One dispatch for every view: copy regions would cost the copy engine about a microsecond
// each, three per view.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words { uint w[]; };

// The views' address tables (ViewBuffers, TABLE_WORDS addresses each): the first address is
// the view's FrameConstants.
layout(set = 0, binding = 0) readonly buffer Table { uint64_t table[]; };
layout(set = 0, binding = 1) writeonly buffer Culls { uint culls[]; };

layout(push_constant) uniform Push {
    uint views;
    uint table_words;   // addresses per view in the table
    uint view_words;    // words of one ViewCull
    uint runs;          // runs in `run` (at most 4)
    uvec4 run[4];       // x: first word in FrameConstants, y: first word in ViewCull, z: words
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint v = i / pc.view_words;
    uint w = i % pc.view_words;
    if (v >= pc.views) return;
    for (uint r = 0u; r < pc.runs; ++r) {
        uvec4 run = pc.run[r];
        if (w >= run.y && w < run.y + run.z) {
            Words constants = Words(table[v * pc.table_words]);
            culls[v * pc.view_words + w] = constants.w[run.x + w - run.y];
        }
    }
}
