// Several views culled in one dispatch (MULTI_VIEW): each view's buffers are reached through
// the addresses in a table of ViewBuffers (src/passes/instance_cull/views.rs writes it), and
// the names the single-view shaders use for them are macros over the selected view's. The
// scene's buffers (records, groups, slot instances) are bound as for one view.
#ifndef CULLGRAPH_CULL_VIEWS_GLSL
#define CULLGRAPH_CULL_VIEWS_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "cull_common.glsl"

// The most views one dispatch culls (MAX_TOGETHER in src/passes/instance_cull/views.rs): the
// pyramids are an array of samplers indexed by constants.
#define MAX_CULL_VIEWS 16u

layout(buffer_reference, std430, buffer_reference_align = 4) buffer U32Ref { uint w[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer CommandsRef { DrawCommand c[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer StatsRef { CullStats s; };

// One view's buffers (120 bytes; 0 where the view binds nothing).
struct ViewBuffers {
    uint64_t constants;      // FrameConstants
    uint64_t group_counts;
    uint64_t scratch;
    uint64_t draw_bits;
    uint64_t vis_prev;
    uint64_t vis;
    uint64_t draw_ids;
    uint64_t commands;
    uint64_t draw_count;
    uint64_t stats;
    uint64_t visible_ids;
    uint64_t list_commands;
    uint64_t list_count;
    uint64_t list_stats;
    uint64_t level_bits;     // LOD: each slot's level as bit planes
};

U32Ref g_group_counts;
U32Ref g_scratch;
U32Ref g_draw_bits;
U32Ref g_vis_prev;
U32Ref g_vis;
U32Ref g_draw_ids;
CommandsRef g_commands;
U32Ref g_draw_count;
StatsRef g_stats;
U32Ref g_visible_ids;
CommandsRef g_list_commands;
U32Ref g_list_count;
StatsRef g_list_stats;
U32Ref g_level_bits;
uint g_view;

void select_view_buffers(ViewBuffers b, uint v) {
    g_group_counts = U32Ref(b.group_counts);
    g_scratch = U32Ref(b.scratch);
    g_draw_bits = U32Ref(b.draw_bits);
    g_vis_prev = U32Ref(b.vis_prev);
    g_vis = U32Ref(b.vis);
    g_draw_ids = U32Ref(b.draw_ids);
    g_commands = CommandsRef(b.commands);
    g_draw_count = U32Ref(b.draw_count);
    g_stats = StatsRef(b.stats);
    g_visible_ids = U32Ref(b.visible_ids);
    g_list_commands = CommandsRef(b.list_commands);
    g_list_count = U32Ref(b.list_count);
    g_list_stats = StatsRef(b.list_stats);
    g_level_bits = U32Ref(b.level_bits);
    g_view = v;
}

#define group_counts g_group_counts.w
#define scratch g_scratch.w
#define draw_bits g_draw_bits.w
#define vis_prev g_vis_prev.w
#define vis_now g_vis.w
#define draw_ids g_draw_ids.w
#define commands g_commands.c
#define draw_count g_draw_count.w
#define stats g_stats.s
#define visible_ids g_visible_ids.w
#define list_commands g_list_commands.c
#define level_bits g_level_bits.w
#define list_count g_list_count.w
#define list_stats g_list_stats.s

#endif
