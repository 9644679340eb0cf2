#version 460
// Zeroes a pass's 64-byte counters before the pass accumulates into them.
layout(local_size_x = 16) in;
layout(set = 0, binding = 0) writeonly buffer Stats { uint words[16]; };
void main() { words[gl_LocalInvocationIndex] = 0u; }
