//! Brute-force proofs of the conservative culling math (`cullgraph::cull::math`): for many
//! thousands of random bounds and cameras, densely sampled points of each bound are projected in
//! `f64` and must all land in the computed pixel rectangle, at depths no larger than the computed
//! nearest depth, and never inside the frustum when the frustum test rejected the bound.
//!
//! Cases: spheres and boxes of every size (sub-pixel to screen-filling), straddling the near
//! plane, behind the eye, around the eye, off to the side; perspective with 1°–179° field of view
//! (with and without a far plane) and orthographic, each centred, off-centre or jittered;
//! aspect 0.1–10; viewports 1×1, 3×3, 1023×767, thin and random up to 4096;
//! worlds 10⁷ from the origin with hi/lo eye-relative inputs; instance boxes with zero and
//! negative scales through `Scene::instance_bounds`.

use cullgraph::cull::math::{self as cm, CullView, ScreenBounds};
use cullgraph::passes::shared::gpu_types::split_hi_lo;
use cullgraph::scene::{Aabb, Instance, Mesh, Scene, Sphere, Transform};
use glam::{DMat3, DVec3, Mat3, Quat, UVec2, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use rand::{Rng, SeedableRng};
use std::cell::RefCell;
use std::collections::BTreeMap;

const CASES: u32 = 10_000;

fn runner(cases: u32) -> TestRunner {
    let cases = std::env::var("ORACLE_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(cases);
    TestRunner::new(Config { cases, failure_persistence: None, ..Config::default() })
}

// ---------------------------------------------------------------------------------------------
// Cameras

#[derive(Clone, Debug)]
struct CamSpec {
    ortho: bool,
    fov_deg: f32,
    aspect: f32,
    near: f32,
    height: f32,
    depth_range: f32,
    quat: [f32; 4],
    size: (u32, u32),
    /// NDC offset: centred, off-centre (a VR eye's) or a sub-pixel jitter.
    offset: (f32, f32),
    /// A finite far plane for perspective (depth_range beyond near).
    finite_far: bool,
}

fn log_uniform(lo: f32, hi: f32) -> impl Strategy<Value = f32> {
    (lo.log10()..hi.log10()).prop_map(|e| 10f32.powf(e))
}

fn cam_strategy() -> impl Strategy<Value = CamSpec> {
    let fov = prop_oneof![1.0f32..179.0, Just(1.0f32), Just(179.0f32), 170.0f32..179.0, 30.0f32..100.0];
    let size = prop_oneof![
        Just((1u32, 1u32)),
        Just((3, 3)),
        Just((1023, 767)),
        (1u32..=4096, 1u32..=4096),
        (1u32..=4, 1u32..=4096),
        (1u32..=4096, 1u32..=4),
        (1u32..=64, 1u32..=64),
    ];
    (
        prop::bool::weighted(0.25),
        fov,
        log_uniform(0.1, 10.0),
        log_uniform(1e-5, 10.0),
        log_uniform(0.01, 1e4),
        log_uniform(0.1, 1e5),
        prop::array::uniform4(-1.0f32..1.0),
        size,
        prop_oneof![Just((0.0f32, 0.0f32)), (-1.5f32..1.5, -1.5f32..1.5), (-0.01f32..0.01, -0.01f32..0.01)],
        prop::bool::weighted(0.3),
    )
        .prop_map(|(ortho, fov_deg, aspect, near, height, depth_range, quat, size, offset, finite_far)| CamSpec {
            ortho,
            fov_deg,
            aspect,
            near,
            height,
            depth_range,
            quat,
            size,
            offset,
            finite_far,
        })
}

impl CamSpec {
    fn rotation(&self) -> Mat3 {
        let q = Quat::from_array(self.quat);
        let q = if q.length() < 0.1 { Quat::IDENTITY } else { q.normalize() };
        Mat3::from_quat(q)
    }

    fn view(&self) -> CullView {
        let mut view = self.centred_view();
        view.offset = glam::Vec2::new(self.offset.0, self.offset.1);
        if self.finite_far && !self.ortho {
            view.far = self.near + self.depth_range;
        }
        view
    }

    fn centred_view(&self) -> CullView {
        let size = UVec2::new(self.size.0, self.size.1);
        if self.ortho {
            CullView::orthographic(
                self.rotation(),
                self.height,
                self.aspect,
                self.near,
                self.near + self.depth_range,
                size,
            )
        } else {
            CullView::perspective(self.rotation(), self.fov_deg.to_radians(), self.aspect, self.near, size)
        }
    }
}

/// Exact (`f64`) projection with the view's own `f32` parameters.
struct Truth {
    view: CullView,
    r: DMat3,
}

impl Truth {
    fn new(view: CullView) -> Self {
        Self { view, r: view.rotation.as_dmat3() }
    }
    fn to_view(&self, p: DVec3) -> DVec3 {
        self.r * p
    }
    fn near(&self) -> f64 {
        self.view.near as f64
    }
    /// Framebuffer position of a view-space point in front of the eye.
    fn pixel(&self, v: DVec3) -> (f64, f64) {
        let (sx, sy) = (self.view.scale.x as f64, self.view.scale.y as f64);
        let (cx, cy) = (self.view.offset.x as f64, self.view.offset.y as f64);
        let d = -v.z;
        let (nx, ny) = if self.view.orthographic {
            (sx * v.x - cx, cy - sy * v.y)
        } else {
            (sx * v.x / d - cx, cy - sy * v.y / d)
        };
        ((nx + 1.0) * 0.5 * self.view.viewport.x as f64, (ny + 1.0) * 0.5 * self.view.viewport.y as f64)
    }
    fn pixel_index(&self, v: DVec3) -> Option<(u32, u32)> {
        let (px, py) = self.pixel(v);
        let (x, y) = (px.floor(), py.floor());
        let (w, h) = (self.view.viewport.x as f64, self.view.viewport.y as f64);
        (x >= 0.0 && y >= 0.0 && x < w && y < h).then_some((x as u32, y as u32))
    }
    fn depth(&self, v: DVec3) -> f64 {
        let d = -v.z;
        let (n, f) = (self.view.near as f64, self.view.far as f64);
        if self.view.orthographic {
            (f - d) / (f - n)
        } else if f.is_finite() {
            n * (f - d) / (d * (f - n))
        } else {
            self.near() / d
        }
    }
    /// Inside the closed view frustum.
    fn inside(&self, v: DVec3) -> bool {
        let (sx, sy) = (self.view.scale.x as f64, self.view.scale.y as f64);
        let (cx, cy) = (self.view.offset.x as f64, self.view.offset.y as f64);
        let d = -v.z;
        if d < self.near() || d > self.view.far as f64 {
            return false;
        }
        if self.view.orthographic {
            (sx * v.x - cx).abs() <= 1.0 && (sy * v.y - cy).abs() <= 1.0
        } else {
            (sx * v.x - cx * d).abs() <= d && (sy * v.y - cy * d).abs() <= d
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Bounds

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    SubPixel,
    Small,
    Large,
    ScreenFilling,
    StraddleNear,
    Behind,
    EyeInside,
    OffToSide,
}

#[derive(Clone, Debug)]
struct BoundSpec {
    kind: Kind,
    ndc: (f64, f64),
    dist: f64,
    size: f64,
    t: f64,
    extents: [f64; 3],
    zero_axes: [bool; 3],
    seed: u64,
}

fn bound_strategy() -> impl Strategy<Value = BoundSpec> {
    let kind = prop_oneof![
        Just(Kind::SubPixel),
        Just(Kind::Small),
        Just(Kind::Large),
        Just(Kind::ScreenFilling),
        Just(Kind::StraddleNear),
        Just(Kind::Behind),
        Just(Kind::EyeInside),
        Just(Kind::OffToSide),
    ];
    (
        kind,
        (-1.5f64..1.5, -1.5f64..1.5),
        0.0f64..1.0,
        0.0f64..1.0,
        -1.0f64..1.0,
        prop::array::uniform3(0.0f64..1.0),
        prop::array::uniform3(prop::bool::weighted(0.1)),
        any::<u64>(),
    )
        .prop_map(|(kind, ndc, dist, size, t, extents, zero_axes, seed)| BoundSpec {
            kind,
            ndc,
            dist,
            size,
            t,
            extents,
            zero_axes,
            seed,
        })
}

/// View-space center and radius of the bound a spec describes.
fn place(view: &CullView, spec: &BoundSpec) -> (DVec3, f64) {
    let (sx, sy) = (view.scale.x as f64, view.scale.y as f64);
    let near = view.near as f64;
    let h_px = view.viewport.y as f64;
    let ortho = view.orthographic;
    let far = if ortho { view.far as f64 } else { f64::INFINITY };
    // Distance: perspective near .. 10^6·near, orthographic near .. 1.2·far.
    let mut d = if ortho { near + (far - near) * 1.2 * spec.dist } else { near * 10f64.powf(6.0 * spec.dist) };
    let mut ndc = spec.ndc;
    if spec.kind == Kind::OffToSide {
        ndc = (spec.ndc.0 * 2.5, spec.ndc.1 * 2.5);
    }
    // Half-screen extents in world units at distance d.
    let (hx, hy) = if ortho { (1.0 / sx, 1.0 / sy) } else { (d / sx, d / sy) };
    let pixel = 2.0 * hy / h_px;
    let r = match spec.kind {
        Kind::SubPixel => pixel * 10f64.powf(-2.0 + 2.0 * spec.size),
        Kind::Small | Kind::OffToSide => hx.min(hy) * 10f64.powf(-3.0 + 2.0 * spec.size),
        Kind::Large => hx.min(hy) * 10f64.powf(-1.0 + spec.size),
        Kind::ScreenFilling => hx.max(hy) * (1.0 + 3.0 * spec.size),
        Kind::StraddleNear => {
            let r = near * 10f64.powf(-2.0 + 4.0 * spec.size);
            d = near + r * spec.t;
            r
        }
        Kind::Behind => {
            d = -near * 10f64.powf(4.0 * spec.dist);
            d.abs() * 10f64.powf(-3.0 + 3.0 * spec.size)
        }
        Kind::EyeInside => {
            let r = near * 10f64.powf(4.0 * spec.size);
            return (DVec3::new(0.3 * spec.t * r, 0.2 * spec.ndc.0 * r, 0.5 * spec.ndc.1 * r), r);
        }
    };
    // NDC (x, y) ↔ t = (x + cx)/sx, u = (cy − y)/sy per unit of distance (perspective).
    let (cx, cy) = (view.offset.x as f64, view.offset.y as f64);
    let (tx, ty) = ((ndc.0 + cx) / sx, (cy - ndc.1) / sy);
    let (x, y) = if ortho { (tx, ty) } else { (tx * d.abs(), ty * d.abs()) };
    (DVec3::new(x, y, -d), r)
}

fn unit_vector(rng: &mut rand::rngs::SmallRng) -> DVec3 {
    loop {
        let v = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let l = v.length();
        if l > 0.05 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Eye-relative world points of a sphere: random surface points plus the exact extremes of its
/// projection (tangent points in x and y, the nearest point, the view-axis extremes).
fn sphere_points(truth: &Truth, center: DVec3, r: f64, seed: u64, n: usize) -> Vec<DVec3> {
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed);
    let mut pts: Vec<DVec3> = (0..n).map(|_| center + unit_vector(&mut rng) * r).collect();
    let to_world = truth.r.transpose();
    let c = truth.to_view(center);
    let mut view_pts = vec![];
    for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
        view_pts.push(c + axis * r);
        view_pts.push(c - axis * r);
    }
    let d = -c.z;
    for (a, is_x) in [(c.x, true), (c.y, false)] {
        let rho = (a * a + d * d).sqrt();
        if r < rho && d > 0.0 {
            let theta = a.atan2(d);
            let alpha = (r / rho).asin();
            let v = rho * alpha.cos();
            for s in [-1.0, 1.0] {
                let th = theta + s * alpha;
                let (ta, td) = (v * th.sin(), v * th.cos());
                view_pts.push(if is_x { DVec3::new(ta, c.y, -td) } else { DVec3::new(c.x, ta, -td) });
            }
        }
    }
    pts.extend(view_pts.into_iter().map(|v| to_world * v));
    pts
}

/// Points of the box `min..max`: corners, edges, faces, interior.
fn box_points(min: DVec3, max: DVec3, seed: u64) -> Vec<DVec3> {
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed);
    let lerp = |t: DVec3| min + (max - min) * t;
    let mut pts = vec![];
    for i in 0..8 {
        pts.push(lerp(DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)));
    }
    for _ in 0..160 {
        let mut t = DVec3::new(rng.random(), rng.random(), rng.random());
        // Pin one or two coordinates to a face or an edge.
        let pins = rng.random_range(0..3);
        for _ in 0..pins {
            let axis = rng.random_range(0..3);
            t[axis] = if rng.random() { 0.0 } else { 1.0 };
        }
        pts.push(lerp(t));
    }
    pts
}

// ---------------------------------------------------------------------------------------------
// The check shared by every case

#[derive(Default)]
struct Stats {
    outcomes: BTreeMap<(Kind, &'static str), u64>,
    frustum_rejected: u64,
    max_over_px: f64,
    max_over_px_normal: f64,
    /// Cases by how many pixels the rectangle reaches past the samples: 0, 1, 2, 3+.
    over_hist: [u64; 4],
    points: u64,
}

thread_local! {
    static STATS: RefCell<Stats> = RefCell::new(Stats::default());
}

/// What the bound is, for the tightness checks.
struct Exact {
    /// True nearest distance along the view axis.
    d_min: f64,
    /// Bound on the length of the bound's points (as the oracle computes `M`).
    m: f64,
}

fn check(
    truth: &Truth,
    kind: Kind,
    points: &[DVec3],
    proj: ScreenBounds,
    in_frustum: bool,
    exact: Exact,
    normal_camera: bool,
) -> Result<(), TestCaseError> {
    let near = truth.near();
    let view_pts: Vec<DVec3> = points.iter().map(|&p| truth.to_view(p)).collect();
    if !in_frustum {
        for (p, v) in points.iter().zip(&view_pts) {
            prop_assert!(!truth.inside(*v), "frustum test rejected a bound with point {p} (view {v}) inside");
        }
    }
    // Not needlessly "crossing near": a bound clearly in front, well conditioned, gets projected.
    let clearly_in_front = exact.d_min - near > 4.0 * cm::REL_EPS as f64 * exact.m
        && exact.m < exact.d_min * cm::MAX_CONDITION as f64 * 0.5
        && exact.m < 1e17;
    let label = match proj {
        ScreenBounds::CrossesNear => {
            prop_assert!(!clearly_in_front, "bound {} in front of the near plane was refused", exact.d_min - near);
            "crosses_near"
        }
        ScreenBounds::OffScreen => {
            for v in &view_pts {
                prop_assert!(-v.z >= near, "off screen but a point is at distance {} < near {near}", -v.z);
                prop_assert!(
                    truth.pixel_index(*v).is_none(),
                    "off screen but point {v} lands on {:?}",
                    truth.pixel(*v)
                );
            }
            "off_screen"
        }
        ScreenBounds::OnScreen { rect, nearest_depth, .. } => {
            let (w, h) = (truth.view.viewport.x, truth.view.viewport.y);
            prop_assert!(rect.x0 <= rect.x1 && rect.y0 <= rect.y1 && rect.x1 < w && rect.y1 < h, "{rect:?}");
            let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
            for v in &view_pts {
                prop_assert!(-v.z >= near, "projected but a point is at distance {} < near {near}", -v.z);
                let depth = truth.depth(*v);
                prop_assert!(nearest_depth as f64 >= depth, "nearest depth {nearest_depth} < {depth} of {v}");
                if let Some((x, y)) = truth.pixel_index(*v) {
                    prop_assert!(
                        rect.contains(x, y),
                        "pixel ({x}, {y}) of {v} at {:?} outside {rect:?}",
                        truth.pixel(*v)
                    );
                }
                let (px, py) = truth.pixel(*v);
                (lo, hi) = ((lo.0.min(px), lo.1.min(py)), (hi.0.max(px), hi.1.max(py)));
            }
            // How far the rectangle reaches past the bounding rectangle of the sampled points,
            // clamped to the screen (tightness, not safety).
            let clamp = |v: f64, n: u32| v.floor().clamp(0.0, n as f64 - 1.0) as i64;
            let e = [clamp(lo.0, w), clamp(lo.1, h), clamp(hi.0, w), clamp(hi.1, h)];
            if lo.0 < w as f64 && lo.1 < h as f64 && hi.0 >= 0.0 && hi.1 >= 0.0 {
                let r = [rect.x0 as i64, rect.y0 as i64, rect.x1 as i64, rect.y1 as i64];
                let over = [e[0] - r[0], e[1] - r[1], r[2] - e[2], r[3] - e[3]].into_iter().max().unwrap();
                STATS.with(|s| {
                    let mut s = s.borrow_mut();
                    s.max_over_px = s.max_over_px.max(over as f64);
                    s.over_hist[over.clamp(0, 3) as usize] += 1;
                    if normal_camera {
                        s.max_over_px_normal = s.max_over_px_normal.max(over as f64);
                    }
                });
                if normal_camera && matches!(kind, Kind::SubPixel | Kind::Small) {
                    prop_assert!(over <= 1, "rectangle {rect:?} reaches {over} px past the exact {e:?}");
                }
            }
            "on_screen"
        }
    };
    STATS.with(|s| {
        let mut s = s.borrow_mut();
        *s.outcomes.entry((kind, label)).or_default() += 1;
        s.frustum_rejected += !in_frustum as u64;
        s.points += points.len() as u64;
    });
    Ok(())
}

fn report(name: &str) {
    STATS.with(|s| {
        let s = s.borrow();
        let total: u64 = s.outcomes.values().sum();
        println!(
            "{name}: {total} cases, {} sampled points, {} rejected by the frustum test",
            s.points, s.frustum_rejected
        );
        for ((kind, label), n) in &s.outcomes {
            println!("  {kind:?} {label}: {n}");
        }
        println!(
            "  rectangle past the sampled extremes: at most {} px (normal cameras: {} px); cases by excess 0/1/2/3+ px: {:?}",
            s.max_over_px, s.max_over_px_normal, s.over_hist
        );
    });
}

fn normal_camera(cam: &CamSpec) -> bool {
    !cam.ortho && (10.0..=120.0).contains(&cam.fov_deg) && (0.25..=4.0).contains(&cam.aspect)
}

// ---------------------------------------------------------------------------------------------
// The tests

#[test]
fn spheres_are_projected_conservatively() {
    runner(CASES)
        .run(&(cam_strategy(), bound_strategy()), |(cam, spec)| {
            let view = cam.view();
            let truth = Truth::new(view);
            let (c_view, r) = place(&view, &spec);
            let center = (truth.r.transpose() * c_view).as_vec3();
            let radius = r as f32;
            // The bound as the oracle sees it: the f32 center and radius.
            let (center64, r64) = (center.as_dvec3(), radius as f64);
            let points = sphere_points(&truth, center64, r64, spec.seed, 400);
            let proj = cm::project_sphere(&view, center, radius);
            let inside = cm::sphere_in_frustum(&view, center, radius);
            let c = truth.to_view(center64);
            let exact = Exact { d_min: -c.z - r64, m: center64.abs().element_sum() + r64 };
            check(&truth, spec.kind, &points, proj, inside, exact, normal_camera(&cam))
        })
        .unwrap();
    report("spheres");
}

#[test]
fn boxes_are_projected_conservatively() {
    runner(CASES)
        .run(&(cam_strategy(), bound_strategy()), |(cam, spec)| {
            let view = cam.view();
            let truth = Truth::new(view);
            let (c_view, r) = place(&view, &spec);
            let center = truth.r.transpose() * c_view;
            let half =
                DVec3::from_array(std::array::from_fn(|i| if spec.zero_axes[i] { 0.0 } else { r * spec.extents[i] }));
            let (min, max) = ((center - half).as_vec3(), (center + half).as_vec3());
            let (min64, max64) = (min.as_dvec3(), max.as_dvec3());
            let points = box_points(min64, max64, spec.seed);
            let proj = cm::project_aabb(&view, min, max);
            let inside = cm::aabb_in_frustum(&view, min, max);
            let d_min = points.iter().map(|&p| -truth.to_view(p).z).fold(f64::INFINITY, f64::min);
            let exact = Exact { d_min, m: min64.abs().max(max64.abs()).element_sum() };
            check(&truth, spec.kind, &points, proj, inside, exact, normal_camera(&cam))
        })
        .unwrap();
    report("boxes");
}

/// Bounds 10^7 from the origin: the oracle gets the eye-relative center from the hi/lo
/// subtraction the GPU does; the truth is the exact `f64` world position minus the eye.
#[test]
fn far_from_the_origin_with_hi_lo_inputs() {
    let strategy = (cam_strategy(), bound_strategy(), prop::array::uniform3(-1.0e7f64..1.0e7), any::<bool>());
    runner(CASES / 2)
        .run(&strategy, |(cam, spec, eye, boxed)| {
            let view = cam.view();
            let truth = Truth::new(view);
            let (mut c_view, mut r) = place(&view, &spec);
            // Within a few centimetres of the eye the hi/lo rounding (6e-8) exceeds the relative
            // allowance; there the bound and its vertices share that rounding (module docs), and
            // the bound given is grown by this center's rounding (`err` below), which it then
            // holds whole.
            let m = c_view.length() + r;
            if m < 0.05 {
                c_view *= 0.05 / m;
                r *= 0.05 / m;
            }
            let eye = DVec3::from_array(eye);
            let rel64 = truth.r.transpose() * c_view;
            let world = eye + rel64;
            let (c_hi, c_lo) = split_hi_lo(world);
            let (e_hi, e_lo) = split_hi_lo(eye);
            let rel = (c_hi - e_hi) + (c_lo - e_lo);
            let err = (rel.as_dvec3() - rel64).length();
            prop_assert!(err <= 1e-7 + 3.0 * f32::EPSILON as f64 * rel64.length(), "hi/lo error {err}");
            let kind = spec.kind;
            if boxed {
                let half = DVec3::from_array(spec.extents) * r;
                let half32 = (half + DVec3::splat(err)).as_vec3();
                let (min, max) = (rel - half32, rel + half32);
                let points = box_points(rel64 - half, rel64 + half, spec.seed);
                let d_min = points.iter().map(|&p| -truth.to_view(p).z).fold(f64::INFINITY, f64::min);
                let m = min.abs().max(max.abs()).element_sum() as f64;
                let (proj, inside) = (cm::project_aabb(&view, min, max), cm::aabb_in_frustum(&view, min, max));
                check(&truth, kind, &points, proj, inside, Exact { d_min, m }, normal_camera(&cam))
            } else {
                let points = sphere_points(&truth, rel64, r, spec.seed, 200);
                let grown = (r + err) as f32;
                let (proj, inside) = (cm::project_sphere(&view, rel, grown), cm::sphere_in_frustum(&view, rel, grown));
                let exact = Exact { d_min: -truth.to_view(rel64).z - r, m: rel64.abs().element_sum() + r };
                check(&truth, kind, &points, proj, inside, exact, normal_camera(&cam))
            }
        })
        .unwrap();
    report("10^7 from the origin");
}

/// Instance boxes through `Scene::instance_bounds`, with zero and negative scales and random
/// rotations; the truth is the transformed local box, computed in `f64`.
#[test]
fn instance_boxes_with_zero_and_negative_scale() {
    let scale = prop_oneof![Just(0.0f32), -4.0f32..-0.01, 0.01f32..4.0, Just(-1.0f32)];
    let strategy = (
        cam_strategy(),
        bound_strategy(),
        prop::array::uniform3(scale),
        prop::array::uniform4(-1.0f32..1.0),
        prop::array::uniform3(-2.0f32..2.0),
        prop::array::uniform3(0.0f32..2.0),
        prop::array::uniform3(-1.0e6f64..1.0e6),
    );
    runner(CASES / 2)
        .run(&strategy, |(cam, spec, scale, q, local_min, local_size, eye)| {
            let view = cam.view();
            let truth = Truth::new(view);
            let (c_view, r) = place(&view, &spec);
            let eye = DVec3::from_array(eye);
            let q = Quat::from_array(q);
            let q = if q.length() < 0.1 { Quat::IDENTITY } else { q.normalize() };
            // Scale the unit-ish local box to the placed bound's size.
            let linear = Mat3::from_quat(q) * Mat3::from_diagonal(Vec3::from_array(scale) * (r as f32).max(1e-6));
            let translation = eye + truth.r.transpose() * c_view;
            let local = Aabb {
                min: Vec3::from_array(local_min),
                max: Vec3::from_array(local_min) + Vec3::from_array(local_size),
            };
            let mut scene = Scene::default();
            scene.meshes.push(Mesh {
                name: "box".into(),
                first_index: 0,
                index_count: 0,
                vertex_offset: 0,
                vertex_count: 0,
                bounds: local,
                sphere: Sphere { center: local.center(), radius: local.half_extent().length() },
                deform: None,
                lods: Vec::new(),
                clusters: Vec::new(),
            });
            let instance = Instance { transform: Transform { linear, translation }, mesh: 0, material: 0, flags: 0 };
            let (wmin, wmax) = scene.instance_bounds(&instance);
            prop_assert!(wmin.cmple(wmax).all());
            let (min, max) = ((wmin - eye).as_vec3(), (wmax - eye).as_vec3());
            let l64 = linear.as_dmat3();
            let points: Vec<DVec3> = box_points(local.min.as_dvec3(), local.max.as_dvec3(), spec.seed)
                .into_iter()
                .map(|p| l64 * p + (translation - eye))
                .collect();
            let d_min = points.iter().map(|&p| -truth.to_view(p).z).fold(f64::INFINITY, f64::min);
            let m = min.abs().max(max.abs()).element_sum() as f64;
            // The world box may be wider than the transformed box: d_min of its corners.
            let corners = box_points(min.as_dvec3(), max.as_dvec3(), 0)[..8].to_vec();
            let d_box = corners.iter().map(|&p| -truth.to_view(p).z).fold(f64::INFINITY, f64::min);
            let (proj, inside) = (cm::project_aabb(&view, min, max), cm::aabb_in_frustum(&view, min, max));
            check(&truth, spec.kind, &points, proj, inside, Exact { d_min: d_min.min(d_box), m }, false)
        })
        .unwrap();
    report("instance boxes");
}

/// Hand-picked hard cases: extreme field of view, tiny near plane, extreme aspect, 1×1 targets.
#[test]
fn extreme_cameras_keep_what_they_see() {
    let rot = Mat3::IDENTITY;
    for (fov, aspect, near, size) in [
        (179.0f32, 10.0f32, 1e-5f32, (4096u32, 410u32)),
        (179.0, 0.1, 1e-5, (410, 4096)),
        (1.0, 1.0, 10.0, (1, 1)),
        (90.0, 1.0, 1e-6, (3, 3)),
        (120.0, 16.0 / 9.0, 0.1, (1023, 767)),
    ] {
        let view = CullView::perspective(rot, fov.to_radians(), aspect, near, UVec2::new(size.0, size.1));
        let truth = Truth::new(view);
        let mut rng = rand::rngs::SmallRng::seed_from_u64(7);
        for _ in 0..3000 {
            let d = near as f64 * 10f64.powf(rng.random_range(0.0..7.0));
            let spread = 1.2 / view.scale.x.min(view.scale.y) as f64;
            let c = DVec3::new(rng.random_range(-spread..spread) * d, rng.random_range(-spread..spread) * d, -d);
            let r = d * 10f64.powf(rng.random_range(-6.0..0.0));
            let (center, radius) = (c.as_vec3(), r as f32);
            let points = sphere_points(&truth, center.as_dvec3(), radius as f64, rng.random(), 100);
            let exact = Exact { d_min: -(center.z as f64) - radius as f64, m: center.abs().element_sum() as f64 + r };
            let proj = cm::project_sphere(&view, center, radius);
            let inside = cm::sphere_in_frustum(&view, center, radius);
            check(&truth, Kind::Small, &points, proj, inside, exact, false).unwrap();
            let (min, max) = (center - radius, center + radius * 0.5);
            let points = box_points(min.as_dvec3(), max.as_dvec3(), rng.random());
            let d_min = points.iter().map(|p| -p.z).fold(f64::INFINITY, f64::min);
            let exact = Exact { d_min, m: min.abs().max(max.abs()).element_sum() as f64 };
            let (proj, inside) = (cm::project_aabb(&view, min, max), cm::aabb_in_frustum(&view, min, max));
            check(&truth, Kind::Small, &points, proj, inside, exact, false).unwrap();
        }
    }
    report("extreme cameras");
}

#[test]
fn nan_and_huge_inputs_are_visible() {
    let view = CullView::perspective(Mat3::IDENTITY, 1.0, 1.0, 0.1, UVec2::new(64, 64));
    for c in [Vec3::new(f32::NAN, 0.0, -5.0), Vec3::new(0.0, f32::INFINITY, -5.0), Vec3::new(0.0, 0.0, -1e30)] {
        assert_eq!(cm::project_sphere(&view, c, 1.0), ScreenBounds::CrossesNear);
        assert!(cm::sphere_in_frustum(&view, c, 1.0));
        assert_eq!(cm::project_aabb(&view, c, c + 1.0), ScreenBounds::CrossesNear);
        assert!(cm::aabb_in_frustum(&view, c, c + 1.0));
    }
    assert_eq!(cm::project_sphere(&view, Vec3::new(0.0, 0.0, -5.0), f32::NAN), ScreenBounds::CrossesNear);
    assert_eq!(cm::project_sphere(&view, Vec3::new(0.0, 0.0, -5.0), -1.0), ScreenBounds::CrossesNear);
}

/// A camera built from `Camera` has exactly the rasterizer's scale factors.
#[test]
fn views_from_cameras_match_the_projection_matrix() {
    use cullgraph::scene::{Camera, Projection};
    let cam = Camera { projection: Projection::Perspective { fov_y_deg: 73.0 }, ..Default::default() };
    let view = CullView::from_camera(&cam, 640, 360);
    let p = cam.projection_matrix(640.0 / 360.0);
    assert_eq!((view.scale.x, view.scale.y), (p.x_axis.x, -p.y_axis.y));
    assert!(!view.orthographic && view.near == cam.near);
    let cam = Camera { projection: Projection::Orthographic { height: 12.0, far: 300.0 }, ..Default::default() };
    let view = CullView::from_camera(&cam, 640, 360);
    let p = cam.projection_matrix(640.0 / 360.0);
    assert_eq!((view.scale.x, view.scale.y, view.far), (p.x_axis.x, -p.y_axis.y, 300.0));
    // A point projected through the full matrix lands where the oracle's convention puts it.
    let rel = Vec3::new(0.7, -0.4, -3.0);
    let clip = cam.view_projection_rel_eye(640.0 / 360.0) * rel.extend(1.0);
    let v = cm::to_view(&view.rotation, rel);
    assert!((clip.x / clip.w - view.scale.x * v.x).abs() < 1e-5);
    assert!((clip.y / clip.w + view.scale.y * v.y).abs() < 1e-5);
    assert!((clip.z / clip.w - (300.0 + v.z) / (300.0 - cam.near)).abs() < 1e-5);
}
