//! Street furniture, vehicles, trees and buildings assembled from the basic and round shapes.
//! Parts may overlap; each part is closed, so the union renders as a solid.

use super::basic::{chamfered_box, cuboid, pyramid, tent_prism};
use super::round::{cone, cylinder, frustum, icosphere, torus, tube, uv_sphere};
use super::{at, combine, Builder};
use crate::scene::mesh::MeshData;
use glam::{Mat4, Vec3};
use std::f32::consts::{FRAC_PI_2, PI};

/// A masonry arch `width` wide and `height` tall, `depth` thick: two pillars and a semicircular
/// vault of `segments` voussoirs; the opening is 64% of the width.
pub fn arch(width: f32, height: f32, depth: f32, segments: u32) -> MeshData {
    let width = width.max(0.1);
    let outer = width * 0.5;
    let inner = outer * 0.64;
    let spring = (height - outer).max(0.1);
    let depth = depth.max(0.01);
    let pillar = outer - inner;
    let mut parts = vec![
        (cuboid(Vec3::new(pillar, spring, depth)), at(-(inner + pillar * 0.5), 0.0, 0.0)),
        (cuboid(Vec3::new(pillar, spring, depth)), at(inner + pillar * 0.5, 0.0, 0.0)),
    ];
    let segments = segments.max(2);
    let mut b = Builder::default();
    for i in 0..segments {
        let (a0, a1) = (PI * i as f32 / segments as f32, PI * (i + 1) as f32 / segments as f32);
        let mut corners = Vec::with_capacity(8);
        for a in [a0, a1] {
            for r in [inner, outer] {
                for z in [-depth * 0.5, depth * 0.5] {
                    corners.push(Vec3::new(r * a.cos(), spring + r * a.sin(), z));
                }
            }
        }
        let inside = corners.iter().copied().sum::<Vec3>() / 8.0;
        // Faces: front, back, inner (intrados), outer (extrados), the two joints.
        for face in [[0, 2, 4, 6], [1, 3, 5, 7], [0, 1, 4, 5], [2, 3, 6, 7], [0, 1, 2, 3], [4, 5, 6, 7]] {
            b.convex_face(&face.map(|k| corners[k]), inside);
        }
    }
    parts.push((b.build(), Mat4::IDENTITY));
    combine(&parts)
}

/// A flight of `steps` solid steps, `width` wide, each `rise` high and `run` deep, climbing
/// towards -z.
pub fn stairs(steps: u32, width: f32, rise: f32, run: f32) -> MeshData {
    let steps = steps.clamp(1, 256);
    let (rise, run) = (rise.max(0.01), run.max(0.01));
    let start = steps as f32 * run * 0.5;
    let parts: Vec<(MeshData, Mat4)> = (0..steps)
        .map(|k| {
            let z = start - (k as f32 + 0.5) * run;
            (cuboid(Vec3::new(width, rise * (k + 1) as f32, run)), at(0.0, 0.0, z))
        })
        .collect();
    combine(&parts)
}

/// Where the light of a [`lamp_post`] of `height` sits, relative to the post's origin.
pub fn lamp_head(height: f32) -> Vec3 {
    Vec3::new(1.1, height.max(2.0) - 0.25, 0.0)
}

/// A street lamp: foot, pole, an arm along +x and a lamp head at [`lamp_head`].
pub fn lamp_post(height: f32, segments: u32) -> MeshData {
    let h = height.max(2.0);
    combine(&[
        (frustum(0.2, 0.12, 0.5, segments), Mat4::IDENTITY),
        (cylinder(0.08, h, segments), Mat4::IDENTITY),
        (cuboid(Vec3::new(1.3, 0.08, 0.08)), at(0.6, h - 0.12, 0.0)),
        (chamfered_box(Vec3::new(0.55, 0.18, 0.3), 0.04), at(1.1, h - 0.34, 0.0)),
    ])
}

/// A bollard: a post with a dome, `height` tall.
pub fn bollard(radius: f32, height: f32, segments: u32) -> MeshData {
    let r = radius.max(0.01);
    let h = height.max(3.0 * r);
    combine(&[
        (cylinder(r, h - r, segments), Mat4::IDENTITY),
        (uv_sphere(r, segments, segments / 2 + 2), at(0.0, h - 2.0 * r, 0.0)),
    ])
}

/// A park bench `length` long: seat, backrest and two side legs.
pub fn bench(length: f32) -> MeshData {
    let l = length.max(0.5);
    combine(&[
        (cuboid(Vec3::new(l, 0.07, 0.45)), at(0.0, 0.42, 0.0)),
        (cuboid(Vec3::new(l, 0.4, 0.06)), at(0.0, 0.5, -0.2)),
        (cuboid(Vec3::new(0.06, 0.9, 0.5)), at(-l * 0.5 + 0.1, 0.0, 0.0)),
        (cuboid(Vec3::new(0.06, 0.9, 0.5)), at(l * 0.5 - 0.1, 0.0, 0.0)),
    ])
}

/// A conifer: trunk and three stacked cones, `height` tall.
pub fn tree_conifer(height: f32, segments: u32) -> MeshData {
    let h = height.max(1.0);
    combine(&[
        (cylinder(0.04 * h, 0.3 * h, segments), Mat4::IDENTITY),
        (cone(0.28 * h, 0.45 * h, segments), at(0.0, 0.2 * h, 0.0)),
        (cone(0.22 * h, 0.4 * h, segments), at(0.0, 0.4 * h, 0.0)),
        (cone(0.15 * h, 0.35 * h, segments), at(0.0, 0.65 * h, 0.0)),
    ])
}

/// A deciduous tree: trunk and an icosphere crown, `height` tall.
pub fn tree_round(height: f32, subdivisions: u32) -> MeshData {
    let h = height.max(1.0);
    combine(&[
        (cylinder(0.05 * h, 0.5 * h, 8), Mat4::IDENTITY),
        (icosphere(0.3 * h, subdivisions), at(0.0, 0.4 * h, 0.0)),
    ])
}

/// A stack of chamfered 0.8 m crates, `layers` high (a pyramid in a row).
pub fn crate_stack(layers: u32) -> MeshData {
    let layers = layers.clamp(1, 16);
    let mut parts = Vec::new();
    for l in 0..layers {
        let count = layers - l;
        for k in 0..count {
            let x = (k as f32 - (count - 1) as f32 * 0.5) * 0.85;
            parts.push((chamfered_box(Vec3::splat(0.8), 0.05), at(x, l as f32 * 0.8, 0.0)));
        }
    }
    combine(&parts)
}

/// A fence segment `length` long along x with `posts` posts (at least 2) and two rails.
pub fn fence(length: f32, posts: u32) -> MeshData {
    let l = length.max(0.5);
    let posts = posts.clamp(2, 64);
    let mut parts: Vec<(MeshData, Mat4)> = (0..posts)
        .map(|k| {
            let x = -l * 0.5 + l * k as f32 / (posts - 1) as f32;
            (cuboid(Vec3::new(0.1, 1.1, 0.1)), at(x, 0.0, 0.0))
        })
        .collect();
    for y in [0.35, 0.8] {
        parts.push((cuboid(Vec3::new(l, 0.08, 0.05)), at(0.0, y, 0.06)));
    }
    combine(&parts)
}

/// A car `length` along x, `width` along z and `height` tall: body, cabin and four wheels.
pub fn car(length: f32, width: f32, height: f32, wheel_segments: u32) -> MeshData {
    let (l, w, h) = (length.max(1.0), width.max(0.5), height.max(0.6));
    let wheel_r = 0.2 * h.min(l * 0.25);
    let wheel_w = 0.12 * w;
    // A cylinder turned to roll along x (axis along z), centred on z.
    let wheel = |x: f32, z: f32| {
        Mat4::from_translation(Vec3::new(x, wheel_r, z - wheel_w * 0.5)) * Mat4::from_rotation_x(FRAC_PI_2)
    };
    let mut parts = vec![
        (chamfered_box(Vec3::new(l, 0.45 * h, w), 0.08 * h), at(0.0, 0.18 * h, 0.0)),
        (chamfered_box(Vec3::new(0.55 * l, 0.37 * h, 0.88 * w), 0.1 * h), at(-0.05 * l, 0.63 * h, 0.0)),
    ];
    for x in [-0.32 * l, 0.32 * l] {
        for z in [-(w * 0.5 - wheel_w * 0.5), w * 0.5 - wheel_w * 0.5] {
            parts.push((cylinder(wheel_r, wheel_w, wheel_segments), wheel(x, z)));
        }
    }
    // The wheels are polygons: set the lowest wheel vertex, not the ideal circle, on the ground.
    let mut car = combine(&parts);
    let lowest = car.positions.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    for p in &mut car.positions {
        p.y -= lowest;
    }
    car
}

/// A fire hydrant: body, dome and two side outlets.
pub fn hydrant(segments: u32) -> MeshData {
    let outlet = |dir: f32| Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)) * Mat4::from_rotation_z(-dir * FRAC_PI_2);
    combine(&[
        (cylinder(0.16, 0.06, segments), Mat4::IDENTITY),
        (cylinder(0.11, 0.62, segments), Mat4::IDENTITY),
        (uv_sphere(0.11, segments, segments / 2 + 2), at(0.0, 0.52, 0.0)),
        (cylinder(0.045, 0.2, segments), outlet(1.0)),
        (cylinder(0.045, 0.2, segments), outlet(-1.0)),
    ])
}

/// A trash can: tapered body, lid and a ring handle.
pub fn trash_can(segments: u32) -> MeshData {
    combine(&[
        (frustum(0.24, 0.28, 0.85, segments), Mat4::IDENTITY),
        (cylinder(0.3, 0.05, segments), at(0.0, 0.85, 0.0)),
        (torus(0.08, 0.02, segments, 6), at(0.0, 0.9, 0.0)),
    ])
}

/// A round planter of diameter `size`: a pipe wall, soil and a shrub.
pub fn planter(size: f32, segments: u32) -> MeshData {
    let r = size.max(0.2) * 0.5;
    combine(&[
        (tube(r * 0.85, r, 0.5, segments), Mat4::IDENTITY),
        (cylinder(r * 0.86, 0.42, segments), Mat4::IDENTITY),
        (icosphere(r * 0.7, 1), at(0.0, 0.3, 0.0)),
    ])
}

/// A street sign: a pole `height` tall with a rectangular and a diamond plate.
pub fn street_sign(height: f32) -> MeshData {
    let h = height.max(1.0);
    let diamond = Mat4::from_translation(Vec3::new(0.0, h - 0.95, 0.04)) * Mat4::from_rotation_z(PI * 0.25);
    combine(&[
        (cylinder(0.035, h, 8), Mat4::IDENTITY),
        (cuboid(Vec3::new(0.7, 0.22, 0.03)), at(0.0, h - 0.3, 0.04)),
        (cuboid(Vec3::new(0.4, 0.4, 0.03)), diamond * Mat4::from_translation(Vec3::new(0.0, -0.2, 0.0))),
    ])
}

/// A traffic cone on a square foot.
pub fn traffic_cone(segments: u32) -> MeshData {
    combine(&[(cuboid(Vec3::new(0.4, 0.04, 0.4)), Mat4::IDENTITY), (cone(0.15, 0.7, segments), Mat4::IDENTITY)])
}

/// A unit-footprint (1 x 1), unit-height building of `tiers` setback tiers; scale it per instance.
pub fn building_stepped(tiers: u32) -> MeshData {
    let tiers = tiers.clamp(1, 8);
    let mut parts = Vec::new();
    let mut y = 0.0;
    for t in 0..tiers {
        let f = 1.0 - 0.22 * t as f32;
        let h = if t + 1 == tiers { 1.0 - y } else { (1.0 - y) * 0.6 };
        parts.push((cuboid(Vec3::new(f, h + 0.001, f)), at(0.0, y, 0.0)));
        y += h;
    }
    combine(&parts)
}

/// A unit building (1 x 1 x 1) whose top `roof` fraction is a gable roof; scale it per instance.
pub fn building_roofed(roof: f32) -> MeshData {
    let roof = roof.clamp(0.05, 0.9);
    combine(&[
        (cuboid(Vec3::new(1.0, 1.0 - roof + 0.001, 1.0)), Mat4::IDENTITY),
        (tent_prism(1.04, roof, 1.04), at(0.0, 1.0 - roof, 0.0)),
    ])
}

/// A kiosk: a prism body of `sides` sides (5 to 12) with a pyramid roof.
pub fn kiosk(sides: u32) -> MeshData {
    combine(&[
        (super::basic::prism(sides.clamp(5, 12), 1.0, 2.4), Mat4::IDENTITY),
        (pyramid(2.4, 2.4, 0.8), at(0.0, 2.4, 0.0)),
    ])
}
