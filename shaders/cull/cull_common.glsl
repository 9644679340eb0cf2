// Data of the instance-cull pass. Layouts mirror src/passes/shared/cull_data.rs and
// src/passes/instance_cull.rs (scalar block layout).
//
// Slots are instances sorted by draw group, each group in spatial order (Morton order of the
// instances' origins, equal codes in instance order; src/passes/shared/scene_buffers.rs), which is the
// unculled draw list's order. Survivors are compacted in slot order by a prefix sum over one survivor bit
// per slot, so each group's survivors form one slice in slot order and draw order, and with
// it every depth tie, does not depend on timing.
#ifndef CULLGRAPH_CULL_COMMON_GLSL
#define CULLGRAPH_CULL_COMMON_GLSL

#extension GL_EXT_scalar_block_layout : require

// Threads (and slots) per block of the prefix sum; a multiple of 32 so blocks own whole words.
#define CULL_BLOCK 256u
#define CULL_WORDS_PER_BLOCK (CULL_BLOCK / 32u)
// A block's bound (src/passes/shared/cull_blocks.rs GpuBlockBound): 12 words, its flags in
// word 7; BLOCK_TESTS_EVERY_SLOT there has the cull test the block slot by slot.
#define BLOCK_BOUND_WORDS 12u
#define BLOCK_BOUND_FLAGS_WORD 7u
#define BLOCK_TESTS_EVERY_SLOT 1u

// Blocks of a pass over `slot_count` slots (at least one, which handles an empty scene).
uint cull_blocks(uint slot_count) { return max(1u, slot_count / CULL_BLOCK + (slot_count % CULL_BLOCK != 0u ? 1u : 0u)); }

// World bound of one slot, 32 bytes. The small quantities are half floats, rounded outward
// on the CPU and widened by their own rounding error (src/passes/shared/cull_data.rs), so the bound
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

// Regions of a command list, each with its own draw count (src/passes/shared/face_cull.rs): back,
// front and none for opaque materials, the same for alpha-masked ones, and the transparent
// instances' region, which the geometry passes skip.
#define FACE_CULL_REGIONS 7u
// The double-sided regions (opaque and masked): both faces drawn.
bool region_is_double_sided(uint region) { return region == 2u || region == 5u; }

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
    uint lod_first;       // the group's first level past the full mesh in the level table
    uint lod_count;       // its levels past the full mesh (0: always drawn whole)
    uint pad;
};

// One level of detail past the full mesh (GpuLodLevel in src/passes/shared/cull_data.rs).
struct LodLevel {
    uint first_index;
    uint index_count;
    float relative_error; // object-space error / the mesh's cull radius (times an instance's cull radius: world units)
    uint pad;
};

// Levels of detail (LOD): the test step chooses a level for each slot it draws or finds visible
// and stores it in three bit planes; each list is compacted level after level (level-major,
// then slot order), so each (level, group) pair's survivors are one slice and get one command.
// A group's counts are at [level * group_count + group]. Without LOD there is one level.
#ifdef LOD
#define LOD_LEVELS 8u
#else
#define LOD_LEVELS 1u
#endif
#define LOD_PLANES 3u

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
    uint level_instances[8];// instances drawn at each level of detail (all at 0 without LOD)
};

#define FLAG_OCCLUDER 1u
// A slot without an instance (src/scene/mod.rs FLAG_EMPTY_SLOT): never visible, never drawn.
#define FLAG_EMPTY_SLOT 64u
bool record_empty(CullRecord r) { return ((r.group_flags >> 24) & FLAG_EMPTY_SLOT) != 0u; }

// Blocks per superblock: a block's survivors-before is the sum of the superblock counts before
// its superblock plus the block counts before it in its superblock, read from what the test
// step finished writing (no workgroup ever waits for another, which Vulkan does not guarantee
// to make progress).
#define CULL_SUPERBLOCK 64u

// The pass's scratch buffer: a header, two halves of superblock records (one half per run,
// alternating, so the compact step can zero the next run's half while its own is being read),
// then one survivor count per block, then one visible count per block (both overwritten by
// every run).
//
// The run number: the test step reads SCRATCH_TEST_RUN (its parity picks the half) and hands it
// on in SCRATCH_PLACE_RUN; the compact step reads that and writes the next run's number into
// SCRATCH_TEST_RUN. Each word is written only in the dispatch that does not read it.
#define SCRATCH_TEST_RUN 0
#define SCRATCH_PLACE_RUN 1
#define SCRATCH_HEADER 8u
// Words of one superblock record, and their meaning (atomic sums over its blocks).
#define SUPER_SURVIVORS 0u      // instances drawn by this pass
#define SUPER_TESTED 1u         // instances evaluated
#define SUPER_FRUSTUM 2u        // of those, outside the frustum
#define SUPER_OCCLUSION 3u      // inside the frustum, behind the Hi-Z
#define SUPER_VISIBLE 4u        // visibility bits set (late phase)
#ifdef LOD
// Then, per list (0: drawn, 1: visible), its slots at each level.
#define SUPER_WORDS 24u
#define SUPER_LEVEL(list, level) (8u + (list) * LOD_LEVELS + (level))
#else
#define SUPER_WORDS 8u
#endif
uint scratch_super(uint superblocks, uint run, uint s) {
    return SCRATCH_HEADER + ((run & 1u) * superblocks + s) * SUPER_WORDS;
}
uint scratch_block(uint superblocks, uint b) { return SCRATCH_HEADER + 2u * superblocks * SUPER_WORDS + b; }
// After the block counts: one count of visibility bits set per block (late phase, VISIBLE_OUT),
// from which the compact step places the visible instances that the next frame's early phase
// draws.
uint scratch_visible_block(uint superblocks, uint slot_count, uint b) {
    uint blocks = cull_blocks(slot_count);
    return scratch_block(superblocks, blocks + b);
}
#ifdef LOD
// After the visible counts (LOD): per list (0: drawn, 1: visible), block and level, the block's
// slots of that list at that level.
uint scratch_level_block(uint superblocks, uint slot_count, uint list, uint b, uint level) {
    uint blocks = cull_blocks(slot_count);
    return scratch_block(superblocks, 2u * blocks + (list * blocks + b) * LOD_LEVELS + level);
}
// After those (LOD), written by `cull_levels.comp` each run: per superblock, list and level,
// where the superblock's slots of that list at that level start in the level-major order (every
// slot of lower levels, then this level's in the superblocks before).
uint scratch_level_start(uint superblocks, uint slot_count, uint s, uint list, uint level) {
    uint blocks = cull_blocks(slot_count);
    return scratch_level_block(superblocks, slot_count, 0u, 2u * blocks, 0u) + (s * 2u + list) * LOD_LEVELS + level;
}
#endif

#endif
