//! The overlay's text panel: the rows of text and numeric fields the CPU lays out once per
//! plan (labels from the cull passes' `phase` or names, and every pass's name for the timings),
//! and the template the GPU formats every frame (`OverlayTemplate` in
//! `shaders/overlay/overlay_common.glsl`).

use super::times::MAX_TIMED;
use super::{OverlaySettings, OverlayView, GBUFFER_STATS_SLOT, STATS_SLOTS};
use crate::graph::plan::{CompiledGraph, PlannedPass, ResolvedKind, SettingValue, Version};
use crate::passes::instance_cull::LIST_STATS_SLOT;

/// Most rows of the panel.
pub(crate) const MAX_ROWS: usize = 48;
/// Most characters per row.
pub const MAX_COLS: usize = 96;
/// Font pixels per glyph side.
pub(crate) const GLYPH: u32 = 8;
/// Font pixels per text line.
pub(crate) const LINE: u32 = 10;
/// Font pixels between the panel's edge and its text.
pub(crate) const PADDING: u32 = 4;
/// Screen pixels between the image's top-left corner and the panel.
pub(crate) const MARGIN: u32 = 8;
/// Length of the longest time bar, in characters.
pub const BAR_CHARS: u32 = 12;
/// Color of label glyphs (sRGB-encoded RGB).
pub const LABEL_COLOR: [u8; 3] = [215, 215, 215];
/// Color of number glyphs (sRGB-encoded RGB).
pub const NUMBER_COLOR: [u8; 3] = [255, 224, 112];
/// Longest pass name shown in the timings (longer ones are cut).
pub(crate) const MAX_NAME: usize = 20;
/// Longest cull-pass label in the drawn line.
pub(crate) const MAX_LABEL: usize = 12;

pub(super) const TOKEN_END: u32 = 0xFFFF_FFFF;
pub(super) const TOKEN_FIELD: u32 = 0x1000_0000;
pub(super) const FIELD_INSTANCES: u32 = 0;
pub(super) const FIELD_TESTED: u32 = 1;
pub(super) const FIELD_FRUSTUM: u32 = 2;
pub(super) const FIELD_OCCLUSION: u32 = 3;
pub(super) const FIELD_DRAWN: u32 = 4;
pub(super) const FIELD_DRAWS: u32 = 5;
pub(super) const FIELD_TRIANGLES: u32 = 6;
pub(super) const FIELD_TOTAL_MS: u32 = 7;
pub(super) const FIELD_TIMED_FRAME: u32 = 8;
pub(super) const FIELD_MARKED: u32 = 9;
pub(super) const FIELD_POOL_USED: u32 = 10;
pub(super) const FIELD_POOL_BLOCKS: u32 = 11;
pub(super) const FIELD_OVERFLOW: u32 = 12;
pub(super) const FIELD_EDGE_PIXELS: u32 = 13;
pub(super) const FIELD_PASS_DRAWN: u32 = 16;
pub(super) const FIELD_PASS_MS: u32 = 32;
/// Characters of a time field.
pub(super) const MS_WIDTH: usize = 8;

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
pub(super) enum Piece {
    Text(String),
    /// A field and its widest rendering in characters.
    Field(u32, usize),
}

/// A template row: pieces, and the pass whose time bar it draws.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Row {
    pub(super) pieces: Vec<Piece>,
    pub(super) bar: Option<usize>,
}

impl Row {
    pub(super) fn text(mut self, s: &str) -> Self {
        self.pieces.push(Piece::Text(s.to_string()));
        self
    }

    pub(super) fn field(mut self, field: u32, widest: usize) -> Self {
        self.pieces.push(Piece::Field(field, widest));
        self
    }

    pub(super) fn count(self, field: u32) -> Self {
        self.field(field, 10)
    }

    pub(super) fn tokens(&self) -> Vec<u32> {
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

    pub(super) fn widest(&self) -> usize {
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
pub(super) struct GpuTemplate {
    pub(super) rows: u32,
    pub(super) bar_col: u32,
    pub(super) bar_chars: u32,
    pub(super) pad: u32,
    pub(super) row_bar: [i32; MAX_ROWS],
    pub(super) tokens: [[u32; MAX_COLS]; MAX_ROWS],
}

/// The panel's rows for a pass of `plan`.
pub(super) struct Panel {
    pub(super) rows: Vec<Row>,
    pub(super) bar_col: usize,
    /// Widest possible row, in characters (the region view `stats` dispatches over).
    pub(super) widest: usize,
}

impl Panel {
    pub(super) fn new(plan: &CompiledGraph, pass: &PlannedPass, settings: &OverlaySettings, labels: &[String]) -> Self {
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

    pub(super) fn gpu(&self) -> GpuTemplate {
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

/// Labels of the cull passes whose counters are bound, in slot order: each writer's `phase`
/// when that tells them apart, else its name. Last frame's `list_stats` (the early draw list a
/// late phase wrote for this frame) is the early phase.
pub(super) fn stats_labels(plan: &CompiledGraph, pass: &PlannedPass) -> Vec<String> {
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
