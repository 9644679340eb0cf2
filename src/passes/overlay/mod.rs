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
//! (uploaded once). The totals are made as [`crate::stats::FrameStats::add_counters`] makes the
//! CPU's.
//!
//! **Timings.** GPU times are known only once a frame has completed. The kind asks the executor
//! for the newest completed frame's ([`crate::graph::PassKind::reads_timings`]) and the pass
//! writes them, in plan order, into a small host-visible buffer of its own per frame in flight
//! (`GpuPassTimes`); the panel says which frame they are from and draws a bar per pass
//! proportional to its time.
//!
//! **Cost.** View `stats` dispatches over the panel's largest possible extent only (and leaves
//! every pixel outside this frame's panel untouched). The debug views are full screen: `hiz`
//! shows one Hi-Z level in grey (nearest: the texel that covers each pixel in the occlusion
//! test); `culled` projects every instance that is inside the frustum but not visible after the
//! late cull pass (= occlusion-culled this frame) with the cull's own math and tints its screen
//! rectangle red: per-row difference counts with integer atomics, a prefix sum per row, then a
//! tint whose depth grows with the number of overlapping rectangles and a bright edge where the
//! count changes. Deterministic: the same frame gives the same pixels.

mod panel;
mod times;

pub use panel::{glyph, glyph_origin, panel_rect, BAR_CHARS, LABEL_COLOR, MAX_COLS, NUMBER_COLOR};
pub(crate) use times::{GpuPassTimes, PASS_TIMES_BYTES};

use super::slots::{slot, COUNTERS_BYTES, HIZ_FORMAT, INSTANCE_BITS, LIT_OUTPUT_FORMAT};
use crate::gpu::barrier::{cmd_barriers, memory_barrier};
use crate::gpu::{Access, Bind, Buffer, BufferDesc, GpuContext, MemoryLocation, Pipeline, Sampler, ShaderCompiler};
use crate::graph::executor::PassContext;
use crate::graph::plan::{CompiledGraph, PlannedPass};
use crate::graph::{
    FormatRule, KindCheck, NodeSetup, PassKind, PassKindInfo, PassNode, Pos, SettingDecl, Stages, Usage,
    FRAMES_IN_FLIGHT,
};
use crate::passes::shared::SceneInputs;
use ash::vk;
use panel::*;

/// Cull passes whose counters the panel can show (slots `stats0`..`stats3`).
pub(crate) const MAX_STATS: usize = 4;
/// The stats slots, in the order the panel lists them.
pub(crate) const STATS_SLOTS: [&str; MAX_STATS] = ["stats0", "stats1", "stats2", "stats3"];
/// The slot of a compressed G-buffer's counters (a `lighting_compressed` pass's `stats`).
pub(crate) const GBUFFER_STATS_SLOT: &str = "gbuffer_stats";

crate::choice! {
    /// What the overlay shows (setting `view`).
    pub enum OverlayView {
        /// The panel only.
        Stats = "stats",
        /// A Hi-Z level in grey over the whole image, and the panel.
        Hiz = "hiz",
        /// Occlusion-culled instances tinted red, and the panel.
        Culled = "culled",
    }
}

/// The pass's settings, from the graph.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct OverlaySettings {
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
    pub fn from_plan(pass: &PlannedPass) -> crate::Result<Self> {
        // The declared ranges keep these within a u32.
        let int = |k: &str| pass.int(k).map(|i| i.clamp(0, u32::MAX as i64) as u32);
        let view = pass.choice("view")?;
        Ok(Self { view, hiz_level: int("hiz_level")?, scale: int("scale")?, timings: pass.flag("timings")? })
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

/// Which level of the image's chain (level 0: the image, level k + 1: `max(1, size_k >> 1)`) the
/// pyramid's mip 0 is (a Hi-Z pyramid may start at half resolution), if any.
fn pyramid_shift(image: vk::Extent2D, pyramid: vk::Extent2D) -> Option<u32> {
    (0..16).find(|&k| (image.width >> k).max(1) == pyramid.width && (image.height >> k).max(1) == pyramid.height)
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
pub(crate) struct OverlayPass {
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
    /// The newest completed frame's GPU times (`GpuPassTimes`), one host-visible buffer per
    /// frame in flight, and the plan's pass names they are listed by.
    times: Vec<Buffer>,
    pass_names: Vec<String>,
}

/// What `view` needs bound that `bound` says is not.
fn view_error(view: OverlayView, bound: impl Fn(&str) -> bool) -> Option<&'static str> {
    match view {
        OverlayView::Hiz if !bound("hiz") => Some("view \"hiz\" needs a pyramid bound to slot 'hiz'"),
        OverlayView::Culled if !bound("visibility") => {
            Some("view \"culled\" needs the late cull pass's visibility bits bound to slot 'visibility'")
        }
        _ => None,
    }
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
        let settings = OverlaySettings::from_plan(pass)?;
        let bound = |slot: &str| pass.bindings.iter().any(|b| b.slot == slot);
        if let Some(m) = view_error(settings.view, bound) {
            return Err(crate::Error::Invalid(format!("pass '{}': {m}", pass.name)));
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
            times: (0..FRAMES_IN_FLIGHT)
                .map(|i| {
                    let desc = BufferDesc {
                        name: &name(&format!("times {i}")),
                        size: PASS_TIMES_BYTES,
                        usage: storage,
                        location: MemoryLocation::CpuToGpu,
                    };
                    Buffer::new(ctx, &desc)
                })
                .collect::<Result<_, _>>()?,
            pass_names: plan.passes.iter().map(|p| p.name.clone()).collect(),
        })
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
            unsafe {
                crate::gpu::line_dispatch::cmd_dispatch_line(
                    &device,
                    cmd,
                    &ctx.caps().limits,
                    scene.instance_count.div_ceil(256),
                )
            };
            cmd_barriers(&device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);
            scan.bind(cmd);
            scan.push_bindings(cmd, &[Bind::Buffer(0, coverage)]);
            scan.push_constants(cmd, &[extent.width, extent.height]);
            // SAFETY: as above.
            unsafe { device.cmd_dispatch(cmd, extent.height.div_ceil(64), 1, 1) };
            cmd_barriers(&device, cmd, &[memory_barrier(Access::COMPUTE_WRITE, Access::COMPUTE_WRITE)], &[]);
        }

        let times = &mut self.times[(rec.frame.frame % FRAMES_IN_FLIGHT as u64) as usize];
        let newest = match rec.timings {
            Some(t) => GpuPassTimes::from_timings(&self.pass_names, t.frame, &t.passes),
            None => GpuPassTimes::none(),
        };
        times.write_bytes(0, bytemuck::bytes_of(&newest))?;
        let times = &self.times[(rec.frame.frame % FRAMES_IN_FLIGHT as u64) as usize];
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
        let push = DrawPush { size: [extent.width, extent.height], scale, hiz_mip, hiz_shift };
        let region = vk::Extent2D { width: region.0, height: region.1 };
        self.draw.dispatch_over(cmd, &binds, bytemuck::bytes_of(&push), region);
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
                slot("stats0", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a cull pass (its `stats` buffer, 64 bytes)").exactly(COUNTERS_BYTES),
                slot("stats1", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a second cull pass").exactly(COUNTERS_BYTES),
                slot("stats2", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a third cull pass").exactly(COUNTERS_BYTES),
                slot("stats3", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "counters of a fourth cull pass").exactly(COUNTERS_BYTES),
                slot("hiz", Usage::Sampled(Stages::Compute), false, FormatRule::Exact(HIZ_FORMAT), "Hi-Z pyramid (view \"hiz\")"),
                slot("visibility", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "this frame's visibility bits from the late cull pass (view \"culled\")").at_least(INSTANCE_BITS),
                slot("gbuffer_stats", Usage::StorageBufferRead(Stages::Compute), false, FormatRule::Any, "a compressed G-buffer's counters (a lighting_compressed pass's `stats`): pool blocks in use, overflowed samples, pixels with several surfaces").exactly(COUNTERS_BYTES),
            ],
            writes: vec![slot(
                "output",
                Usage::StorageImageReadWrite(Stages::Compute),
                true,
                FormatRule::Exact(LIT_OUTPUT_FORMAT),
                "the lit image, drawn on in place",
            )],
            settings: vec![
                SettingDecl::choice::<OverlayView>("view", "the counter panel only; plus a Hi-Z mip in grey over the whole image; plus occlusion-culled instances tinted red"),
                SettingDecl::int("hiz_level", 0, (0, 15), "mip of the Hi-Z pyramid shown by view \"hiz\" (clamped to the last)"),
                SettingDecl::int("scale", 0, (0, 64), "text size in pixels per font pixel (0: max(1, height / 720))"),
                SettingDecl::flag("timings", true, "show GPU milliseconds per pass (of the newest completed frame)"),
            ],
            slots_from_shader: false,
        }
    }

    fn create_node(&self, s: &NodeSetup<'_>) -> crate::Result<Box<dyn PassNode>> {
        Ok(Box::new(OverlayPass::new(s.ctx, s.shaders, s.pass, s.plan)?))
    }

    fn reads_timings(&self) -> bool {
        true
    }

    fn check_compiled(&self, check: &KindCheck<'_>) -> Vec<(Pos, String)> {
        let Some(settings) = check.planned.and_then(|p| OverlaySettings::from_plan(p).ok()) else { return Vec::new() };
        view_error(settings.view, |slot| check.binding(slot).is_some())
            .map(|m| {
                let at = check.pass.settings.iter().find(|s| s.name == "view").map_or(check.pass.pos, |s| s.pos);
                (at, format!("pass '{}': {m}", check.pass.name))
            })
            .into_iter()
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::PassTiming;
    use crate::graph::plan::{Binding, MemoryPlan, PlannedResource, ResourceClass};
    use crate::graph::plan::{ResolvedKind, SettingValue, Version};
    use crate::graph::usage::{Stages, Usage};

    fn plan(phases: [&str; 2]) -> CompiledGraph {
        let resource = |name: &str| PlannedResource {
            name: name.into(),
            kind: ResolvedKind::Buffer { size: 64, usage: vk::BufferUsageFlags::STORAGE_BUFFER },
            class: ResourceClass::Transient,
            lifetime: None,
            pos: Default::default(),
            owner: None,
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
            pos: Default::default(),
        };
        let read = Usage::StorageBufferRead(Stages::Compute);
        let overlay = PlannedPass {
            name: "overlay".into(),
            kind: "overlay".into(),
            bindings: vec![bind("stats1", 1, read), bind("stats0", 0, read)],
            settings: OverlayKind.info().default_settings(),
            shader: None,
            dispatch: None,
            barriers: vec![],
            pos: Default::default(),
        };
        CompiledGraph {
            name: "test".into(),
            file: "test.ron".into(),
            files: vec!["test.ron".into()],
            passes: vec![cull("cull_a", phases[0], 0), cull("cull_b", phases[1], 1), overlay],
            pruned: vec![],
            resources: vec![resource("a"), resource("b")],
            outputs: vec![],
            output_pos: vec![],
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
        let settings = OverlaySettings::from_plan(&p.passes[2]).unwrap();
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
        let p: Vec<String> = plan(["early", "late"]).passes.iter().map(|p| p.name.clone()).collect();
        let timing = |name: &str, ms| PassTiming { name: name.into(), start_ms: 0.0, ms };
        let t =
            GpuPassTimes::from_timings(&p, 7, &[timing("frame", 3.0), timing("cull_b", 2.0), timing("overlay", 0.5)]);
        assert_eq!((t.count, t.frame, t.total_ms), (3, 7, 3.0));
        assert_eq!(t.ms[..4], [-1.0, 2.0, 0.5, -1.0]);
        assert_eq!(PASS_TIMES_BYTES, 16 + 4 * times::MAX_TIMED as u64);
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
