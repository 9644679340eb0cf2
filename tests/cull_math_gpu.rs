//! GPU agreement of the culling math: a compute shader including `common/cull_math.glsl` and
//! `common/hiz.glsl` evaluates thousands of random cases (frustum tests, screen rectangles,
//! nearest depths, Hi-Z levels, occlusion against small uploaded pyramids stored as flat buffers
//! with level offsets) and every result is compared with the CPU twin in `cullgraph::oracle`.
//!
//! Decisions (frustum, near/off/on screen, occlusion, level) must be identical. A rectangle or
//! depth that differs in the last bits is tolerated only if both are still conservative against
//! the exact `f64` projection (rectangle: every pixel of the exact rectangle inside both, at most
//! one pixel apart; depth: both ≥ the exact nearest depth, at most 8 ulps apart); every tolerated
//! difference is printed. `CULLGRAPH_TEST_DEVICE` runs it on another device (one whose division
//! is not correctly rounded puts some nearest depths an ulp or two from the oracle's).

mod common;

use ash::vk;
use bytemuck::{Pod, Zeroable};
use common::GpuTest;
use cullgraph::cull::hiz::{is_occluded, HiZPyramid, HizVariant};
use cullgraph::cull::math::{self as cm, CullView, ScreenBounds};
use cullgraph::gpu::{transfer, Bind, Pipeline, UploadBatch};
use glam::{DMat3, DVec3, Mat3, Quat, Vec2, Vec3};
use rand::{Rng, SeedableRng};

const SHADER: &str = r#"#version 460
#extension GL_EXT_scalar_block_layout : require
#include "common/cull_math.glsl"
layout(local_size_x = 64) in;

struct Case {
    vec3 rot0; vec3 rot1; vec3 rot2;   // columns of the world->view rotation
    vec2 scale; float near; float far; uint ortho; uvec2 viewport; vec2 offset;
    uint kind;                          // 0: sphere (a = center, radius), 1: box (a = min, b = max)
    vec3 a; vec3 b; float radius;
    uint pyramid;
};
struct Pyramid { uvec2 base; uint offset; uint pad; };
struct Result {
    uint frustum; uint status; uvec4 rect; float depth; uint level; uint occ_coarse; uint occ_finer; uint covers;
};

layout(scalar, set = 0, binding = 0) readonly buffer Cases { Case cases[]; };
layout(scalar, set = 0, binding = 1) readonly buffer Pyramids { Pyramid pyramids[]; };
layout(scalar, set = 0, binding = 2) readonly buffer Texels { float texels[]; };
layout(scalar, set = 0, binding = 3) writeonly buffer Results { Result results[]; };
layout(push_constant) uniform Push { uint count; };

uint g_pyramid;

float hiz_load(uint level, uvec2 texel) {
    Pyramid p = pyramids[g_pyramid];
    uvec2 size = hiz_level_size(p.base, level);
    return texels[p.offset + hiz_level_offset(p.base, level) + texel.y * size.x + texel.x];
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    Case c = cases[i];
    g_pyramid = c.pyramid;
    CullView view;
    view.rotation = mat3(c.rot0, c.rot1, c.rot2);
    view.scale = c.scale;
    view.near = c.near;
    view.far = c.far;
    view.orthographic = c.ortho;
    view.viewport = c.viewport;
    view.offset = c.offset;
    Result r;
    uvec4 rect;
    float depth;
    bool covers;
    if (c.kind == 0u) {
        r.frustum = cull_sphere_in_frustum(view, c.a, c.radius) ? 1u : 0u;
        r.status = cull_project_sphere(view, c.a, c.radius, rect, depth, covers);
    } else {
        r.frustum = cull_aabb_in_frustum(view, c.a, c.b) ? 1u : 0u;
        r.status = cull_project_aabb(view, c.a, c.b, rect, depth, covers);
    }
    r.covers = (r.status == CULL_ON_SCREEN && covers) ? 1u : 0u;
    r.rect = rect;
    r.depth = depth;
    r.level = 0u;
    r.occ_coarse = 0u;
    r.occ_finer = 0u;
    if (r.status == CULL_ON_SCREEN) {
        r.level = cull_hiz_level(rect);
        uvec2 base = pyramids[c.pyramid].base;
        r.occ_coarse = cull_hiz_occluded(rect, depth, base, false) ? 1u : 0u;
        r.occ_finer = cull_hiz_occluded(rect, depth, base, true) ? 1u : 0u;
    }
    results[i] = r;
}
"#;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuCase {
    rot: [[f32; 3]; 3],
    scale: [f32; 2],
    near: f32,
    far: f32,
    ortho: u32,
    viewport: [u32; 2],
    offset: [f32; 2],
    kind: u32,
    a: [f32; 3],
    b: [f32; 3],
    radius: f32,
    pyramid: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
struct GpuResult {
    frustum: u32,
    status: u32,
    rect: [u32; 4],
    depth: f32,
    level: u32,
    occ_coarse: u32,
    occ_finer: u32,
    covers: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuPyramid {
    base: [u32; 2],
    offset: u32,
    pad: u32,
}

/// A depth buffer of random rectangles at reversed-Z depths 10^-4 .. 1, over a far background.
fn depth_buffer(w: u32, h: u32, rng: &mut rand::rngs::SmallRng) -> Vec<f32> {
    let mut d =
        vec![if rng.random_bool(0.5) { 0.0 } else { 10f32.powf(-rng.random_range(2.0..4.0)) }; (w * h) as usize];
    for _ in 0..rng.random_range(1..12) {
        let (x0, y0) = (rng.random_range(0..w), rng.random_range(0..h));
        let (x1, y1) = (rng.random_range(x0..w), rng.random_range(y0..h));
        let z = 10f32.powf(-rng.random_range(0.0..4.0));
        for y in y0..=y1 {
            for x in x0..=x1 {
                d[(y * w + x) as usize] = z;
            }
        }
    }
    d
}

struct Case {
    view: CullView,
    sphere: bool,
    a: Vec3,
    b: Vec3,
    radius: f32,
    pyramid: usize,
}

fn random_case(rng: &mut rand::rngs::SmallRng, pyramids: &[HiZPyramid]) -> Case {
    let pyramid = rng.random_range(0..pyramids.len());
    let size = pyramids[pyramid].base_size();
    let q = Quat::from_xyzw(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let rotation = Mat3::from_quat(if q.length() < 0.1 { Quat::IDENTITY } else { q.normalize() });
    let aspect = 10f32.powf(rng.random_range(-1.0..1.0));
    let near = 10f32.powf(rng.random_range(-4.0..0.5));
    let ortho = rng.random_bool(0.25);
    let mut view = if ortho {
        let height = 10f32.powf(rng.random_range(-1.0..3.0));
        CullView::orthographic(rotation, height, aspect, near, near + 10f32.powf(rng.random_range(0.0..4.0)), size)
    } else {
        let fov = if rng.random_bool(0.1) { 179.0f32 } else { rng.random_range(1.0..179.0) };
        CullView::perspective(rotation, fov.to_radians(), aspect, near, size)
    };
    // Off-centre (a VR eye's, up to a whole view width), a sub-pixel jitter, or neither; a finite
    // far plane for a third of the perspective views.
    view.offset = match rng.random_range(0..3) {
        0 => Vec2::new(rng.random_range(-1.5..1.5), rng.random_range(-1.5..1.5)),
        1 => Vec2::new(rng.random_range(-1.0..1.0) / size.x as f32, rng.random_range(-1.0..1.0) / size.y as f32),
        _ => Vec2::ZERO,
    };
    if !ortho && rng.random_bool(0.33) {
        view.far = near * 10f32.powf(rng.random_range(0.3..4.0));
    }
    let (sx, sy) = (view.scale.x as f64, view.scale.y as f64);
    // NDC position of the center, offset included: t = (ndc.x + cx)/sx, u = (cy − ndc.y)/sy.
    let (nx, ny) =
        (rng.random_range(-1.5..1.5) + view.offset.x as f64, rng.random_range(-1.5..1.5) - view.offset.y as f64);
    let (c, r) = if ortho {
        let d = near as f64 + (view.far - near) as f64 * rng.random_range(-0.05..1.1);
        (DVec3::new(nx / sx, -ny / sy, -d), 10f64.powf(rng.random_range(-3.0..0.5)) / sy)
    } else {
        let d = near as f64 * 10f64.powf(rng.random_range(-0.2..4.0)).min(1.2 * view.far as f64 / near as f64);
        (DVec3::new(nx * d / sx, -ny * d / sy, -d), d * 10f64.powf(rng.random_range(-4.0..0.3)))
    };
    let center = rotation.as_dmat3().transpose() * c;
    let sphere = rng.random_bool(0.5);
    if sphere {
        Case { view, sphere, a: center.as_vec3(), b: Vec3::ZERO, radius: r as f32, pyramid }
    } else {
        let half = DVec3::new(rng.random(), rng.random(), rng.random()) * r;
        Case { view, sphere, a: (center - half).as_vec3(), b: (center + half).as_vec3(), radius: 0.0, pyramid }
    }
}

/// The exact (f64, no allowance) pixel rectangle and nearest depth of a case, when its bound lies
/// in front of the near plane: from the sphere's tangents or the box's corners.
fn exact(case: &Case) -> Option<(Option<[i64; 4]>, f64)> {
    let v = &case.view;
    let r: DMat3 = v.rotation.as_dmat3();
    let (sx, sy) = (v.scale.x as f64, v.scale.y as f64);
    let near = v.near as f64;
    let (mut tx, mut ty, d_min);
    if case.sphere {
        let c = r * case.a.as_dvec3();
        let rad = case.radius as f64;
        let d = -c.z;
        d_min = d - rad;
        if d_min < near {
            return None;
        }
        let tan = |a: f64| {
            if v.orthographic {
                (a - rad, a + rad)
            } else {
                let rho = (a * a + d * d).sqrt();
                let (th, al) = (a.atan2(d), (rad / rho).asin());
                ((th - al).tan(), (th + al).tan())
            }
        };
        tx = tan(c.x);
        ty = tan(c.y);
    } else {
        tx = (f64::INFINITY, f64::NEG_INFINITY);
        ty = tx;
        let mut dm = f64::INFINITY;
        for i in 0..8 {
            let p = DVec3::new(
                if i & 1 == 0 { case.a.x } else { case.b.x } as f64,
                if i & 2 == 0 { case.a.y } else { case.b.y } as f64,
                if i & 4 == 0 { case.a.z } else { case.b.z } as f64,
            );
            let q = r * p;
            dm = dm.min(-q.z);
            let (x, y) = if v.orthographic { (q.x, q.y) } else { (q.x / -q.z, q.y / -q.z) };
            tx = (tx.0.min(x), tx.1.max(x));
            ty = (ty.0.min(y), ty.1.max(y));
        }
        d_min = dm;
        if d_min < near {
            return None;
        }
    }
    let (w, h) = (v.viewport.x as f64, v.viewport.y as f64);
    let (cx, cy) = (v.offset.x as f64, v.offset.y as f64);
    let px = |t: f64| ((sx * t - cx + 1.0) * 0.5 * w).floor();
    let py = |t: f64| ((cy - sy * t + 1.0) * 0.5 * h).floor();
    let (x0, x1, y0, y1) = (px(tx.0), px(tx.1), py(ty.1), py(ty.0));
    let far = v.far as f64;
    let depth = if v.orthographic {
        (far - d_min) / (far - near)
    } else if far.is_finite() {
        near * (far - d_min) / (d_min * (far - near))
    } else {
        near / d_min
    };
    if x1 < 0.0 || y1 < 0.0 || x0 >= w || y0 >= h {
        return Some((None, depth));
    }
    let c = |a: f64, n: f64| a.clamp(0.0, n - 1.0) as i64;
    Some((Some([c(x0, w), c(y0, h), c(x1, w), c(y1, h)]), depth))
}

fn contains(rect: [u32; 4], e: [i64; 4]) -> bool {
    rect[0] as i64 <= e[0] && rect[1] as i64 <= e[1] && rect[2] as i64 >= e[2] && rect[3] as i64 >= e[3]
}

#[test]
fn gpu_and_cpu_make_the_same_decisions() {
    let gpu = GpuTest::new();
    let shaders = gpu.shaders();
    let spirv = shaders.compile_source("test/cull_math_agreement.comp", SHADER, &[]).unwrap_or_else(|e| panic!("{e}"));
    let pipeline = Pipeline::compute(&gpu, "cull math agreement", &spirv).unwrap();

    let mut rng = rand::rngs::SmallRng::seed_from_u64(0xC011_0001);
    let sizes = [(37u32, 23u32), (1, 1), (1, 17), (29, 1), (64, 48), (1023, 767), (5, 3)];
    let pyramids: Vec<HiZPyramid> =
        sizes.iter().map(|&(w, h)| HiZPyramid::from_depth(w, h, &depth_buffer(w, h, &mut rng))).collect();
    let mut texels = vec![];
    let mut table = vec![];
    for p in &pyramids {
        let (flat, offsets) = p.to_flat();
        // The flat layout's offsets are the ones the shader computes.
        for (k, &o) in offsets.iter().enumerate() {
            assert_eq!(o, cullgraph::cull::hiz::level_offset(p.base_size(), k as u32));
        }
        table.push(GpuPyramid { base: p.base_size().to_array(), offset: texels.len() as u32, pad: 0 });
        texels.extend(flat);
    }

    let n = 40_000usize;
    let cases: Vec<Case> = (0..n).map(|_| random_case(&mut rng, &pyramids)).collect();
    let gpu_cases: Vec<GpuCase> = cases
        .iter()
        .map(|c| GpuCase {
            rot: [
                c.view.rotation.x_axis.to_array(),
                c.view.rotation.y_axis.to_array(),
                c.view.rotation.z_axis.to_array(),
            ],
            scale: c.view.scale.to_array(),
            near: c.view.near,
            far: c.view.far,
            ortho: c.view.orthographic as u32,
            viewport: c.view.viewport.to_array(),
            offset: c.view.offset.to_array(),
            kind: (!c.sphere) as u32,
            a: c.a.to_array(),
            b: c.b.to_array(),
            radius: c.radius,
            pyramid: c.pyramid as u32,
        })
        .collect();

    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let mut batch = UploadBatch::default();
    let case_buf = batch.buffer(&gpu, "cases", storage, bytemuck::cast_slice(&gpu_cases)).unwrap();
    let table_buf = batch.buffer(&gpu, "pyramids", storage, bytemuck::cast_slice(&table)).unwrap();
    let texel_buf = batch.buffer(&gpu, "texels", storage, bytemuck::cast_slice(&texels)).unwrap();
    let zeros = vec![GpuResult::default(); n];
    let result_buf = batch
        .buffer(&gpu, "results", storage | vk::BufferUsageFlags::TRANSFER_SRC, bytemuck::cast_slice(&zeros))
        .unwrap();
    gpu.submit_and_wait(|cmd| {
        batch.record(&gpu, cmd);
        pipeline.bind(cmd);
        pipeline.push_bindings(
            cmd,
            &[
                Bind::Buffer(0, case_buf.handle()),
                Bind::Buffer(1, table_buf.handle()),
                Bind::Buffer(2, texel_buf.handle()),
                Bind::Buffer(3, result_buf.handle()),
            ],
        );
        pipeline.push_constants(cmd, &(n as u32));
        unsafe { gpu.device().cmd_dispatch(cmd, (n as u32).div_ceil(64), 1, 1) };
        cullgraph::gpu::GpuResult::Ok(())
    })
    .unwrap();
    let bytes = transfer::read_buffer(&gpu, &result_buf).unwrap();
    let results: &[GpuResult] = bytemuck::cast_slice(&bytes);

    let (mut identical, mut tolerated, mut failures) = (0usize, vec![], vec![]);
    let mut statuses = [0usize; 3];
    let (mut culled_coarse, mut culled_finer) = (0usize, 0usize);
    // On-screen bounds that cover no sample position (the small-object test culls them).
    let mut uncovered = 0usize;
    let (mut depth_diffs, mut max_ulps, mut rect_diffs) = (0usize, 0u32, 0usize);
    for (i, (case, got)) in cases.iter().zip(results).enumerate() {
        let view = &case.view;
        let (frustum, proj) = if case.sphere {
            (cm::sphere_in_frustum(view, case.a, case.radius), cm::project_sphere(view, case.a, case.radius))
        } else {
            (cm::aabb_in_frustum(view, case.a, case.b), cm::project_aabb(view, case.a, case.b))
        };
        let pyramid = &pyramids[case.pyramid];
        let mut want = GpuResult { frustum: frustum as u32, ..Default::default() };
        match proj {
            ScreenBounds::CrossesNear => want.status = 0,
            ScreenBounds::OffScreen => want.status = 1,
            ScreenBounds::OnScreen { rect, nearest_depth, covers_sample } => {
                want.status = 2;
                want.covers = covers_sample as u32;
                uncovered += !covers_sample as usize;
                want.rect = [rect.x0, rect.y0, rect.x1, rect.y1];
                want.depth = nearest_depth;
                want.level = cm::hiz_level(rect);
                want.occ_coarse = is_occluded(pyramid, rect, nearest_depth, HizVariant::Coarse) as u32;
                want.occ_finer = is_occluded(pyramid, rect, nearest_depth, HizVariant::Finer) as u32;
            }
        }
        statuses[want.status as usize] += 1;
        culled_coarse += want.occ_coarse as usize;
        culled_finer += want.occ_finer as usize;
        // Only an on-screen result carries a rectangle and a depth.
        let got = &if got.status == 2 { *got } else { GpuResult { rect: [0; 4], depth: 0.0, ..*got } };
        if *got == want {
            identical += 1;
            continue;
        }
        let describe = || {
            format!(
                "case {i}: {} a={:?} b={:?} r={:e} rot={:?} scale={:?} offset={:?} near={:e} far={:e} ortho={} viewport={:?}\n  cpu {want:?}\n  gpu {got:?}",
                if case.sphere { "sphere" } else { "box" },
                case.a.to_array(),
                case.b.to_array(),
                case.radius,
                view.rotation.to_cols_array(),
                view.scale.to_array(),
                view.offset.to_array(),
                view.near,
                view.far,
                view.orthographic,
                view.viewport.to_array()
            )
        };
        // Differences in the last bits of the rectangle or depth are tolerated when both sides
        // stay conservative and the decisions agree.
        let same_decisions = got.frustum == want.frustum
            && got.status == want.status
            && got.status == 2
            && got.occ_coarse == want.occ_coarse
            && got.occ_finer == want.occ_finer
            && got.covers == want.covers
            && (got.level == want.level || got.rect != want.rect);
        let ex = exact(case);
        let ok = same_decisions
            && match ex {
                Some((rect, depth)) => {
                    let rect_ok = got.rect == want.rect
                        || (rect.is_none_or(|e| contains(got.rect, e) && contains(want.rect, e))
                            && got.rect.iter().zip(&want.rect).all(|(a, b)| a.abs_diff(*b) <= 1));
                    let depth_ok = got.depth.to_bits().abs_diff(want.depth.to_bits()) <= 8
                        && got.depth as f64 >= depth
                        && want.depth as f64 >= depth;
                    rect_ok && depth_ok
                }
                None => false,
            };
        if ok {
            let ulps = got.depth.to_bits().abs_diff(want.depth.to_bits());
            depth_diffs += (ulps != 0) as usize;
            max_ulps = max_ulps.max(ulps);
            rect_diffs += (got.rect != want.rect) as usize;
            tolerated.push(describe());
        } else {
            failures.push(describe());
        }
    }
    println!(
        "{n} cases on {}: {identical} identical, {} tolerated, {} mismatched; crosses near {}, off screen {}, on screen {}; \
         occluded: coarse {culled_coarse}, finer {culled_finer}; covering no sample {uncovered}",
        gpu.caps().name,
        tolerated.len(),
        failures.len(),
        statuses[0],
        statuses[1],
        statuses[2]
    );
    println!(
        "tolerated: {depth_diffs} nearest depths differ (at most {max_ulps} ulps), {rect_diffs} rectangles differ by one pixel"
    );
    for t in tolerated.iter().take(5) {
        println!("tolerated {t}");
    }
    assert!(failures.is_empty(), "{} mismatches:\n{}", failures.len(), failures[..failures.len().min(20)].join("\n"));
    // The cases must exercise every outcome.
    assert!(statuses.iter().all(|&s| s > n / 50), "{statuses:?}");
    assert!(culled_coarse > n / 100 && culled_finer > culled_coarse, "{culled_coarse} {culled_finer}");
    assert!(uncovered > n / 1000, "{uncovered} small bounds");
}

/// The headers compile on their own, in a shader that uses only the projection (no `hiz_load`).
#[test]
fn headers_compile_without_a_pyramid_reader() {
    let gpu = GpuTest::new();
    let source = r#"#version 460
        #include "common/cull_math.glsl"
        layout(local_size_x = 1) in;
        layout(set = 0, binding = 0) buffer Out { uvec4 rect; float depth; uint status; };
        void main() {
            CullView v;
            v.rotation = mat3(1.0);
            v.scale = vec2(1.0);
            v.near = 0.1;
            v.far = 1.0e30;
            v.orthographic = 0u;
            v.viewport = uvec2(64u);
            v.offset = vec2(0.0);
            status = cull_project_sphere(v, vec3(0.0, 0.0, -5.0), 1.0, rect, depth);
        }"#;
    gpu.shaders().compile_source("test/cull_headers.comp", source, &[]).unwrap_or_else(|e| panic!("{e}"));
}
