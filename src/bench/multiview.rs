//! Two VR eyes drawn with `VK_KHR_multiview` against one pass per eye.
//!
//! Each eye is a view of the renderer, culled with its own history, so it draws its own list.
//! A multiview pass draws one command stream into both layers of a 2-layer target (view mask
//! `0b11`, `gl_ViewIndex` picking the eye's matrix), so it can only draw one list for both
//! eyes: the union of what the eyes drew, giving up what each eye's occlusion culling saved
//! the other. This measures both sides of that trade on the city: the G-buffer-like geometry
//! of the eyes' own lists in two passes, of the union in two passes, and of the union in one
//! multiview pass (`stereo`), with timestamp queries.

mod eye_list;
mod layered;
mod stereo;

pub use eye_list::EyeList;
pub use stereo::{EyeColors, EyeImages, StereoDraws};

use super::median;
use crate::error::{Error, Result};
use crate::gpu::{GpuContext, GpuTimer, ShaderCompiler};
use crate::passes::shared::scene_buffers::DrawList;
use crate::render::{DrawnInstances, FrameObserver, GraphSpec, RenderSettings, Renderer, ViewId};
use crate::scene::{Camera, Projection, Scene};
use crate::stats::FrameStats;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

/// Distance between the eyes, in metres (world units).
pub const EYE_SEPARATION: f64 = 0.064;

/// What to measure.
#[derive(Clone, Debug)]
pub struct MultiviewBench {
    /// Each eye's width in pixels.
    pub width: u32,
    /// Each eye's height in pixels.
    pub height: u32,
    /// Frames before measuring.
    pub warmup: u32,
    /// Frames measured (medians are reported).
    pub frames: u32,
}

/// The figures of one run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct MultiviewReport {
    /// Each eye's width.
    pub width: u32,
    /// Each eye's height.
    pub height: u32,
    /// Whether the device has multiview on ([`crate::gpu::DeviceCaps::multiview`]); without
    /// it only the separate passes are measured.
    pub multiview: bool,
    /// Instances each eye drew in the renderer (left, right): its own culled lists.
    pub drawn: [u32; 2],
    /// Instances either eye drew: the list a multiview pass draws for both.
    pub union: u32,
    /// Triangles of each eye's own list.
    pub triangles: [u64; 2],
    /// Triangles of the union list.
    pub union_triangles: u64,
    /// Median GPU milliseconds of two passes, each eye drawing its own list.
    pub separate_own_ms: f64,
    /// Median GPU milliseconds of two passes, each eye drawing the union list.
    pub separate_union_ms: f64,
    /// Median GPU milliseconds of one multiview pass drawing the union list for both eyes
    /// (`None` without multiview).
    pub multiview_union_ms: Option<f64>,
}

/// Asks the renderer to keep each pass's draw list, so each eye's drawn instances can be read.
struct KeepDrawLists;

impl FrameObserver for KeepDrawLists {
    fn needs_draw_lists(&self) -> bool {
        true
    }

    fn completed(&mut self, _: &Renderer, _: ViewId, _: u64, _: &mut FrameStats) -> Result<()> {
        Ok(())
    }
}

/// The eyes of a head at `head`: `EYE_SEPARATION` apart along its right axis, looking the
/// same way, each with an off-centre projection wider towards its own side (as a headset's
/// eyes), 80° high and as wide as `width` x `height` pixels make it.
pub fn eye_cameras(head: &Camera, width: u32, height: u32) -> [Camera; 2] {
    let right = head.view_rotation().row(0).as_dvec3();
    let tan_up = 40f32.to_radians().tan();
    // Half the horizontal extent, in tangents, for square pixels; a tenth more on the outer side.
    let half = tan_up * width.max(1) as f32 / height.max(1) as f32;
    let outer = (1.1 * half).atan().to_degrees().min(89.0);
    let inner = (0.9 * half).atan().to_degrees().min(89.0);
    [(-1.0, -outer, inner), (1.0, -inner, outer)].map(|(side, left_deg, right_deg)| {
        let offset = right * (side * EYE_SEPARATION * 0.5);
        Camera {
            eye: head.eye + offset,
            target: head.target + offset,
            projection: Projection::OffCenter {
                left_deg,
                right_deg,
                up_deg: 40.0,
                down_deg: -40.0,
                far: f32::INFINITY,
            },
            ..head.clone()
        }
    })
}

/// Renders `eyes` as two views of one renderer over `scene` (the default graph, `width` x
/// `height` each) for `frames` frames (at least 2, so that the second frame culls with the
/// first frame's history), and returns the renderer with the instances each eye drew in the
/// last frame (over all its drawing passes).
pub fn drawn_by_eyes(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: Scene,
    eyes: &[Camera; 2],
    (width, height): (u32, u32),
    frames: u32,
) -> Result<(Renderer, [BTreeSet<u32>; 2])> {
    let spec = GraphSpec::default_graph();
    let settings = RenderSettings::new(width, height);
    let mut renderer = Renderer::with_graph(ctx, shaders, scene, settings.clone(), &spec)?;
    renderer.attach(KeepDrawLists)?;
    let right = renderer.add_view(shaders, settings, &spec)?;
    let views = [ViewId::MAIN, right];
    for _ in 0..frames.max(2) {
        renderer.render_views(&[(views[0], &eyes[0]), (views[1], &eyes[1])])?;
    }
    let all = renderer.gpu_scene().instance_count;
    let mut drawn = [BTreeSet::new(), BTreeSet::new()];
    for (set, view) in drawn.iter_mut().zip(views) {
        for list in renderer.drawn_in_view(view)?.unwrap_or_default() {
            match list {
                DrawnInstances::All => set.extend(0..all),
                DrawnInstances::Some(ids) => set.extend(ids),
            }
        }
    }
    Ok((renderer, drawn))
}

/// Runs the measurement over `scene` seen from `head` (the views bench's first street camera).
pub fn run(
    ctx: &GpuContext,
    shaders: &ShaderCompiler,
    scene: &Scene,
    head: &Camera,
    bench: &MultiviewBench,
    progress: &dyn Fn(&str),
) -> Result<MultiviewReport> {
    let (width, height) = (bench.width, bench.height);
    let multiview = ctx.caps().multiview;
    progress(&format!(
        "views: two eyes of {width}x{height}, multiview {}",
        if multiview { "on" } else { "not on this device: separate passes only" }
    ));
    let eyes = eye_cameras(head, width, height);
    let (renderer, drawn) = drawn_by_eyes(ctx, shaders, scene.clone(), &eyes, (width, height), bench.warmup + 1)?;
    let union: BTreeSet<u32> = drawn[0].union(&drawn[1]).copied().collect();
    let all = DrawList::all_instances(renderer.scene());
    let own = [EyeList::upload(ctx, "left eye", &all, &drawn[0])?, EyeList::upload(ctx, "right eye", &all, &drawn[1])?];
    let both = EyeList::upload(ctx, "both eyes", &all, &union)?;
    let draws = StereoDraws::new(ctx, shaders, &eyes, width, height)?;
    let scene = renderer.gpu_scene();

    const OWN: &str = "separate, own lists";
    const UNION: &str = "separate, union list";
    const MULTIVIEW: &str = "multiview, union list";
    let mut timer = GpuTimer::new(ctx, 3)?;
    let mut times: [Vec<f64>; 3] = Default::default();
    for frame in 0..bench.warmup + bench.frames.max(1) {
        ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, OWN);
            draws.record_separate(cmd, scene, [&own[0], &own[1]]);
            timer.end(cmd);
            timer.begin(cmd, UNION);
            draws.record_separate(cmd, scene, [&both, &both]);
            timer.end(cmd);
            if draws.has_multiview() {
                timer.begin(cmd, MULTIVIEW);
                draws.record_multiview(cmd, scene, &both)?;
                timer.end(cmd);
            }
            Ok::<(), Error>(())
        })?;
        if frame < bench.warmup {
            continue;
        }
        for t in timer.results()? {
            if let Some(at) = [OWN, UNION, MULTIVIEW].iter().position(|n| *n == t.name) {
                times[at].push(t.ms);
            }
        }
    }
    let [own_ms, union_ms, multiview_ms] = &mut times;
    Ok(MultiviewReport {
        width,
        height,
        multiview: draws.has_multiview(),
        drawn: [own[0].instances, own[1].instances],
        union: both.instances,
        triangles: [own[0].triangles, own[1].triangles],
        union_triangles: both.triangles,
        separate_own_ms: median(own_ms),
        separate_union_ms: median(union_ms),
        multiview_union_ms: draws.has_multiview().then(|| median(multiview_ms)),
    })
}

impl MultiviewReport {
    /// The report as Markdown (a subsection of the views suite's).
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "\n### Multiview: two VR eyes\n\nTwo eyes of {}x{} ({} mm apart, off-centre projections), each culled as a view \
             of its own: {} and {} instances drawn ({} and {} triangles), {} in their union ({} triangles). The \
             eyes' geometry drawn with a normal-writing fragment shader:\n\n\
             | draws | GPU ms | against one multiview pass |\n|---|---|---|\n",
            self.width,
            self.height,
            EYE_SEPARATION * 1e3,
            self.drawn[0],
            self.drawn[1],
            self.triangles[0],
            self.triangles[1],
            self.union,
            self.union_triangles,
        );
        let against = |ms: f64| match self.multiview_union_ms {
            Some(m) => format!("{:.2}", ms / m.max(1e-9)),
            None => "-".into(),
        };
        md += &format!(
            "| a pass per eye, each eye's own list | {:.3} | {} |\n",
            self.separate_own_ms,
            against(self.separate_own_ms)
        );
        md += &format!(
            "| a pass per eye, the union list | {:.3} | {} |\n",
            self.separate_union_ms,
            against(self.separate_union_ms)
        );
        match self.multiview_union_ms {
            Some(ms) => md += &format!("| one multiview pass, the union list | {ms:.3} | 1.00 |\n"),
            None => {
                md += "\nMultiview is not on on this device (not supported, or a host's device created without \
                       it): the multiview pass was not measured.\n"
            }
        }
        md
    }
}
