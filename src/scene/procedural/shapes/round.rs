//! Surfaces of revolution about the y axis (cylinder, cone, frustum, spheres, capsule, torus,
//! tube) and the icosphere.

use super::Builder;
use crate::scene::mesh::MeshData;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

/// A smooth run of a profile: points `(r, y)` with their outward normals `(nr, ny)`.
type Run = Vec<(Vec2, Vec2)>;

/// Revolves a profile around the y axis with `segments` steps. Each run must go
/// counter-clockwise around the solid's cross-section in the (r, y) half-plane (the outward
/// normal on the right of the direction of travel); runs meet at hard edges.
fn lathe(runs: &[Run], segments: u32) -> MeshData {
    let segments = segments.max(3);
    let angles: Vec<Vec2> = (0..segments).map(|i| Vec2::from_angle(TAU * i as f32 / segments as f32)).collect();
    let mut b = Builder::default();
    for run in runs {
        let rows: Vec<Vec<u32>> = run
            .iter()
            .map(|(p, n)| {
                let n = n.normalize_or_zero();
                angles
                    .iter()
                    .map(|a| b.vertex(Vec3::new(p.x * a.x, p.y, p.x * a.y), Vec3::new(n.x * a.x, n.y, n.x * a.y)))
                    .collect()
            })
            .collect();
        for k in 0..run.len().saturating_sub(1) {
            let (lower_on_axis, upper_on_axis) = (run[k].0.x <= 0.0, run[k + 1].0.x <= 0.0);
            for i in 0..segments as usize {
                let j = (i + 1) % segments as usize;
                let [a, bb, c, d] = [rows[k][i], rows[k + 1][i], rows[k + 1][j], rows[k][j]];
                if !upper_on_axis {
                    b.triangle(a, bb, c);
                }
                if !lower_on_axis {
                    b.triangle(a, c, d);
                }
            }
        }
    }
    b.build()
}

/// A straight run from `a` to `b` with the outward normal of that direction.
fn segment(a: Vec2, b: Vec2) -> Run {
    let d = b - a;
    let n = Vec2::new(d.y, -d.x);
    vec![(a, n), (b, n)]
}

/// A frustum (truncated cone) with bottom radius `r_bottom`, top radius `r_top` (0 gives a cone)
/// and `height`, with flat caps.
pub fn frustum(r_bottom: f32, r_top: f32, height: f32, segments: u32) -> MeshData {
    let (rb, rt, h) = (r_bottom.max(1e-3), r_top.max(0.0), height.max(1e-3));
    let mut runs = vec![segment(Vec2::ZERO, Vec2::new(rb, 0.0)), segment(Vec2::new(rb, 0.0), Vec2::new(rt, h))];
    if rt > 0.0 {
        runs.push(segment(Vec2::new(rt, h), Vec2::new(0.0, h)));
    }
    lathe(&runs, segments)
}

/// A capped cylinder.
pub fn cylinder(radius: f32, height: f32, segments: u32) -> MeshData {
    frustum(radius, radius, height, segments)
}

/// A cone with a flat base.
pub fn cone(radius: f32, height: f32, segments: u32) -> MeshData {
    frustum(radius, 0.0, height, segments)
}

/// A smooth arc of a circle around `center` from angle `from` to `to` (counter-clockwise when
/// `to > from`), in `steps` pieces.
fn arc(center: Vec2, radius: f32, from: f32, to: f32, steps: u32) -> Run {
    (0..=steps.max(1))
        .map(|i| {
            let dir = Vec2::from_angle(from + (to - from) * i as f32 / steps.max(1) as f32);
            (center + dir * radius, dir)
        })
        .collect()
}

/// A UV sphere resting on y = 0 with `rings` latitude bands.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> MeshData {
    let r = radius.max(1e-3);
    lathe(&[arc(Vec2::new(0.0, r), r, -FRAC_PI_2, FRAC_PI_2, rings.max(2))], segments)
}

/// A capsule of total `height` (at least `2 * radius`): a cylinder with hemispherical ends of
/// `rings` bands each.
pub fn capsule(radius: f32, height: f32, segments: u32, rings: u32) -> MeshData {
    let r = radius.max(1e-3);
    let h = height.max(2.0 * r + 1e-3);
    let mut run = arc(Vec2::new(0.0, r), r, -FRAC_PI_2, 0.0, rings.max(1));
    run.extend(arc(Vec2::new(0.0, h - r), r, 0.0, FRAC_PI_2, rings.max(1)));
    lathe(&[run], segments)
}

/// A torus lying flat (axis y): ring radius `major`, tube radius `minor`.
pub fn torus(major: f32, minor: f32, segments: u32, tube_segments: u32) -> MeshData {
    let minor = minor.max(1e-3);
    let major = major.max(minor * 1.01);
    lathe(&[arc(Vec2::new(major, minor), minor, -PI, PI, tube_segments.max(3))], segments)
}

/// A hollow cylinder (pipe): radii `inner` < `outer`, capped with flat rings.
pub fn tube(inner: f32, outer: f32, height: f32, segments: u32) -> MeshData {
    let outer = outer.max(2e-3);
    let inner = inner.clamp(1e-3, outer * 0.98);
    let h = height.max(1e-3);
    let (a, b, c, d) = (Vec2::new(inner, 0.0), Vec2::new(outer, 0.0), Vec2::new(outer, h), Vec2::new(inner, h));
    lathe(&[segment(a, b), segment(b, c), segment(c, d), segment(d, a)], segments)
}

/// An icosphere resting on y = 0: an icosahedron subdivided `subdivisions` times (at most 5).
pub fn icosphere(radius: f32, subdivisions: u32) -> MeshData {
    let r = radius.max(1e-3);
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut points: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from_array(*p).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions.min(5) {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, points: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                points.push(((points[a as usize] + points[b as usize]) * 0.5).normalize());
                points.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let (ab, bc, ca) = (mid(a, b, &mut points), mid(b, c, &mut points), mid(c, a, &mut points));
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    MeshData {
        positions: points.iter().map(|p| *p * r + Vec3::new(0.0, r, 0.0)).collect(),
        normals: points,
        indices: faces.into_iter().flatten().collect(),
        ..Default::default()
    }
}
