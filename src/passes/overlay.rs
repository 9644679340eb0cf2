//! The culling-stat overlay (kind `overlay`): this frame's cull counters, the newest completed
//! frame's GPU milliseconds per pass, and two debug views, drawn in compute over the lit image.
//!
//! **Text without readback.** When the pass is created, the CPU describes the panel as text
//! templates (`shaders/overlay/overlay_common.glsl`): rows of tokens, each an ASCII character or a
//! numeric field (instances, tested, frustum-culled, occlusion-culled, drawn in total and per cull
//! pass, draws, triangles, milliseconds; with `gbuffer_stats` bound, the compressed G-buffer's
//! pool blocks in use, overflowed samples and pixels with two or more surfaces). Labels come
//! from the plan: the cull passes' `phase` (or their names) and every pass's name for the
//! timings. Each frame `overlay_text.comp` (one
//! workgroup, a thread per row) formats the fields from the counters the cull passes wrote to
//! their `stats` buffers earlier in the same frame, so the figures are this frame's, on the
//! GPU, with no readback; then `overlay_draw.comp` draws the character grid with font8x8 glyphs
//! (uploaded once). The totals are made as [`crate::stats::cull::totals`] makes the CPU's.
//!
//! **Timings.** GPU times are known only once a frame has completed. The renderer writes the
//! newest completed frame's times, in plan order, into a small host-visible buffer per frame in
//! flight ([`GpuPassTimes`], [`crate::passes::shared::SceneInputs::pass_times`]); the panel says
//! which frame they are from and draws a bar per pass proportional to its time.
//!
//! **Cost.** View `stats` dispatches over the panel's largest possible extent only (and leaves
//! every pixel outside this frame's panel untouched). The debug views are full screen: `hiz`
//! shows one Hi-Z level in grey (nearest: the texel that covers each pixel in the occlusion
//! test); `culled` projects every instance that is inside the frustum but not visible after the
//! late cull pass (= occlusion-culled this frame) with the cull's own math and tints its screen
//! rectangle red: per-row difference counts with integer atomics, a prefix sum per row, then a
//! tint whose depth grows with the number of overlapping rectangles and a bright edge where the
//! count changes. Deterministic: the same frame gives the same pixels.

use super::slots::{sized, slot, COUNTERS_BYTES, HIZ_FORMAT, LIT_OUTPUT_FORMAT};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{
    Access, Bind, Buffer, BufferDesc, GpuContext, MemoryLocation, PassTiming, Pipeline, Sampler, ShaderCompiler,
};
use crate::graph::executor::{PassContext, LIST_STATS_SLOT};
use crate::graph::plan::{CompiledGraph, PlannedPass, ResolvedKind, SettingValue, Version};
use crate::graph::{
    FormatRule, MinBytes, NodeSetup, PassKind, PassKindInfo, PassNode, SettingDecl, SettingDefault, Stages, Usage,
};
use crate::passes::shared::SceneInputs;
use ash::vk;

/// Most rows of the panel.
pub const MAX_ROWS: usize = 48;
/// Most characters per row.
pub const MAX_COLS: usize = 96;
/// Cull passes whose counters the panel can show (slots `stats0`..`stats3`).
pub const MAX_STATS: usize = 4;
/// Passes whose GPU time the per-frame buffer carries.
pub const MAX_TIMED: usize = 64;
/// Font pixels per glyph side.
pub const GLYPH: u32 = 8;
/// Font pixels per text line.
pub const LINE: u32 = 10;
/// Font pixels between the panel's edge and its text.
pub const PADDING: u32 = 4;
/// Screen pixels between the image's top-left corner and the panel.
pub const MARGIN: u32 = 8;
/// Length of the longest time bar, in characters.
pub const BAR_CHARS: u32 = 12;
/// Color of label glyphs (sRGB-encoded RGB).
pub const LABEL_COLOR: [u8; 3] = [215, 215, 215];
/// Color of number glyphs (sRGB-encoded RGB).
pub const NUMBER_COLOR: [u8; 3] = [255, 224, 112];
/// Longest pass name shown in the timings (longer ones are cut).
pub const MAX_NAME: usize = 20;
/// Longest cull-pass label in the drawn line.
pub const MAX_LABEL: usize = 12;

/// The stats slots, in the order the panel lists them.
pub const STATS_SLOTS: [&str; MAX_STATS] = ["stats0", "stats1", "stats2", "stats3"];
/// The slot of a compressed G-buffer's counters (a `lighting_compressed` pass's `stats`).
pub const GBUFFER_STATS_SLOT: &str = "gbuffer_stats";

const TOKEN_END: u32 = 0xFFFF_FFFF;
const TOKEN_FIELD: u32 = 0x1000_0000;
const FIELD_INSTANCES: u32 = 0;
const FIELD_TESTED: u32 = 1;
const FIELD_FRUSTUM: u32 = 2;
const FIELD_OCCLUSION: u32 = 3;
const FIELD_DRAWN: u32 = 4;
const FIELD_DRAWS: u32 = 5;
const FIELD_TRIANGLES: u32 = 6;
const FIELD_TOTAL_MS: u32 = 7;
const FIELD_TIMED_FRAME: u32 = 8;
const FIELD_MARKED: u32 = 9;
const FIELD_POOL_USED: u32 = 10;
const FIELD_POOL_BLOCKS: u32 = 11;
const FIELD_OVERFLOW: u32 = 12;
const FIELD_EDGE_PIXELS: u32 = 13;
const FIELD_PASS_DRAWN: u32 = 16;
const FIELD_PASS_MS: u32 = 32;
/// Characters of a time field.
const MS_WIDTH: usize = 8;

/// The newest completed frame's GPU times as the overlay reads them (`OverlayTimes` in
/// `shaders/overlay/overlay_common.glsl`); one host-visible buffer per frame in flight.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPassTimes {
    /// Entries of `ms` in use (the plan's passes, in execution order).
    pub count: u32,
    /// The frame they were measured in; `u32::MAX` when none has completed yet.
    pub frame: u32,
    /// The whole frame, milliseconds; negative when unknown.
    pub total_ms: f32,
    /// Unused.
    pub pad: f32,
    /// Per pass, milliseconds; negative when unknown.
    pub ms: [f32; MAX_TIMED],
}

/// Bytes of [`GpuPassTimes`].
pub const PASS_TIMES_BYTES: u64 = std::mem::size_of::<GpuPassTimes>() as u64;

impl GpuPassTimes {
    /// No times yet.
    pub fn none() -> Self {
        Self { count: 0, frame: u32::MAX, total_ms: -1.0, pad: 0.0, ms: [-1.0; MAX_TIMED] }
    }

    /// The times of `frame` (scopes named as the plan's passes, plus "frame") in `plan`'s order.
    pub fn from_timings(plan: &CompiledGraph, frame: u64, timings: &[PassTiming]) -> Self {
        let mut out = Self::none();
        out.frame = u32::try_from(frame).unwrap_or(u32::MAX - 1);
        out.count = plan.passes.len().min(MAX_TIMED) as u32;
        let find = |name: &str| timings.iter().find(|t| t.name == name).map(|t| t.ms as f32);
        for (slot, pass) in out.ms.iter_mut().zip(&plan.passes) {
            *slot = find(&pass.name).unwrap_or(-1.0);
        }
        out.total_ms = find("frame").unwrap_or(-1.0);
        out
    }
}

/// What the overlay shows (setting `view`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OverlayView {
    /// The panel only.
    Stats,
    /// A Hi-Z level in grey over the whole image, and the panel.
    Hiz,
    /// Occlusion-culled instances tinted red, and the panel.
    Culled,
}

/// The pass's settings, from the graph.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlaySettings {
    /// What to show.
    pub view: OverlayView,
    /// Mip of the Hi-Z pyramid view `hiz` shows (clamped to the last).
    pub hiz_level: u32,
    /// Screen pixels per font pixel; 0: `max(1, height / 720)`.
    pub scale: u32,
    /// Show GPU milliseconds per pass.
    pub timings: bool,
}

impl OverlaySettings {
    /// Reads a planned pass's settings (validation filled every default).
    pub fn from_plan(pass: &PlannedPass) -> Self {
        let int = |k: &str| match pass.settings.get(k) {
            Some(SettingValue::Int(i)) => (*i).clamp(0, u32::MAX as i64) as u32,
            Some(SettingValue::Float(f)) => f.clamp(0.0, u32::MAX as f64) as u32,
            _ => 0,
        };
        let view = match pass.settings.get("view") {
            Some(SettingValue::Choice(c)) if c == "hiz" => OverlayView::Hiz,
            Some(SettingValue::Choice(c)) if c == "culled" => OverlayView::Culled,
            _ => OverlayView::Stats,
        };
        Self {
            view,
            hiz_level: int("hiz_level"),
            scale: int("scale"),
            timings: !matches!(pass.settings.get("timings"), Some(SettingValue::Bool(false))),
        }
    }

    /// The text scale for an image `height` pixels high.
    pub fn scale_for(&self, height: u32) -> u32 {
        if self.scale > 0 {
            self.scale.min(16)
        } else {
            (height / 720).max(1)
        }
    }
}

/// The panel's rectangle for `cols` x `rows` characters at `scale`: (x0, y0, x1, y1), the end
/// exclusive, before clipping to the image.
pub fn panel_rect(cols: u32, rows: u32, scale: u32) -> (u32, u32, u32, u32) {
    let w = (cols * GLYPH + 2 * PADDING) * scale;
    let h = (rows * LINE + 2 * PADDING) * scale;
    (MARGIN, MARGIN, MARGIN + w, MARGIN + h)
}

/// Screen position of the top-left pixel of the glyph at (`row`, `col`) of the panel.
pub fn glyph_origin(row: u32, col: u32, scale: u32) -> (u32, u32) {
    (MARGIN + (PADDING + col * GLYPH) * scale, MARGIN + (PADDING + row * LINE) * scale)
}

/// font8x8's bitmap of `c` (ASCII; others show as '?'): 8 rows, bit `x` of a row is column `x`.
pub fn glyph(c: char) -> [u8; 8] {
    let code = if c.is_ascii() { c as usize } else { '?' as usize };
    font8x8::legacy::BASIC_LEGACY[code]
}

/// One piece of a template row.
#[derive(Clone, Debug, PartialEq)]
enum Piece {
    Text(String),
    /// A field and its widest rendering in characters.
    Field(u32, usize),
}

/// A template row: pieces, and the pass whose time bar it draws.
#[derive(Clone, Debug, Default, PartialEq)]
struct Row {
    pieces: Vec<Piece>,
    bar: Option<usize>,
}

impl Row {
    fn text(mut self, s: &str) -> Self {
        self.pieces.push(Piece::Text(s.to_string()));
        self
    }

    fn field(mut self, field: u32, widest: usize) -> Self {
        self.pieces.push(Piece::Field(field, widest));
        self
    }

    fn count(self, field: u32) -> Self {
        self.field(field, 10)
    }

    fn tokens(&self) -> Vec<u32> {
        let mut out = Vec::new();
        for p in &self.pieces {
            match p {
                Piece::Text(s) => out.extend(s.chars().map(|c| if c.is_ascii() { c as u32 } else { '?' as u32 })),
                Piece::Field(f, _) => out.push(TOKEN_FIELD | f),
            }
        }
        out.truncate(MAX_COLS);
        out
    }

    fn widest(&self) -> usize {
        self.pieces
            .iter()
            .map(|p| match p {
                Piece::Text(s) => s.chars().count(),
                Piece::Field(_, widest) => *widest,
            })
            .sum()
    }
}

/// The panel's layout as the GPU reads it (`OverlayTemplate`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuTemplate {
    rows: u32,
    bar_col: u32,
    bar_chars: u32,
    pad: u32,
    row_bar: [i32; MAX_ROWS],
    tokens: [[u32; MAX_COLS]; MAX_ROWS],
}

/// The panel's rows for a pass of `plan`.
struct Panel {
    rows: Vec<Row>,
    bar_col: usize,
    /// Widest possible row, in characters (the region view `stats` dispatches over).
    widest: usize,
}

impl Panel {
    fn new(plan: &CompiledGraph, pass: &PlannedPass, settings: &OverlaySettings, labels: &[String]) -> Self {
        let mut rows = Vec::new();
        let n = labels.len();
        if n == 0 {
            rows.push(Row::default().text("instances ").count(FIELD_INSTANCES).text("  (no cull counters)"));
        } else {
            rows.push(Row::default().text("instances ").count(FIELD_INSTANCES).text("  tested ").count(FIELD_TESTED));
            rows.push(Row::default().text("frustum culled ").count(FIELD_FRUSTUM));
            rows.push(Row::default().text("occlusion culled ").count(FIELD_OCCLUSION));
        }
        let drawn = Row::default().text("drawn ").count(FIELD_DRAWN);
        match n {
            0 | 1 => rows.push(drawn),
            2 => rows.push(
                drawn
                    .text(&format!(" ({} ", labels[0]))
                    .count(FIELD_PASS_DRAWN)
                    .text(&format!(", {} ", labels[1]))
                    .count(FIELD_PASS_DRAWN + 1)
                    .text(")"),
            ),
            _ => {
                rows.push(drawn);
                for (k, label) in labels.iter().enumerate() {
                    rows.push(Row::default().text(&format!("  {label} ")).count(FIELD_PASS_DRAWN + k as u32));
                }
            }
        }
        rows.push(Row::default().text("draws ").count(FIELD_DRAWS).text("  triangles ").field(FIELD_TRIANGLES, 20));
        if pass.bindings.iter().any(|b| b.slot == GBUFFER_STATS_SLOT) {
            rows.push(
                Row::default()
                    .text("pool blocks ")
                    .count(FIELD_POOL_USED)
                    .text(" / ")
                    .count(FIELD_POOL_BLOCKS)
                    .text("  overflow ")
                    .count(FIELD_OVERFLOW)
                    .text(" samples"),
            );
            rows.push(Row::default().text("pixels with 2+ surfaces ").count(FIELD_EDGE_PIXELS));
        }
        match settings.view {
            OverlayView::Stats => {}
            OverlayView::Hiz => {
                let (level, last, size) = hiz_info(plan, pass, settings.hiz_level);
                rows.push(
                    Row::default().text(&format!("hi-z mip {level}/{last} ({}x{}), white = near", size.0, size.1)),
                );
            }
            OverlayView::Culled => {
                rows.push(Row::default().text("red: ").count(FIELD_MARKED).text(" occlusion-culled instances"));
            }
        }
        let mut bar_col = 0;
        if settings.timings {
            let names: Vec<String> = plan.passes.iter().map(|p| p.name.chars().take(MAX_NAME).collect()).collect();
            let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0).max("total".len());
            rows.push(Row::default().text("gpu ms (frame ").field(FIELD_TIMED_FRAME, 10).text(")"));
            let room = MAX_ROWS.saturating_sub(rows.len() + 2);
            let shown = names.len().min(MAX_TIMED).min(room);
            for (k, name) in names.iter().take(shown).enumerate() {
                let row = Row::default().text(&format!("{name:width$} ")).field(FIELD_PASS_MS + k as u32, MS_WIDTH);
                rows.push(Row { bar: Some(k), ..row });
            }
            if shown < names.len() {
                rows.push(Row::default().text(&format!("({} more passes)", names.len() - shown)));
            }
            rows.push(Row::default().text(&format!("{:width$} ", "total")).field(FIELD_TOTAL_MS, MS_WIDTH));
            bar_col = width + 1 + MS_WIDTH + 1;
        }
        rows.truncate(MAX_ROWS);
        let bars = rows.iter().any(|r| r.bar.is_some());
        let widest = rows
            .iter()
            .map(|r| if r.bar.is_some() { r.widest().max(bar_col + BAR_CHARS as usize) } else { r.widest() })
            .max()
            .unwrap_or(0)
            .min(MAX_COLS);
        Self { rows, bar_col: if bars { bar_col } else { 0 }, widest }
    }

    fn gpu(&self) -> GpuTemplate {
        let mut t = GpuTemplate {
            rows: self.rows.len() as u32,
            bar_col: self.bar_col as u32,
            bar_chars: if self.bar_col > 0 { BAR_CHARS } else { 0 },
            pad: 0,
            row_bar: [-1; MAX_ROWS],
            tokens: [[TOKEN_END; MAX_COLS]; MAX_ROWS],
        };
        for (i, row) in self.rows.iter().enumerate() {
            t.row_bar[i] = row.bar.map_or(-1, |b| b as i32);
            for (slot, token) in t.tokens[i].iter_mut().zip(row.tokens()) {
                *slot = token;
            }
        }
        t
    }
}

/// Which level of the image's chain (level 0: the image, level k + 1: `max(1, size_k >> 1)`) the
/// pyramid's mip 0 is (a Hi-Z pyramid may start at half resolution), if any.
fn pyramid_shift(image: vk::Extent2D, pyramid: vk::Extent2D) -> Option<u32> {
    (0..16).find(|&k| (image.width >> k).max(1) == pyramid.width && (image.height >> k).max(1) == pyramid.height)
}

/// The mip view `hiz` shows (clamped), the last mip and the mip's size, from the plan.
fn hiz_info(plan: &CompiledGraph, pass: &PlannedPass, level: u32) -> (u32, u32, (u32, u32)) {
    let image = pass.bindings.iter().find(|b| b.slot == "hiz").map(|b| &plan.resources[b.resource].kind);
    match image {
        Some(ResolvedKind::Image { extent, mip_levels, .. }) => {
            let last = mip_levels.saturating_sub(1);
            let level = level.min(last);
            let size = ((extent.width >> level).max(1), (extent.height >> level).max(1));
            (level, last, size)
        }
        _ => (0, 0, (0, 0)),
    }
}

/// Labels of the cull passes whose counters are bound, in slot order: each writer's `phase`
/// when that tells them apart, else its name. Last frame's `list_stats` (the early draw list a
/// late phase wrote for this frame) is the early phase.
fn stats_labels(plan: &CompiledGraph, pass: &PlannedPass) -> Vec<String> {
    let position = plan.passes.iter().position(|p| p.name == pass.name).unwrap_or(plan.passes.len());
    // (writer, whether it is last frame's early draw list)
    let writers: Vec<(Option<&PlannedPass>, bool)> = STATS_SLOTS
        .iter()
        .filter_map(|slot| pass.bindings.iter().find(|b| b.slot == *slot))
        .map(|b| {
            let writes_it = |p: &&PlannedPass| {
                p.bindings.iter().any(|w| w.resource == b.resource && w.version == Version::Current && w.usage.writes())
            };
            if b.version == Version::Previous {
                let writer = plan.passes.iter().find(writes_it);
                let list = writer
                    .is_some_and(|w| w.bindings.iter().any(|l| l.slot == LIST_STATS_SLOT && l.resource == b.resource));
                (writer, list)
            } else {
                (plan.passes[..position].iter().rev().find(writes_it), false)
            }
        })
        .collect();
    let phases: Vec<Option<String>> = writers
        .iter()
        .map(|(w, list)| match (list, w.and_then(|w| w.settings.get("phase"))) {
            (true, _) => Some("early".to_string()),
            (false, Some(SettingValue::Choice(c))) if c != "all" => Some(c.clone()),
            _ => None,
        })
        .collect();
    let distinct = phases.iter().all(|p| p.is_some())
        && phases.iter().enumerate().all(|(i, p)| phases[..i].iter().all(|q| q != p));
    writers
        .iter()
        .zip(&phases)
        .enumerate()
        .map(|(k, ((w, _), phase))| {
            let label = match (distinct, phase, w) {
                (true, Some(phase), _) => phase.clone(),
                (_, _, Some(w)) => w.name.clone(),
                _ => format!("stats{k}"),
            };
            label.chars().take(MAX_LABEL).collect()
        })
        .collect()
}

/// Push constants of `overlay_text.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TextPush {
    stats_count: u32,
    instances: u32,
    all_draws: u32,
    all_triangles_lo: u32,
    all_triangles_hi: u32,
}

/// Push constants of `overlay_draw.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DrawPush {
    size: [u32; 2],
    scale: u32,
    hiz_mip: u32,
    hiz_shift: u32,
}

/// Bytes of the character grid (`OverlayText`).
const TEXT_BYTES: u64 = (16 + MAX_ROWS * 4 + MAX_ROWS * MAX_COLS * 4) as u64;

/// The overlay pass.
pub struct OverlayPass {
    name: String,
    settings: OverlaySettings,
    /// Widest possible panel, in characters, and its rows.
    widest: u32,
    rows: u32,
    text_step: Pipeline,
    draw: Pipeline,
    /// View `culled`: marking and the row prefix sum.
    mark: Option<Pipeline>,
    scan: Option<Pipeline>,
    sampler: Sampler,
    template: Buffer,
    font: Buffer,
    text: Buffer,
    /// Bound to stats slots the graph left empty (never read).
    no_stats: Buffer,
    /// View `culled`: header + per-row coverage counts, for the size it was made for.
    coverage: Option<(vk::Extent2D, Buffer)>,
}

impl OverlayPass {
    /// The pass of a graph node: compiles the view's shaders and uploads the font and the panel's
    /// template (labels from `plan`).
    pub fn new(
        ctx: &GpuContext,
        shaders: &ShaderCompiler,
        pass: &PlannedPass,
        plan: &CompiledGraph,
    ) -> crate::Result<Self> {
        let settings = OverlaySettings::from_plan(pass);
        let bound = |slot: &str| pass.bindings.iter().any(|b| b.slot == slot);
        let invalid = |m: &str| crate::Error::Invalid(format!("pass '{}': {m}", pass.name));
        match settings.view {
            OverlayView::Hiz if !bound("hiz") => {
                return Err(invalid("view \"hiz\" needs a pyramid bound to slot 'hiz'"))
            }
            OverlayView::Culled if !bound("visibility") => {
                return Err(invalid(
                    "view \"culled\" needs the late cull pass's visibility bits bound to slot 'visibility'",
                ))
            }
            _ => {}
        }
        let labels = stats_labels(plan, pass);
        let panel = Panel::new(plan, pass, &settings, &labels);
        let name = |step: &str| format!("{} ({step})", pass.name);
        let culled = settings.view == OverlayView::Culled;
        let mut text_defines = Vec::new();
        if culled {
            text_defines.push(("HAS_MARKS", "1"));
        }
        if bound(GBUFFER_STATS_SLOT) {
            text_defines.push(("HAS_GBUFFER", "1"));
        }
        let text_step =
            Pipeline::compute(ctx, &name("text"), &shaders.compile("overlay/overlay_text.comp", &text_defines)?)?;
        let view_define: &[(&str, &str)] = match settings.view {
            OverlayView::Stats => &[],
            OverlayView::Hiz => &[("VIEW_HIZ", "1")],
            OverlayView::Culled => &[("VIEW_CULLED", "1")],
        };
        let draw = Pipeline::compute(ctx, &name("draw"), &shaders.compile("overlay/overlay_draw.comp", view_define)?)?;
        let (mark, scan) = if culled {
            (
                Some(Pipeline::compute(ctx, &name("mark"), &shaders.compile("overlay/overlay_mark.comp", &[])?)?),
                Some(Pipeline::compute(ctx, &name("scan"), &shaders.compile("overlay/overlay_scan.comp", &[])?)?),
            )
        } else {
            (None, None)
        };
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let font: Vec<u8> = font8x8::legacy::BASIC_LEGACY.iter().flatten().copied().collect();
        let template = panel.gpu();
        let text = Buffer::new(
            ctx,
            &BufferDesc { name: &name("text"), size: TEXT_BYTES, usage: storage, location: MemoryLocation::GpuOnly },
        )?;
        Ok(Self {
            name: pass.name.clone(),
            widest: panel.widest as u32,
            rows: panel.rows.len() as u32,
            settings,
            text_step,
            draw,
            mark,
            scan,
            sampler: Sampler::nearest_clamp(ctx)?,
            template: Buffer::with_data(ctx, &name("template"), storage, bytemuck::bytes_of(&template))?,
            font: Buffer::with_data(ctx, &name("font8x8"), storage, &font)?,
            text,
            no_stats: Buffer::with_data(ctx, &name("no stats"), storage, &[0u8; 64])?,
            coverage: None,
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &OverlaySettings {
        &self.settings
    }

    /// The coverage buffer for an image of `extent` (made on first use and when the size changes).
    fn coverage(&mut self, ctx: &GpuContext, extent: vk::Extent2D) -> crate::Result<&Buffer> {
        if self.coverage.as_ref().is_none_or(|(e, _)| *e != extent) {
            let size = 16 + (extent.width as u64 + 1) * extent.height as u64 * 4;
            let buffer = Buffer::new(
                ctx,
                &BufferDesc {
                    name: &format!("{} (coverage)", self.name),
                    size,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                    location: MemoryLocation::GpuOnly,
                },
            )?;
            self.coverage = Some((extent, buffer));
        }
        Ok(&self.coverage.as_ref().expect("made above").1)
    }
}

/// Storage reads and writes of compute shaders and transfer writes: every use the pass makes of
/// its own buffers.
const OWN: Access = Access {
    stage: vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags2::ALL_TRANSFER.as_raw(),
    ),
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
            | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw()
            | vk::AccessFlags2::TRANSFER_WRITE.as_raw(),
    ),
    layout: vk::ImageLayout::UNDEFINED,
};

impl PassNode for OverlayPass {
    fn record(&mut self, rec: &PassContext<'_>) -> crate::Result<()> {
        let (ctx, cmd, frame) = (rec.ctx, rec.cmd, SceneInputs::of(rec)?);
        let device = ctx.device().clone();
        let output = rec.slots.required_image("output")?;
        let extent = output.extent();
        let pass_name = self.name.clone();
        let invalid = |m: String| crate::Error::Invalid(format!("pass '{pass_name}': {m}"));
        let stats: Vec<&Buffer> = STATS_SLOTS.iter().filter_map(|s| rec.slots.buffer(s)).collect();
        if let Some(small) = stats.iter().find(|b| b.size() < 64) {
            return Err(invalid(format!(
                "counters '{}' hold {} bytes; a cull pass writes 64",
                small.name(),
                small.size()
            )));
        }
        let scene = &frame.scene;
        // The previous frame's uses of the pass's own buffers finish before this frame's.
        cmd_barriers(&device, cmd, &[memory_barrier(OWN, OWN)], &[]);

        if self.settings.view == OverlayView::Culled {
            let visibility =
                rec.slots.buffer("visibility").ok_or_else(|| invalid("nothing bound to 'visibility'".into()))?;
            let words = scene.instance_count.div_ceil(32) as u64 * 4;
            if visibility.size() < words {
                return Err(invalid(format!(
                    "visibility '{}' holds {} bytes; {} instances need {words}",
                    visibility.name(),
                    visibility.size(),
                    scene.instance_count
                )));
            }
            let coverage = self.coverage(ctx, extent)?.handle();
            let (records, constants, vis) =
                (scene.cull_records.handle(), frame.constants().handle(), visibility.handle());
            let (Some(mark), Some(scan)) = (&self.mark, &self.scan) else {
                return Err(invalid("view \"culled\" without its pipelines".into()));
            };
            // SAFETY: cmd recording; the buffer has TRANSFER_DST usage.
            unsafe { device.cmd_fill_buffer(cmd, coverage, 0, vk::WHOLE_SIZE, 0) };
            cmd_barriers(&device, cmd, &[memory_barrier(Access::TRANSFER_WRITE, Access::COMPUTE_WRITE)], &[]);
            mark.bind(cmd);
            mark.push_bindings(
                cmd,
                &[
                    Bind::Buffer(0, records),
                    Bind::Buffer(1, constants),
                    Bind::Buffer(2, vis),
                    Bind::Buffer(3, coverage),
                ],
            );
            mark.push_constants(cmd, &[scene.instance_count, extent.width, extent.height]);
            // SAFETY: cmd recording with the pipeline bound and every binding pushed.
            unsafe { device.cmd_dispatch(cmd, scene.instance_count.div_ceil(256).max(1), 1, 1) };
            cmd_barriers(&device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);
            scan.bind(cmd);
            scan.push_bindings(cmd, &[Bind::Buffer(0, coverage)]);
            scan.push_constants(cmd, &[extent.width, extent.height]);
            // SAFETY: as above.
            unsafe { device.cmd_dispatch(cmd, extent.height.div_ceil(64), 1, 1) };
            cmd_barriers(&device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);
        }

        let times = frame.pass_times();
        let mut binds: Vec<Bind> = (0..MAX_STATS)
            .map(|k| Bind::Buffer(k as u32, stats.get(k).copied().unwrap_or(&self.no_stats).handle()))
            .collect();
        binds.extend([
            Bind::Buffer(4, self.template.handle()),
            Bind::Buffer(5, times.handle()),
            Bind::Buffer(6, self.text.handle()),
        ]);
        if let Some((_, coverage)) = &self.coverage {
            binds.push(Bind::Buffer(7, coverage.handle()));
        }
        if let Some(gbuffer) = rec.slots.buffer(GBUFFER_STATS_SLOT) {
            binds.push(Bind::Buffer(8, gbuffer.handle()));
        }
        let triangles = scene.triangles;
        self.text_step.bind(cmd);
        self.text_step.push_bindings(cmd, &binds);
        self.text_step.push_constants(
            cmd,
            &TextPush {
                stats_count: stats.len() as u32,
                instances: scene.instance_count,
                all_draws: scene.regions.groups(),
                all_triangles_lo: triangles as u32,
                all_triangles_hi: (triangles >> 32) as u32,
            },
        );
        // SAFETY: as above.
        unsafe { device.cmd_dispatch(cmd, 1, 1, 1) };
        cmd_barriers(&device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);

        let scale = self.settings.scale_for(extent.height);
        let mut binds = vec![
            Bind::StorageImage(0, output.view()),
            Bind::Buffer(1, self.text.handle()),
            Bind::Buffer(2, self.font.handle()),
        ];
        let (mut hiz_mip, mut hiz_shift) = (0, u32::MAX);
        if self.settings.view == OverlayView::Hiz {
            let hiz = rec.slots.required_image("hiz")?;
            hiz_mip = self.settings.hiz_level.min(hiz.mip_levels() - 1);
            hiz_shift = pyramid_shift(extent, hiz.extent()).map_or(u32::MAX, |first| first + hiz_mip);
            let layout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
            binds.push(Bind::Sampled(3, hiz.view(), self.sampler.handle(), layout));
        }
        if let (OverlayView::Culled, Some((_, coverage))) = (self.settings.view, &self.coverage) {
            binds.push(Bind::Buffer(4, coverage.handle()));
        }
        let region = match self.settings.view {
            OverlayView::Stats => {
                let (_, _, x1, y1) = panel_rect(self.widest, self.rows, scale);
                (x1.min(extent.width), y1.min(extent.height))
            }
            _ => (extent.width, extent.height),
        };
        self.draw.bind(cmd);
        self.draw.push_bindings(cmd, &binds);
        self.draw.push_constants(cmd, &DrawPush { size: [extent.width, extent.height], scale, hiz_mip, hiz_shift });
        // SAFETY: as above.
        unsafe { device.cmd_dispatch(cmd, region.0.div_ceil(8).max(1), region.1.div_ceil(8).max(1), 1) };
        Ok(())
    }
}

/// The `overlay` pass kind.
pub struct OverlayKind;

impl PassKind for OverlayKind {
    fn info(&self) -> PassKindInfo {
        PassKindInfo {
            name: "overlay",
            doc: "draws this frame's culling counters (formatted on the GPU), with `gbuffer_stats` the compressed G-buffer's, per-pass GPU milliseconds and optional debug views (a Hi-Z mip, occlusion-culled instances) over the lit image",
            reads: vec![
                sized(slot("stats0", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a cull pass (its `stats` buffer, 64 bytes)"), COUNTERS_BYTES),
                sized(slot("stats1", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a second cull pass"), COUNTERS_BYTES),
                sized(slot("stats2", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a third cull pass"), COUNTERS_BYTES),
                sized(slot("stats3", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a fourth cull pass"), COUNTERS_BYTES),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid (view \"hiz\")"),
                sized(slot("visibility", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "this frame's visibility bits from the late cull pass (view \"culled\")"), MinBytes::InstanceBits),
                sized(slot("gbuffer_stats", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "a compressed G-buffer's counters (a lighting_compressed pass's `stats`): pool blocks in use, overflowed samples, pixels with several surfaces"), COUNTERS_BYTES),
            ],
            writes: vec![slot(
                "output",
                Usage::StorageImageReadWrite(Stages::Compute),
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "the lit image, drawn on in place",
            )],
            settings: vec![
                SettingDecl {
                    name: "view",
                    default: SettingDefault::Choice(&["stats", "hiz", "culled"]),
                    doc: "the counter panel only; plus a Hi-Z mip in grey over the whole image; plus occlusion-culled instances tinted red",
                },
                SettingDecl { name: "hiz_level", default: SettingDefault::Int(0), doc: "mip of the Hi-Z pyramid shown by view \"hiz\" (clamped to the last)" },
                SettingDecl { name: "scale", default: SettingDefault::Int(0), doc: "text size in pixels per font pixel (0: max(1, height / 720))" },
                SettingDecl { name: "timings", default: SettingDefault::Bool(true), doc: "show GPU milliseconds per pass (of the newest completed frame)" },
            ],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(OverlayPass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::plan::{Binding, MemoryPlan, PlannedResource, ResourceClass};
    use crate::graph::usage::{Stages, Usage};

    fn plan(phases: [&str; 2]) -> CompiledGraph {
        let resource = |name: &str| PlannedResource {
            name: name.into(),
            kind: ResolvedKind::Buffer { size: 64, usage: vk::BufferUsageFlags::STORAGE_BUFFER },
            class: ResourceClass::Transient,
            lifetime: None,
        };
        let bind =
            |slot: &str, resource, usage| Binding { slot: slot.into(), resource, version: Version::Current, usage };
        let cull = |name: &str, phase: &str, resource| PlannedPass {
            name: name.into(),
            kind: "instance_cull".into(),
            bindings: vec![bind("stats", resource, Usage::StorageBufferWrite(Stages::Compute))],
            settings: [("phase".to_string(), SettingValue::Choice(phase.into()))].into(),
            shader: None,
            dispatch: None,
            barriers: vec![],
        };
        let read = Usage::StorageBufferRead(Stages::Compute);
        let overlay = PlannedPass {
            name: "overlay".into(),
            kind: "overlay".into(),
            bindings: vec![bind("stats1", 1, read), bind("stats0", 0, read)],
            settings: Default::default(),
            shader: None,
            dispatch: None,
            barriers: vec![],
        };
        CompiledGraph {
            name: "test".into(),
            passes: vec![cull("cull_a", phases[0], 0), cull("cull_b", phases[1], 1), overlay],
            pruned: vec![],
            resources: vec![resource("a"), resource("b")],
            outputs: vec![],
            memory: MemoryPlan::default(),
            kinds: Default::default(),
        }
    }

    #[test]
    fn cull_passes_are_labelled_by_phase_when_that_tells_them_apart() {
        let p = plan(["early", "late"]);
        assert_eq!(stats_labels(&p, &p.passes[2]), ["early", "late"]);
        let p = plan(["all", "all"]);
        assert_eq!(stats_labels(&p, &p.passes[2]), ["cull_a", "cull_b"]);
        let p = plan(["late", "late"]);
        assert_eq!(stats_labels(&p, &p.passes[2]), ["cull_a", "cull_b"]);
    }

    #[test]
    fn the_panel_has_a_row_per_figure_and_pass_and_fits_its_limits() {
        let p = plan(["early", "late"]);
        let settings = OverlaySettings::from_plan(&p.passes[2]);
        assert_eq!((settings.view, settings.scale_for(1080), settings.scale_for(2160)), (OverlayView::Stats, 1, 3));
        let panel = Panel::new(&p, &p.passes[2], &settings, &stats_labels(&p, &p.passes[2]));
        // 5 figures, the timings header, 3 passes, the total.
        assert_eq!(panel.rows.len(), 10);
        assert_eq!(panel.bar_col, "overlay".len() + 1 + MS_WIDTH + 1);
        // "drawn " + 10 + " (early " + 10 + ", late " + 10 + ")".
        assert_eq!(panel.widest, 6 + 10 + 8 + 10 + 7 + 10 + 1);
        let gpu = panel.gpu();
        assert_eq!(gpu.row_bar[..10], [-1, -1, -1, -1, -1, -1, 0, 1, 2, -1]);
        assert_eq!(gpu.tokens[1][..15].iter().map(|&t| t as u8 as char).collect::<String>(), "frustum culled ");
        assert_eq!(gpu.tokens[1][15], TOKEN_FIELD | FIELD_FRUSTUM);
        assert_eq!(gpu.tokens[1][16], TOKEN_END);
        assert_eq!(std::mem::size_of::<GpuTemplate>(), 16 + MAX_ROWS * 4 + MAX_ROWS * MAX_COLS * 4);
    }

    #[test]
    fn times_follow_the_plan_order_and_unknown_ones_are_negative() {
        let p = plan(["early", "late"]);
        let timing = |name: &str, ms| PassTiming { name: name.into(), start_ms: 0.0, ms };
        let t =
            GpuPassTimes::from_timings(&p, 7, &[timing("frame", 3.0), timing("cull_b", 2.0), timing("overlay", 0.5)]);
        assert_eq!((t.count, t.frame, t.total_ms), (3, 7, 3.0));
        assert_eq!(t.ms[..4], [-1.0, 2.0, 0.5, -1.0]);
        assert_eq!(PASS_TIMES_BYTES, 16 + 4 * MAX_TIMED as u64);
        assert_eq!(GpuPassTimes::none().frame, u32::MAX);
    }

    #[test]
    fn pyramids_starting_at_half_size_map_pixels_by_shifts() {
        let e = |width, height| vk::Extent2D { width, height };
        assert_eq!(pyramid_shift(e(320, 240), e(320, 240)), Some(0));
        assert_eq!(pyramid_shift(e(321, 241), e(160, 120)), Some(1));
        assert_eq!(pyramid_shift(e(1, 1), e(1, 1)), Some(0));
        assert_eq!(pyramid_shift(e(320, 240), e(100, 100)), None);
        assert_eq!(glyph_origin(0, 0, 2), (MARGIN + PADDING * 2, MARGIN + PADDING * 2));
        assert_eq!(panel_rect(1, 1, 1), (MARGIN, MARGIN, MARGIN + GLYPH + 2 * PADDING, MARGIN + LINE + 2 * PADDING));
        assert_eq!(glyph('A'), font8x8::legacy::BASIC_LEGACY[65]);
    }
}
