#version 460
// Instance cull, step 2 of 2. Workgroup 0 writes the commands; every other workgroup places the
// survivors of its share of the blocks (MULTI_VIEW: of one block, every view's). All read only
// what the test step finished writing, so none waits for another (Vulkan does not promise that
// a waiting workgroup lets another make progress).
//
// Survivors are compacted in slot order: a survivor's position is the number of survivors in
// slots before it (superblock counts before its superblock + block counts before its block in
// the superblock + bits before it in the block). Slots are sorted by draw group, so each group's
// survivors form one slice, in slot order, every run; the group's command starts there
// (first instance = the survivors of the groups before it, summed from the group counts).
// Groups are sorted by face cull (src/passes/shared/face_cull.rs): each face cull's commands are
// compacted from its region's first group on, with a count of its own.
//
// VISIBLE_OUT (late phase): each block also places the instance ids of its visible slots, the
// same way, and workgroup 0 writes the commands, the count and the counters of that list too:
// the draw list that the next frame's early draw draws as it is, with no cull pass of its own.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "cull_common.glsl"
#include "../common/line_dispatch.glsl"

#define THREADS 256u
layout(local_size_x = 256) in;

#ifdef MULTI_VIEW
// Workgroup v < view_count writes view v's commands; every other workgroup places one block's
// survivors of every view that has any there.
#include "cull_views.glsl"
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 14, scalar) readonly buffer ViewTable { ViewBuffers view_table[]; };
#ifdef LOD
// Each view's level bits are reached through the table.
layout(set = 0, binding = 15, scalar) readonly buffer LodLevels { LodLevel lod_levels[]; };
#endif
#else
layout(set = 0, binding = 0) readonly buffer DrawBits { uint draw_bits[]; };
layout(set = 0, binding = 1) buffer Scratch { uint scratch[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Groups { DrawGroup groups[]; };
layout(set = 0, binding = 3) readonly buffer SlotInstances { uint slot_instances[]; };
layout(set = 0, binding = 4) writeonly buffer DrawIds { uint draw_ids[]; };
layout(set = 0, binding = 5) buffer GroupCounts { uint group_counts[]; };
layout(set = 0, binding = 6, scalar) writeonly buffer Commands { DrawCommand commands[]; };
layout(set = 0, binding = 7) writeonly buffer DrawCount { uint draw_count[FACE_CULL_REGIONS]; };
layout(set = 0, binding = 8, scalar) writeonly buffer Stats { CullStats stats; };

#ifdef LOD
layout(set = 0, binding = 14, scalar) readonly buffer LodLevels { LodLevel lod_levels[]; };
layout(set = 0, binding = 15) readonly buffer LevelBits { uint level_bits[]; };
#endif
#ifdef VISIBLE_OUT
layout(set = 0, binding = 9) readonly buffer VisNow { uint vis_now[]; };
layout(set = 0, binding = 10) writeonly buffer VisibleIds { uint visible_ids[]; };
// The next frame's early draw list: its commands, their count, and its counters (CullStats,
// tested 0), all history buffers the next frame reads as `.prev`.
layout(set = 0, binding = 11, scalar) writeonly buffer ListCommands { DrawCommand list_commands[]; };
layout(set = 0, binding = 12) writeonly buffer ListCount { uint list_count[FACE_CULL_REGIONS]; };
layout(set = 0, binding = 13, scalar) writeonly buffer ListStats { CullStats list_stats; };
#endif

#endif

layout(push_constant) uniform Push {
    uint slot_count;
    uint group_count;
    uint superblocks;
    uint region_first[FACE_CULL_REGIONS];  // first group of each face cull's region
#ifdef MULTI_VIEW
    uint view_count;
#else
    uint placers;                          // workgroups that place blocks (all but workgroup 0)
#endif
    uint groups_out_of_slot_order;         // 1: `group_order` is not the identity
} pc;

// The draw groups in the order of their slots (groups with slots first, by first slot). A
// changing world's group that grew takes slots after every other group's, while its command
// stays in its region: its survivors are then placed after groups that come later in group
// order, and commands take their first instance from this order.
layout(set = 0, binding = 16) readonly buffer GroupOrder { uint group_order[]; };
#ifdef BLOCK_LIST
// The test step's dispatch size, which the block step counts up (`BlockList` in
// instance_cull.comp): zeroed here, after the test step read it, for the next run.
layout(set = 0, binding = 17) writeonly buffer BlockList { uint block_list_count; };
#endif

// Placing a block: its draw bits [0] and visibility bits [1], and the survivors / visible slots
// before it.
shared uint sh_words[2][CULL_WORDS_PER_BLOCK];
shared uint sh_before[2];
// Writing the commands.
shared uvec4 sh_scan[THREADS];
shared uint sh_totals[8];
// Per list (0: drawn, 1: visible) and level, its slots this run (LOD); whether any list has
// slots at a level.
shared uint sh_level_totals[2][LOD_LEVELS];
shared uint sh_level_used[LOD_LEVELS];


// Bits of `sh_words[which]` below bit `k` of the block (0..CULL_BLOCK).
uint local_before(uint which, uint k) {
    uint count = 0u;
    for (uint w = 0u; w < (k >> 5u); ++w) count += bitCount(sh_words[which][w]);
    uint bit = k & 31u;
    if (bit != 0u) count += bitCount(sh_words[which][k >> 5u] & ((1u << bit) - 1u));
    return count;
}

bool bit_set(uint which, uint k) { return ((sh_words[which][k >> 5u] >> (k & 31u)) & 1u) != 0u; }

#ifdef LOD
// The block's level bit planes, and per list and level the slots placed before the block.
shared uint sh_planes[LOD_PLANES][CULL_WORDS_PER_BLOCK];
shared uint sh_level_before[2][LOD_LEVELS];

// Word `w` of the block's slots at `level`.
uint level_mask(uint w, uint level) {
    uint mask = ~0u;
    for (uint p = 0u; p < LOD_PLANES; ++p) mask &= ((level >> p) & 1u) != 0u ? sh_planes[p][w] : ~sh_planes[p][w];
    return mask;
}

uint level_of(uint k) {
    uint level = 0u;
    for (uint p = 0u; p < LOD_PLANES; ++p) level |= ((sh_planes[p][k >> 5u] >> (k & 31u)) & 1u) << p;
    return level;
}

// Bits of `sh_words[which]` at `level` below bit `k` of the block.
uint local_before_at(uint which, uint k, uint level) {
    uint count = 0u;
    for (uint w = 0u; w < (k >> 5u); ++w) count += bitCount(sh_words[which][w] & level_mask(w, level));
    uint bit = k & 31u;
    if (bit != 0u) count += bitCount(sh_words[which][k >> 5u] & level_mask(k >> 5u, level) & ((1u << bit) - 1u));
    return count;
}

// Per list and level, the slots before block `block` in the level-major order: where its
// superblock's slots of that level start (`cull_levels.comp`), plus that level's slots in the
// blocks before it in the superblock (one invocation per such block, at most 63). Called in
// uniform control flow; `sh_level_before` is complete after the next barrier.
void sum_levels_before(uint block) {
    uint lane = gl_LocalInvocationIndex;
    uint super_index = block / CULL_SUPERBLOCK;
    if (lane < 2u * LOD_LEVELS) {
        uint list = lane / LOD_LEVELS, level = lane % LOD_LEVELS;
        sh_level_before[list][level] = scratch[scratch_level_start(pc.superblocks, pc.slot_count, super_index, list, level)];
    }
    barrier();
    uint k = super_index * CULL_SUPERBLOCK + lane;
    bool before = k < block;
    for (uint list = 0u; list < 2u; ++list) {
        for (uint level = 0u; level < LOD_LEVELS; ++level) {
            uint n = before ? scratch[scratch_level_block(pc.superblocks, pc.slot_count, list, k, level)] : 0u;
            n = subgroupAdd(n);
            if (subgroupElect() && n != 0u) atomicAdd(sh_level_before[list][level], n);
        }
    }
}
#endif

// Places block `block`'s survivors (and with VISIBLE_OUT its visible slots). Called in uniform
// control flow.
void place_block(uint block, uint run) {
    uint lane = gl_LocalInvocationIndex;
    uint drawn = scratch[scratch_block(pc.superblocks, block)];
#ifdef VISIBLE_OUT
    uint visible = scratch[scratch_visible_block(pc.superblocks, pc.slot_count, block)];
#else
    uint visible = 0u;
#endif
    // Nothing to place (every invocation reads the same words, so all return together).
    if (drawn == 0u && visible == 0u) return;
    if (lane < CULL_WORDS_PER_BLOCK) {
        sh_words[0][lane] = drawn != 0u ? draw_bits[block * CULL_WORDS_PER_BLOCK + lane] : 0u;
        sh_words[1][lane] = 0u;
#ifdef VISIBLE_OUT
        // The visibility buffer holds ceil(slots / 32) words; the last block may run past it.
        uint vis_word = block * CULL_WORDS_PER_BLOCK + lane;
        if (visible != 0u && vis_word < (pc.slot_count + 31u) / 32u) sh_words[1][lane] = vis_now[vis_word];
#endif
    }
    if (lane < 2u) sh_before[lane] = 0u;
#ifdef LOD
    if (lane < LOD_PLANES * CULL_WORDS_PER_BLOCK) {
        uint p = lane / CULL_WORDS_PER_BLOCK, w = lane % CULL_WORDS_PER_BLOCK;
        uint blocks = cull_blocks(pc.slot_count);
        sh_planes[p][w] = level_bits[p * blocks * CULL_WORDS_PER_BLOCK + block * CULL_WORDS_PER_BLOCK + w];
    }
    sum_levels_before(block);
    barrier();
    uint slot = block * CULL_BLOCK + lane;
    uint level = level_of(lane);
    if (bit_set(0u, lane)) {
        draw_ids[sh_level_before[0][level] + local_before_at(0u, lane, level)] = slot_instances[slot];
    }
#ifdef VISIBLE_OUT
    if (bit_set(1u, lane)) {
        visible_ids[sh_level_before[1][level] + local_before_at(1u, lane, level)] = slot_instances[slot];
    }
#endif
#else
    uint super_index = block / CULL_SUPERBLOCK;
    uvec2 sum = uvec2(0u);
    for (uint s = lane; s < super_index; s += THREADS) {
        uint at = scratch_super(pc.superblocks, run, s);
        sum.x += scratch[at + SUPER_SURVIVORS];
#ifdef VISIBLE_OUT
        sum.y += scratch[at + SUPER_VISIBLE];
#endif
    }
    for (uint k = super_index * CULL_SUPERBLOCK + lane; k < block; k += THREADS) {
        sum.x += scratch[scratch_block(pc.superblocks, k)];
#ifdef VISIBLE_OUT
        sum.y += scratch[scratch_visible_block(pc.superblocks, pc.slot_count, k)];
#endif
    }
    barrier();
    sum = subgroupAdd(sum);
    if (subgroupElect()) {
        if (sum.x != 0u) atomicAdd(sh_before[0], sum.x);
        if (sum.y != 0u) atomicAdd(sh_before[1], sum.y);
    }
    barrier();
    // Bits past the last slot are never set.
    uint slot = block * CULL_BLOCK + lane;
    if (bit_set(0u, lane)) draw_ids[sh_before[0] + local_before(0u, lane)] = slot_instances[slot];
#ifdef VISIBLE_OUT
    if (bit_set(1u, lane)) visible_ids[sh_before[1] + local_before(1u, lane)] = slot_instances[slot];
#endif
#endif
}

// Scan of one value per invocation in invocation order (four sums at once); returns the
// invocation's exclusive prefix, and the total over the workgroup in `total`. `sh_scan` keeps
// the inclusive scan for the caller, which waits (barrier) before the next scan.
uvec4 workgroup_exclusive_scan(uvec4 value, out uvec4 total) {
    uint lane = gl_LocalInvocationIndex;
    sh_scan[lane] = value;
    barrier();
    for (uint offset = 1u; offset < THREADS; offset <<= 1u) {
        uvec4 add = lane >= offset ? sh_scan[lane - offset] : uvec4(0u);
        barrier();
        sh_scan[lane] += add;
        barrier();
    }
    uvec4 inclusive = sh_scan[lane];
    total = sh_scan[THREADS - 1u];
    return inclusive - value;
}

// Counters of the run: sums of the superblock records (indices into sh_totals).
#define TOTAL_TESTED 0
#define TOTAL_FRUSTUM 1
#define TOTAL_OCCLUSION 2
#define TOTAL_VISIBLE 3
#define TOTAL_TRIANGLES 5   // three words: triangle count bits 0-23, 24-47, 48-63

// A group's count in `group_counts` (survivors of group g at level l at
// `l * group_count + g`, then the visible slots the same way), zeroed for the next run.
uint take_group_count(uint at) {
    uint count = group_counts[at];
    if (count != 0u) group_counts[at] = 0u;
    return count;
}

// Where the first instance of group `g`'s command at `level` in list `list` (0: drawn, 1:
// visible) is kept when groups are out of slot order: after the counts in `group_counts`.
uint first_instance_at(uint list, uint level, uint g) {
    return ((2u + list) * LOD_LEVELS + level) * pc.group_count + g;
}

// What one draw list's commands add up to (their number per region: `sh_written`).
struct ListTotals {
    uint placed;         // instances
    uint64_t triangles;  // this invocation's share
};

// Per list (0: drawn, 1: visible) and region, the commands written so far. In shared memory,
// not in each invocation's registers: the pipeline's placers would pay for those too.
shared uint sh_written[2][FACE_CULL_REGIONS];

// The region of group `g`.
uint region_of(uint g) {
    uint r = 0u;
    for (uint i = 1u; i < FACE_CULL_REGIONS; ++i) r += g >= pc.region_first[i] ? 1u : 0u;
    return r;
}

// One past the last group of region `r`.
uint region_end(uint r) { return r + 1u < FACE_CULL_REGIONS ? pc.region_first[r + 1u] : pc.group_count; }

// Groups per chunk of the command scan: one fewer than the threads, so that the scan's last
// lane (which holds no group) reads as the chunk's total.
#define CHUNK_GROUPS (THREADS - 1u)

// The lane of group `g` in the chunk from group `chunk` on, clamped to the chunk.
uint chunk_lane(uint g, uint chunk) { return clamp(g, chunk, chunk + CHUNK_GROUPS) - chunk; }

// The scan before lane `lane` (the inclusive scan is still in `sh_scan`).
uvec4 scanned_before(uint lane) { return lane == 0u ? uvec4(0u) : sh_scan[lane - 1u]; }

// Adds the chunk's commands in region `r` of list `list` to `sh_written`: the chunk's commands
// before the region's end less those before its start (scan component y for the drawn list,
// w for the visible one).
void add_region_commands(uint list, uint r, uint chunk) {
    uvec4 end = scanned_before(chunk_lane(region_end(r), chunk));
    uvec4 start = scanned_before(chunk_lane(pc.region_first[r], chunk));
    sh_written[list][r] += list == 0u ? end.y - start.y : end.w - start.w;
}

// A group's command at level `level` for `count` instances from `first_instance` on; adds its
// triangles to `t`.
DrawCommand group_command(DrawGroup group, uint level, uint count, uint first_instance, inout ListTotals t) {
    DrawCommand cmd;
    cmd.index_count = group.index_count;
    cmd.first_index = group.first_index;
#ifdef LOD
    if (level != 0u) {
        LodLevel l = lod_levels[group.lod_first + level - 1u];
        cmd.index_count = l.index_count;
        cmd.first_index = l.first_index;
    }
#endif
    cmd.instance_count = count;
    cmd.vertex_offset = group.vertex_offset;
    cmd.first_instance = first_instance;
    t.triangles += uint64_t(cmd.index_count / 3u) * uint64_t(count);
    return cmd;
}

// For groups out of slot order: each group's first instance in each list, level after level
// and in slot order within a level (the order the placers put the instance ids in), into
// `group_counts` at `first_instance_at`. The counts are read, not taken. Called in uniform
// control flow.
void first_instances_in_slot_order() {
    uint lane = gl_LocalInvocationIndex;
    uvec2 placed = uvec2(0u);
    for (uint level = 0u; level < LOD_LEVELS; ++level) {
#ifdef LOD
        if (sh_level_used[level] == 0u) continue;
#endif
        for (uint chunk = 0u; chunk < pc.group_count; chunk += THREADS) {
            uint i = chunk + lane;
            uint g = i < pc.group_count ? group_order[i] : 0u;
            uvec2 counts = uvec2(0u);
            if (i < pc.group_count) {
                counts.x = group_counts[level * pc.group_count + g];
#ifdef VISIBLE_OUT
                counts.y = group_counts[(LOD_LEVELS + level) * pc.group_count + g];
#endif
            }
            uvec4 total;
            uvec4 before = workgroup_exclusive_scan(uvec4(counts, 0u, 0u), total);
            if (i < pc.group_count) {
                group_counts[first_instance_at(0u, level, g)] = placed.x + before.x;
                group_counts[first_instance_at(1u, level, g)] = placed.y + before.y;
            }
            placed += total.xy;
            // The scan is read before the next chunk's overwrites it.
            barrier();
        }
    }
    // The first instances are read by other invocations of this workgroup.
    memoryBarrierBuffer();
    barrier();
}

// One command per non-empty group and level, level after level and in group order within a
// level, for this run's survivors (`commands`) and, with VISIBLE_OUT, for the visible list
// (`list_commands`), from one scan of both counts; every count back to zero. Levels that no
// slot took (`sh_level_used`) are skipped. Called in uniform control flow.
void write_group_commands(out ListTotals drawn, out ListTotals listed) {
    uint lane = gl_LocalInvocationIndex;
    drawn = ListTotals(0u, 0ul);
    listed = ListTotals(0u, 0ul);
    if (lane < 2u * FACE_CULL_REGIONS) sh_written[lane / FACE_CULL_REGIONS][lane % FACE_CULL_REGIONS] = 0u;
    bool out_of_order = pc.groups_out_of_slot_order != 0u;
    if (out_of_order) first_instances_in_slot_order();
    barrier();
    for (uint level = 0u; level < LOD_LEVELS; ++level) {
#ifdef LOD
        if (sh_level_used[level] == 0u) continue;
#endif
        for (uint chunk = 0u; chunk < pc.group_count; chunk += CHUNK_GROUPS) {
            uint g = chunk + lane;
            uint count = 0u, visible = 0u;
            DrawGroup group;
            if (lane < CHUNK_GROUPS && g < pc.group_count) {
                count = take_group_count(level * pc.group_count + g);
#ifdef VISIBLE_OUT
                visible = take_group_count((LOD_LEVELS + level) * pc.group_count + g);
#endif
                if (count != 0u || visible != 0u) group = groups[g];
            }
            uint r = region_of(g);
            uvec4 total;
            uvec4 before = workgroup_exclusive_scan(
                uvec4(count, count != 0u ? 1u : 0u, visible, visible != 0u ? 1u : 0u), total);
            // Groups are sorted by region, so the region's groups in the chunk are one run of
            // lanes: a command's place in its region is the chunk's commands before it less
            // those before the run, after what earlier chunks wrote in the region.
            uvec4 before_run = uvec4(0u);
            if (count != 0u || visible != 0u) before_run = scanned_before(chunk_lane(pc.region_first[r], chunk));
            if (count != 0u) {
                uint at = pc.region_first[r] + sh_written[0][r] + before.y - before_run.y;
                uint first = out_of_order ? group_counts[first_instance_at(0u, level, g)] : drawn.placed + before.x;
                commands[at] = group_command(group, level, count, first, drawn);
            }
#ifdef VISIBLE_OUT
            if (visible != 0u) {
                uint at = pc.region_first[r] + sh_written[1][r] + before.w - before_run.w;
                uint first = out_of_order ? group_counts[first_instance_at(1u, level, g)] : listed.placed + before.z;
                list_commands[at] = group_command(group, level, visible, first, listed);
            }
#endif
            drawn.placed += total.x;
            listed.placed += total.z;
            // Every invocation has read `sh_written` before it grows...
            barrier();
            if (lane < 2u * FACE_CULL_REGIONS) add_region_commands(lane / FACE_CULL_REGIONS, lane % FACE_CULL_REGIONS, chunk);
            // ...and the scan, before the next chunk's overwrites it.
            barrier();
        }
    }
}

// The workgroup's triangle total (each part is below 2^24 per invocation, so a sum over 256
// fits), from the subgroups' sums added into `sh_totals[TOTAL_TRIANGLES..]`; `sh_totals` zeroed
// before. Called in uniform control flow.
uint64_t workgroup_triangles(uint64_t triangles) {
    uvec3 parts = subgroupAdd(uvec3(uint(triangles) & 0xFFFFFFu, uint(triangles >> 24) & 0xFFFFFFu,
                                    uint(triangles >> 48)));
    if (subgroupElect()) {
        for (uint i = 0u; i < 3u; ++i) atomicAdd(sh_totals[TOTAL_TRIANGLES + i], parts[i]);
    }
    barrier();
    return uint64_t(sh_totals[TOTAL_TRIANGLES]) + (uint64_t(sh_totals[TOTAL_TRIANGLES + 1]) << 24)
        + (uint64_t(sh_totals[TOTAL_TRIANGLES + 2]) << 48);
}

CullStats stats_record(uint tested, uint frustum, uint occlusion, uint drawn, uint draws, uint64_t triangles,
                       uint survivors, uint list) {
    CullStats s;
    s.tested = tested;
    s.frustum_culled = frustum;
    s.occlusion_culled = occlusion;
    s.drawn = drawn;
    s.draws = draws;
    s.triangles_lo = uint(triangles);
    s.triangles_hi = uint(triangles >> 32);
    s.survivors = survivors;
    for (uint i = 0u; i < 8u; ++i) s.level_instances[i] = 0u;
#ifdef LOD
    for (uint i = 0u; i < LOD_LEVELS; ++i) s.level_instances[i] = sh_level_totals[list][i];
#else
    s.level_instances[0] = drawn;
#endif
    return s;
}

// The commands of list `list` (0: drawn, 1: visible), once `write_group_commands` returned.
uint commands_of(uint list) {
    uint n = 0u;
    for (uint r = 0u; r < FACE_CULL_REGIONS; ++r) n += sh_written[list][r];
    return n;
}

void write_commands() {
    uint lane = gl_LocalInvocationIndex;
    if (lane < 8u) sh_totals[lane] = 0u;
    barrier();
    uvec4 counters = uvec4(0u);
    uint run = scratch[SCRATCH_PLACE_RUN];
    for (uint s = lane; s < pc.superblocks; s += THREADS) {
        uint at = scratch_super(pc.superblocks, run, s);
        counters += uvec4(scratch[at + SUPER_TESTED], scratch[at + SUPER_FRUSTUM], scratch[at + SUPER_OCCLUSION],
                          scratch[at + SUPER_VISIBLE]);
    }
#ifdef LOD
    if (lane < 2u * LOD_LEVELS) sh_level_totals[lane / LOD_LEVELS][lane % LOD_LEVELS] = 0u;
    barrier();
    uint level_sums[2][LOD_LEVELS];
    for (uint list = 0u; list < 2u; ++list) {
        for (uint l = 0u; l < LOD_LEVELS; ++l) level_sums[list][l] = 0u;
    }
    for (uint s = lane; s < pc.superblocks; s += THREADS) {
        uint at = scratch_super(pc.superblocks, run, s);
        for (uint list = 0u; list < 2u; ++list) {
            for (uint l = 0u; l < LOD_LEVELS; ++l) level_sums[list][l] += scratch[at + SUPER_LEVEL(list, l)];
        }
    }
    for (uint list = 0u; list < 2u; ++list) {
        for (uint l = 0u; l < LOD_LEVELS; ++l) {
            uint sum = subgroupAdd(level_sums[list][l]);
            if (subgroupElect() && sum != 0u) atomicAdd(sh_level_totals[list][l], sum);
        }
    }
    barrier();
    if (lane < LOD_LEVELS) sh_level_used[lane] = sh_level_totals[0][lane] | sh_level_totals[1][lane];
    // Read before the next run's half is zeroed below (the halves alternate, so not this one),
    // and before write_group_commands reads sh_level_used.
    barrier();
#endif
    // The next run's half back to zero (its last readers finished in the previous run).
    uint next = scratch_super(pc.superblocks, run + 1u, 0u);
    for (uint i = lane; i < pc.superblocks * SUPER_WORDS; i += THREADS) scratch[next + i] = 0u;

    ListTotals drawn, listed;
    write_group_commands(drawn, listed);
    counters = subgroupAdd(counters);
    if (subgroupElect()) {
        for (uint i = 0u; i < 4u; ++i) atomicAdd(sh_totals[TOTAL_TESTED + i], counters[i]);
    }
    uint64_t triangles = workgroup_triangles(drawn.triangles);
    if (lane == 0u) {
        for (uint r = 0u; r < FACE_CULL_REGIONS; ++r) draw_count[r] = sh_written[0][r];
        stats = stats_record(sh_totals[TOTAL_TESTED], sh_totals[TOTAL_FRUSTUM], sh_totals[TOTAL_OCCLUSION], drawn.placed,
                             commands_of(0u), triangles, sh_totals[TOTAL_VISIBLE], 0u);
        // Nothing reads this word in this dispatch: the next run's test step does.
        scratch[SCRATCH_TEST_RUN] = run + 1u;
#ifdef BLOCK_LIST
        block_list_count = 0u;
#endif
    }
#ifdef VISIBLE_OUT
    // The next frame's early draw list: this frame's visible slots, per group, placed by the
    // other workgroups into `visible_ids`.
    barrier();
    if (lane >= TOTAL_TRIANGLES && lane < TOTAL_TRIANGLES + 3u) sh_totals[lane] = 0u;
    barrier();
    uint64_t list_triangles = workgroup_triangles(listed.triangles);
    if (lane == 0u) {
        for (uint r = 0u; r < FACE_CULL_REGIONS; ++r) list_count[r] = sh_written[1][r];
        list_stats = stats_record(0u, 0u, 0u, listed.placed, commands_of(1u), list_triangles, 0u, 1u);
    }
#endif
}

#ifndef MULTI_VIEW
// The blocks of this placer's batch that have something to place, and how many.
shared uint sh_batch[THREADS];
shared uint sh_batch_count;

// Places the blocks of placer `placer` (one of pc.placers): blocks placer, placer + placers,
// placer + 2 placers..., THREADS at a time. Each invocation reads one block's counts, so a batch
// costs one memory round trip however few of its blocks hold survivors (most blocks of a large
// scene hold none), and only those are placed; the interleaving spreads the blocks that do
// over the placers. Fewer workgroups than blocks, since a workgroup per block costs more to
// launch than most blocks cost to read.
void place_blocks(uint placer) {
    uint lane = gl_LocalInvocationIndex;
    uint blocks = cull_blocks(pc.slot_count);
    uint run = scratch[SCRATCH_PLACE_RUN];
    uint mine = placer < blocks ? (blocks - placer + pc.placers - 1u) / pc.placers : 0u;
    for (uint first = 0u; first < mine; first += THREADS) {
        if (lane == 0u) sh_batch_count = 0u;
        barrier();
        uint block = placer + (first + lane) * pc.placers;
        if (first + lane < mine) {
            uint work = scratch[scratch_block(pc.superblocks, block)];
#ifdef VISIBLE_OUT
            work |= scratch[scratch_visible_block(pc.superblocks, pc.slot_count, block)];
#endif
            if (work != 0u) sh_batch[atomicAdd(sh_batch_count, 1u)] = block;
        }
        barrier();
        uint count = sh_batch_count;
        for (uint i = 0u; i < count; ++i) {
            place_block(sh_batch[i], run);
            // The next block reuses the shared words.
            barrier();
        }
        // Every invocation has read the count before the next batch zeroes it.
        barrier();
    }
}
#endif

#ifdef MULTI_VIEW
// Which views have survivors or visible slots in the block.
shared uint sh_views_with_work;

// Places block `block` of every view that has something there, one view after another.
void place_block_of_views(uint block) {
    uint lane = gl_LocalInvocationIndex;
    if (lane == 0u) sh_views_with_work = 0u;
    barrier();
    if (lane < pc.view_count) {
        select_view_buffers(view_table[lane], lane);
        uint work = scratch[scratch_block(pc.superblocks, block)];
#ifdef VISIBLE_OUT
        work |= scratch[scratch_visible_block(pc.superblocks, pc.slot_count, block)];
#endif
        if (work != 0u) atomicOr(sh_views_with_work, 1u << lane);
    }
    barrier();
    uint views = sh_views_with_work;
    while (views != 0u) {
        uint v = findLSB(views);
        views &= views - 1u;
        select_view_buffers(view_table[v], v);
        place_block(block, scratch[SCRATCH_PLACE_RUN]);
        // The next view reuses the shared words.
        barrier();
    }
}
#endif

void main() {
    uint w = line_workgroup();
#ifdef MULTI_VIEW
    if (w < pc.view_count) {
        select_view_buffers(view_table[w], w);
        write_commands();
        return;
    }
    // Past the last block of the line (the whole workgroup, before any barrier).
    if (w - pc.view_count >= cull_blocks(pc.slot_count)) return;
    place_block_of_views(w - pc.view_count);
#else
    if (w == 0u) {
        write_commands();
        return;
    }
    // Past the last placer of the line (the whole workgroup, before any barrier).
    if (w - 1u >= pc.placers) return;
    place_blocks(w - 1u);
#endif
}
