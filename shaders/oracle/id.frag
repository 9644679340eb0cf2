#version 460
// Writes the instance id + 1 (0 stays "nothing") at every covered sample.
layout(location = 0) flat in uint in_instance;
layout(location = 0) out uint out_id;
void main() { out_id = in_instance + 1u; }
