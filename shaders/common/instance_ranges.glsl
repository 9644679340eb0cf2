// The instance records (GpuInstance, 64 bytes) as src/passes/shared/instance_ranges.rs binds
// them: one buffer in two ranges of INSTANCE_RANGE_RECORDS records (4 GiB - 64 bytes), since one
// storage buffer binding addresses at most maxStorageBufferRange bytes (2^32 - 1 on NVIDIA and
// AMD) and 10^8 records take 6.4 GB. Range 0 is at the shader's own binding INSTANCES_BINDING,
// range 1 at INSTANCE_RANGE_BINDING; with PREV_INSTANCES_BINDING defined, the previous records
// (motion vectors) likewise, range 1 at PREV_INSTANCE_RANGE_BINDING. Shaders that write records
// see them as four 16-byte words each instead: INSTANCE_WORDS_BINDING and
// PREV_INSTANCE_WORDS_BINDING. A range past the scene's end is bound but never read. Include
// after scene.glsl.
#ifndef CULLGRAPH_INSTANCE_RANGES_GLSL
#define CULLGRAPH_INSTANCE_RANGES_GLSL

#define INSTANCE_RANGE_RECORDS 67108863u
// After the textures' 16 bindings from 16 on (textures.glsl).
#define INSTANCE_RANGE_BINDING 32
#define PREV_INSTANCE_RANGE_BINDING 33

#ifdef INSTANCES_BINDING
layout(set = 0, binding = INSTANCES_BINDING, scalar) readonly buffer InstanceRange0 { GpuInstance instance_range_0[]; };
layout(set = 0, binding = INSTANCE_RANGE_BINDING, scalar) readonly buffer InstanceRange1 { GpuInstance instance_range_1[]; };

// (Assigned in branches, not chosen by a conditional expression or returned from them: the two
// blocks' structs are distinct types, which the compiler copies member by member only there.)
GpuInstance instance_record(uint id) {
    GpuInstance record;
    if (id < INSTANCE_RANGE_RECORDS) {
        record = instance_range_0[id];
    } else {
        record = instance_range_1[id - INSTANCE_RANGE_RECORDS];
    }
    return record;
}
#endif

#ifdef PREV_INSTANCES_BINDING
layout(set = 0, binding = PREV_INSTANCES_BINDING, scalar) readonly buffer PrevInstanceRange0 { GpuInstance prev_instance_range_0[]; };
layout(set = 0, binding = PREV_INSTANCE_RANGE_BINDING, scalar) readonly buffer PrevInstanceRange1 { GpuInstance prev_instance_range_1[]; };

GpuInstance prev_instance_record(uint id) {
    GpuInstance record;
    if (id < INSTANCE_RANGE_RECORDS) {
        record = prev_instance_range_0[id];
    } else {
        record = prev_instance_range_1[id - INSTANCE_RANGE_RECORDS];
    }
    return record;
}
#endif

#ifdef INSTANCE_WORDS_BINDING
layout(set = 0, binding = INSTANCE_WORDS_BINDING) buffer InstanceWords0 { uvec4 instance_words_0[]; };
layout(set = 0, binding = INSTANCE_RANGE_BINDING) buffer InstanceWords1 { uvec4 instance_words_1[]; };

// Word `k` (0..3) of instance `id`'s record.
uvec4 instance_word(uint id, uint k) {
    return id < INSTANCE_RANGE_RECORDS ? instance_words_0[id * 4u + k]
                                       : instance_words_1[(id - INSTANCE_RANGE_RECORDS) * 4u + k];
}

void set_instance_word(uint id, uint k, uvec4 word) {
    if (id < INSTANCE_RANGE_RECORDS) {
        instance_words_0[id * 4u + k] = word;
    } else {
        instance_words_1[(id - INSTANCE_RANGE_RECORDS) * 4u + k] = word;
    }
}
#endif

#ifdef PREV_INSTANCE_WORDS_BINDING
layout(set = 0, binding = PREV_INSTANCE_WORDS_BINDING) writeonly buffer PrevInstanceWords0 { uvec4 prev_instance_words_0[]; };
layout(set = 0, binding = PREV_INSTANCE_RANGE_BINDING) writeonly buffer PrevInstanceWords1 { uvec4 prev_instance_words_1[]; };

void set_prev_instance_word(uint id, uint k, uvec4 word) {
    if (id < INSTANCE_RANGE_RECORDS) {
        prev_instance_words_0[id * 4u + k] = word;
    } else {
        prev_instance_words_1[(id - INSTANCE_RANGE_RECORDS) * 4u + k] = word;
    }
}
#endif

#endif
