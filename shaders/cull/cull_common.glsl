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
// Blocks per workgroup of the test step: each thread has this many slots in flight, and fewer
// workgroups end with the done-counter's round trip.
#define CULL_TEST_BLOCKS 2u

// World bound of one slot, 32 bytes. The small quantities are half floats, rounded outward
// on the CPU and widened by their own rounding error (src/render/cull_data.rs), so the bound
// read here always contains the exact one.
struct CullRecord {
    vec3 center_hi;       // world center, hi part
    uint group_flags;     // draw group (24 bits) | instance flags << 24 | CULL_HUGE
    uint lo_xy;           // world center, lo part: f16 x, y
    uint lo_z_radius;     // f16 lo z, f16 sphere radius
    uint half_xy;         // f16 half extents x, y of the world box
    uint half_z;          // f16 half extent z (high half unused)
};

// Set when a bound does not fit half floats (larger than 65504): always visible.
#define CULL_HUGE 0x80000000u

vec3 record_center_lo(CullRecord r) { return vec3(unpackHalf2x16(r.lo_xy), unpackHalf2x16(r.lo_z_radius).x); }
float record_radius(CullRecord r) { return unpackHalf2x16(r.lo_z_radius).y; }
vec3 record_half_extent(CullRecord r) { return vec3(unpackHalf2x16(r.half_xy), unpackHalf2x16(r.half_z).x); }
uint record_group(CullRecord r) { return r.group_flags & 0xFFFFFFu; }

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

// The pass's scratch buffer: a header of counters, then one word per block, then one more per
// block. The test step stores each block's survivor count in the first and the draw group of its
// first survivor in the second; the last test workgroup to finish replaces the counts by their
// exclusive prefix sum. The scatter step reads both. No workgroup ever waits for another, which
// Vulkan does not guarantee to make progress.
//
// Finding the last workgroup takes two levels of counters: workgroup w counts into lane
// w % CULL_LANES, and the last of each lane into the top counter. Returning atomics on one
// address are serialised in the L2 (several ns each: some 20 us for 4000 workgroups on an
// H100), so each lane's counter and its share of the statistics live in their own 128-byte line.
#define CULL_LANES 64u
#define CULL_LINE 32u
#define SCRATCH_DONE_TOP 0u
// Words of lane l's line: done counter, then the statistics.
#define LANE_DONE 0u
#define LANE_TESTED 1u
#define LANE_FRUSTUM 2u
#define LANE_OCCLUSION 3u
#define LANE_VISIBLE 4u
uint scratch_lane(uint l, uint word) { return CULL_LINE * (1u + l) + word; }
#define SCRATCH_HEADER (CULL_LINE * (1u + CULL_LANES))
uint scratch_block(uint b) { return SCRATCH_HEADER + b; }
uint scratch_block_group(uint blocks, uint b) { return SCRATCH_HEADER + blocks + b; }

#endif
