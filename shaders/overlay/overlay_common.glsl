// Data of the overlay pass. Layouts mirror src/passes/overlay.rs (scalar block layout).
//
// The CPU describes the panel once, when the pass is created, as text templates: one row of
// tokens per line, each token a literal ASCII character or a numeric field. Every frame
// overlay_text.comp fills the fields from this frame's cull counters (and the newest completed
// frame's GPU times, which the renderer writes to a host-visible buffer) into a grid of
// characters; overlay_draw.comp draws the grid with font8x8 glyphs over the image.
#ifndef CULLGRAPH_OVERLAY_COMMON_GLSL
#define CULLGRAPH_OVERLAY_COMMON_GLSL

#extension GL_EXT_scalar_block_layout : require

#define OVERLAY_MAX_ROWS 48u
#define OVERLAY_MAX_COLS 96u
#define OVERLAY_MAX_STATS 4u
#define OVERLAY_MAX_TIMED 64u

// Panel geometry in font pixels (times the scale): 8x8 glyphs on 10-pixel lines.
#define OVERLAY_GLYPH 8u
#define OVERLAY_LINE 10u
#define OVERLAY_PADDING 4u
#define OVERLAY_MARGIN 8u

// Template tokens: an ASCII code (< 128), a field, or the end of the row.
#define TOKEN_END 0xFFFFFFFFu
#define TOKEN_FIELD 0x10000000u

// Fields. Counters: the frame's totals as `crate::stats::cull::totals` makes them (culled counts
// of the pass that tested the most instances, drawn/draws/triangles summed over the passes).
#define FIELD_INSTANCES 0u
#define FIELD_TESTED 1u
#define FIELD_FRUSTUM 2u
#define FIELD_OCCLUSION 3u
#define FIELD_DRAWN 4u
#define FIELD_DRAWS 5u
#define FIELD_TRIANGLES 6u
#define FIELD_TOTAL_MS 7u      // the timed frame's total, as a time field
#define FIELD_TIMED_FRAME 8u   // which frame the times are from ("-" when none yet)
#define FIELD_MARKED 9u        // instances the culled view outlined
#define FIELD_POOL_USED 10u    // compressed G-buffer: pool blocks in use this frame
#define FIELD_POOL_BLOCKS 11u  // blocks in the pool
#define FIELD_OVERFLOW 12u     // samples whose fragments found the pool full
#define FIELD_EDGE_PIXELS 13u  // pixels with two or more distinct surfaces
#define FIELD_PASS_DRAWN 16u   // + stats slot: instances that pass drew
#define FIELD_PASS_MS 32u      // + pass index: its GPU time, 8 characters wide ("-" when unknown)

// Grid cells: 0 blank, else the ASCII code, | CELL_NUMBER for digits of fields.
#define CELL_NUMBER 0x100u

// Static description of the panel (written once by the CPU).
struct OverlayTemplate {
    uint rows;
    uint bar_col;      // column where the time bars start
    uint bar_chars;    // bar length at the largest time, in characters (0: no bars)
    uint pad0;
    int row_bar[OVERLAY_MAX_ROWS];                          // pass index of the row's bar, -1 none
    uint tokens[OVERLAY_MAX_ROWS * OVERLAY_MAX_COLS];       // per row, ended by TOKEN_END
};

// The newest completed frame's GPU times (written by the renderer every frame).
struct OverlayTimes {
    uint count;        // entries in ms (the plan's passes, in execution order)
    uint frame;        // frame they were measured in; 0xFFFFFFFF: none yet
    float total_ms;    // the whole frame; < 0 unknown
    float pad0;
    float ms[OVERLAY_MAX_TIMED];                            // < 0 unknown
};

// The formatted panel (written by overlay_text.comp, read by overlay_draw.comp).
struct OverlayText {
    uint rows;
    uint cols;         // panel width in characters (bars included)
    uint bar_col;      // as in the template
    uint bar_chars;
    float bar[OVERLAY_MAX_ROWS];                            // bar length in [0, 1], < 0 none
    uint cells[OVERLAY_MAX_ROWS * OVERLAY_MAX_COLS];
};

#endif
