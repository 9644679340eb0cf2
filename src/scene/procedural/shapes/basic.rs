//! Flat-shaded polyhedra: boxes, chamfered boxes, pyramids, prisms, wedges, the ground quad.

use super::Builder;
use crate::scene::mesh::MeshData;
use glam::{Vec2, Vec3};
use std::f32::consts::TAU;

/// A convex polyhedron from its corner points and its faces (lists of corner indices, any order).
fn polyhedron(points: &[Vec3], faces: &[&[usize]]) -> MeshData {
    let inside = points.iter().copied().sum::<Vec3>() / points.len() as f32;
    let mut b = Builder::default();
    for face in faces {
        let corners: Vec<Vec3> = face.iter().map(|&i| points[i]).collect();
        b.convex_face(&corners, inside);
    }
    b.build()
}

/// A box of `size`, standing on y = 0.
pub fn cuboid(size: Vec3) -> MeshData {
    let size = size.max(Vec3::splat(1e-3));
    let h = size * 0.5;
    let points: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { 0.0 } else { size.y },
                if i & 4 == 0 { -h.z } else { h.z },
            )
        })
        .collect();
    polyhedron(&points, &[&[0, 2, 4, 6], &[1, 3, 5, 7], &[0, 1, 4, 5], &[2, 3, 6, 7], &[0, 1, 2, 3], &[4, 5, 6, 7]])
}

/// A box of `size` whose 12 edges are cut by flat bevels of width `bevel` (standing on y = 0).
pub fn chamfered_box(size: Vec3, bevel: f32) -> MeshData {
    let size = size.max(Vec3::splat(1e-2));
    let h = size * 0.5;
    let bevel = bevel.clamp(1e-3, h.min_element() * 0.9);
    let inner = h - Vec3::splat(bevel);
    let lift = Vec3::new(0.0, h.y, 0.0);
    let mut b = Builder::default();
    let signs = [-1.0f32, 1.0];
    // Point on the face of `axis` (pushed out to h) with the other coordinates at `inner`.
    let on_face = |axis: usize, s: Vec3| {
        let mut p = inner * s;
        p[axis] = h[axis] * s[axis];
        p + lift
    };
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for sa in signs {
            // Main face.
            let mut face = Vec::new();
            for su in signs {
                for sv in signs {
                    let mut s = Vec3::ZERO;
                    s[axis] = sa;
                    s[u] = su;
                    s[v] = sv;
                    face.push(on_face(axis, s));
                }
            }
            b.convex_face(&face, lift);
            // Edge bevels between this face and the face of axis `u`.
            for su in signs {
                let mut quad = Vec::new();
                for sv in signs {
                    let mut s = Vec3::ZERO;
                    s[axis] = sa;
                    s[u] = su;
                    s[v] = sv;
                    quad.push(on_face(axis, s));
                    quad.push(on_face(u, s));
                }
                b.convex_face(&quad, lift);
            }
        }
    }
    // Corner triangles.
    for i in 0..8 {
        let s = Vec3::new(signs[i & 1], signs[(i >> 1) & 1], signs[(i >> 2) & 1]);
        b.convex_face(&[on_face(0, s), on_face(1, s), on_face(2, s)], lift);
    }
    b.build()
}

/// A pyramid with a `width` x `depth` base and its apex `height` above the base center.
pub fn pyramid(width: f32, depth: f32, height: f32) -> MeshData {
    let (w, d, hgt) = (width.max(1e-3) * 0.5, depth.max(1e-3) * 0.5, height.max(1e-3));
    let points = [
        Vec3::new(-w, 0.0, -d),
        Vec3::new(w, 0.0, -d),
        Vec3::new(w, 0.0, d),
        Vec3::new(-w, 0.0, d),
        Vec3::new(0.0, hgt, 0.0),
    ];
    polyhedron(&points, &[&[0, 1, 2, 3], &[0, 1, 4], &[1, 2, 4], &[2, 3, 4], &[3, 0, 4]])
}

/// A vertical prism over a regular polygon of `sides` (at least 3) with circumradius `radius`.
pub fn prism(sides: u32, radius: f32, height: f32) -> MeshData {
    let sides = sides.max(3) as usize;
    let outline: Vec<Vec2> =
        (0..sides).map(|i| Vec2::from_angle(TAU * i as f32 / sides as f32) * radius.max(1e-3)).collect();
    extrude_up(&outline, height)
}

/// A convex outline in the x/z plane (x, z pairs) extruded from y = 0 to `height`.
fn extrude_up(outline: &[Vec2], height: f32) -> MeshData {
    let n = outline.len();
    let height = height.max(1e-3);
    let mut points: Vec<Vec3> = outline.iter().map(|p| Vec3::new(p.x, 0.0, p.y)).collect();
    points.extend(outline.iter().map(|p| Vec3::new(p.x, height, p.y)));
    let bottom: Vec<usize> = (0..n).collect();
    let top: Vec<usize> = (n..2 * n).collect();
    let sides: Vec<[usize; 4]> = (0..n).map(|i| [i, (i + 1) % n, n + i, n + (i + 1) % n]).collect();
    let mut faces: Vec<&[usize]> = vec![&bottom, &top];
    faces.extend(sides.iter().map(|s| s.as_slice()));
    polyhedron(&points, &faces)
}

/// A triangular prism lying along z: a tent or gable roof, `width` wide, `height` tall,
/// `length` long.
pub fn tent_prism(width: f32, height: f32, length: f32) -> MeshData {
    let (w, h, l) = (width.max(1e-3) * 0.5, height.max(1e-3), length.max(1e-3) * 0.5);
    let points = [
        Vec3::new(-w, 0.0, -l),
        Vec3::new(w, 0.0, -l),
        Vec3::new(0.0, h, -l),
        Vec3::new(-w, 0.0, l),
        Vec3::new(w, 0.0, l),
        Vec3::new(0.0, h, l),
    ];
    polyhedron(&points, &[&[0, 1, 2], &[3, 4, 5], &[0, 1, 3, 4], &[1, 2, 4, 5], &[0, 2, 3, 5]])
}

/// A ramp: `size.x` wide, rising from y = 0 at +z to `size.y` at -z, `size.z` deep.
pub fn wedge(size: Vec3) -> MeshData {
    let s = size.max(Vec3::splat(1e-3));
    let (w, d) = (s.x * 0.5, s.z * 0.5);
    let points = [
        Vec3::new(-w, 0.0, -d),
        Vec3::new(w, 0.0, -d),
        Vec3::new(-w, 0.0, d),
        Vec3::new(w, 0.0, d),
        Vec3::new(-w, s.y, -d),
        Vec3::new(w, s.y, -d),
    ];
    polyhedron(&points, &[&[0, 1, 2, 3], &[0, 1, 4, 5], &[2, 3, 4, 5], &[0, 2, 4], &[1, 3, 5]])
}

/// A square of side `size` at y = 0 facing +Y (open; the only shape that is not closed).
pub fn ground(size: f32) -> MeshData {
    let h = size.max(1e-3) * 0.5;
    MeshData {
        positions: vec![Vec3::new(-h, 0.0, -h), Vec3::new(-h, 0.0, h), Vec3::new(h, 0.0, h), Vec3::new(h, 0.0, -h)],
        normals: vec![Vec3::Y; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        ..Default::default()
    }
}
