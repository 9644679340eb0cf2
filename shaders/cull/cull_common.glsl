// Data of the instance-cull pass. Layouts mirror src/render/cull_data.rs and
// src/passes/instance_cull.rs (scalar block layout).
//
// Slots are instances sorted by draw group, each group in instance order (the unculled draw
// list's order). Survivors are compacted per group in slot order by a prefix sum over one
// survivor bit per slot, so draw order, and with it every depth tie, does not depend on timing.
#ifndef CULLGRAPH_CULL_COMMON_GLSL
#define CULLGRAPH_CULL_COMMON_GLSL

#extension GL_EXT_scalar_block_layout : require

// Threads (and slots) per block of the prefix sum; a multiple of 32 so blocks own whole words.
#define CULL_BLOCK 256u
#define CULL_WORDS_PER_BLOCK (CULL_BLOCK / 32u)

struct CullRecord {
    vec3 center_hi;     // world center of the bound, hi part
    float radius;       // bounding sphere radius
    vec3 center_lo;     // world center, lo part
    uint instance;      // scene instance id
    vec3 half_extent;   // world axis-aligned box half extents
    uint group_flags;   // draw group (24 bits) | instance flags << 24
};

struct DrawGroup {
    uint first_slot;
    uint slot_count;
    uint index_count;
    uint first_index;
    int vertex_offset;
    uint pad0;
    uint pad1;
    uint pad2;
};

struct DrawCommand {     // VkDrawIndexedIndirectCommand
    uint index_count;
    uint instance_count;
    uint first_index;
    int vertex_offset;
    uint first_instance;
};

// Counters of one cull pass (64 bytes; CullStats in src/stats/cull.rs).
struct CullStats {
    uint tested;            // instances this pass evaluated
    uint frustum_culled;    // of those, outside the frustum
    uint occlusion_culled;  // inside the frustum, behind the Hi-Z
    uint drawn;             // instances in this pass's draw list
    uint draws;             // non-empty draw commands
    uint triangles_lo;      // triangles drawn, low 32 bits
    uint triangles_hi;      // high 32 bits
    uint survivors;         // instances whose visibility bit this pass set (late phase)
    uint pad[8];
};

#define FLAG_OCCLUDER 1u

#endif
