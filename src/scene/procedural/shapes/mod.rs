//! Parameterised mesh kinds for the generators, as [`MeshData`] triangle lists.
//!
//! Conventions for every shape: right-handed, +Y up, counter-clockwise front faces seen from
//! outside, outward unit normals, closed surfaces (except [`ground`]), and the shape stands on
//! the y = 0 plane centred on the y axis, so a generator places it with a translation on the
//! ground. Sizes are in meters. Segment counts are clamped to sane minima, so every parameter
//! choice gives a valid mesh.

mod basic;
mod composite;
mod round;

pub use basic::{chamfered_box, cuboid, ground, prism, pyramid, tent_prism, wedge};
pub use composite::{
    arch, bench, bollard, building_roofed, building_stepped, car, crate_stack, fence, hydrant, kiosk, lamp_head,
    lamp_post, planter, stairs, street_sign, traffic_cone, trash_can, tree_conifer, tree_round,
};
pub use round::{capsule, cone, cylinder, frustum, icosphere, torus, tube, uv_sphere};

use crate::scene::mesh::MeshData;
use glam::{Mat3, Mat4, Vec3};

/// Accumulates triangles; faces are added with their outward normals.
#[derive(Default)]
pub(crate) struct Builder {
    data: MeshData,
}

impl Builder {
    /// Adds a vertex and returns its index.
    pub(crate) fn vertex(&mut self, position: Vec3, normal: Vec3) -> u32 {
        self.data.positions.push(position);
        self.data.normals.push(normal);
        self.data.positions.len() as u32 - 1
    }

    /// Adds a triangle of existing vertices (counter-clockwise from the front).
    pub(crate) fn triangle(&mut self, a: u32, b: u32, c: u32) {
        self.data.indices.extend_from_slice(&[a, b, c]);
    }

    /// Adds a flat convex polygon, wound so that it faces away from `inside` (a point on the
    /// inner side of its plane). The points may come in any order.
    pub(crate) fn convex_face(&mut self, points: &[Vec3], inside: Vec3) {
        let centroid = points.iter().copied().sum::<Vec3>() / points.len() as f32;
        // Newell-free normal: the largest cross product of two spokes from the centroid.
        let mut normal = Vec3::ZERO;
        for p in points {
            for q in points {
                let c = (*p - centroid).cross(*q - centroid);
                if c.length_squared() > normal.length_squared() {
                    normal = c;
                }
            }
        }
        let mut normal = normal.normalize_or_zero();
        if normal.dot(centroid - inside) < 0.0 {
            normal = -normal;
        }
        let u = (points[0] - centroid).normalize_or_zero();
        let v = normal.cross(u);
        let mut sorted: Vec<Vec3> = points.to_vec();
        sorted.sort_by(|a, b| {
            let angle = |p: &Vec3| (*p - centroid).dot(v).atan2((*p - centroid).dot(u));
            angle(a).total_cmp(&angle(b))
        });
        let first = self.vertex(sorted[0], normal);
        let mut prev = self.vertex(sorted[1], normal);
        for p in &sorted[2..] {
            let next = self.vertex(*p, normal);
            self.triangle(first, prev, next);
            prev = next;
        }
    }

    /// Adds `part` transformed by `m` (an affine map; a mirroring one flips the winding back).
    pub(crate) fn append(&mut self, part: &MeshData, m: Mat4) {
        let base = self.data.positions.len() as u32;
        let linear = Mat3::from_mat4(m);
        let normal_matrix = linear.inverse().transpose();
        for (i, p) in part.positions.iter().enumerate() {
            let n = part.normals.get(i).copied().unwrap_or(Vec3::Y);
            self.data.positions.push(m.transform_point3(*p));
            self.data.normals.push(normal_matrix.mul_vec3(n).normalize_or_zero());
        }
        let flip = linear.determinant() < 0.0;
        for t in part.indices.chunks_exact(3) {
            if flip {
                self.triangle(base + t[0], base + t[2], base + t[1]);
            } else {
                self.triangle(base + t[0], base + t[1], base + t[2]);
            }
        }
    }

    /// The finished mesh.
    pub(crate) fn build(self) -> MeshData {
        self.data
    }
}

/// Joins parts, each placed by its transform, into one mesh.
pub fn combine(parts: &[(MeshData, Mat4)]) -> MeshData {
    let mut b = Builder::default();
    for (part, m) in parts {
        b.append(part, *m);
    }
    b.build()
}

/// Translation shorthand for composite shapes.
pub(crate) fn at(x: f32, y: f32, z: f32) -> Mat4 {
    Mat4::from_translation(Vec3::new(x, y, z))
}

/// A named constructor of a mesh kind, for listing and testing every shape.
pub type ShapeFn = fn() -> MeshData;

/// Every shape kind with typical parameters, by name (at least 16 distinct kinds).
pub fn catalogue() -> Vec<(&'static str, ShapeFn)> {
    vec![
        ("cuboid", || cuboid(Vec3::new(1.0, 2.0, 3.0))),
        ("chamfered_box", || chamfered_box(Vec3::new(2.0, 1.0, 1.5), 0.15)),
        ("cylinder", || cylinder(0.5, 2.0, 16)),
        ("cone", || cone(0.7, 1.5, 12)),
        ("frustum", || frustum(1.0, 0.4, 1.2, 10)),
        ("uv_sphere", || uv_sphere(1.0, 16, 8)),
        ("icosphere", || icosphere(1.0, 2)),
        ("torus", || torus(1.0, 0.3, 16, 8)),
        ("capsule", || capsule(0.4, 2.0, 12, 4)),
        ("pyramid", || pyramid(2.0, 2.0, 1.5)),
        ("prism", || prism(6, 1.0, 1.0)),
        ("tent_prism", || tent_prism(2.0, 1.0, 3.0)),
        ("wedge", || wedge(Vec3::new(2.0, 1.0, 3.0))),
        ("tube", || tube(0.6, 1.0, 2.0, 16)),
        ("arch", || arch(4.0, 4.0, 1.0, 12)),
        ("stairs", || stairs(5, 2.0, 0.2, 0.3)),
        ("lamp_post", || lamp_post(6.0, 10)),
        ("bollard", || bollard(0.15, 1.0, 10)),
        ("bench", || bench(1.8)),
        ("tree_conifer", || tree_conifer(6.0, 10)),
        ("tree_round", || tree_round(5.0, 1)),
        ("crate_stack", || crate_stack(3)),
        ("fence", || fence(4.0, 3)),
        ("car", || car(4.2, 1.8, 1.5, 10)),
        ("hydrant", || hydrant(10)),
        ("trash_can", || trash_can(12)),
        ("planter", || planter(1.2, 12)),
        ("street_sign", || street_sign(2.6)),
        ("traffic_cone", || traffic_cone(10)),
        ("building_stepped", || building_stepped(3)),
        ("building_roofed", || building_roofed(0.4)),
        ("kiosk", || kiosk(6)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six times the signed volume: positive for a closed mesh with outward winding.
    fn signed_volume(m: &MeshData) -> f32 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                a.dot(b.cross(c))
            })
            .sum::<f32>()
            / 6.0
    }

    #[test]
    fn every_shape_is_valid_outward_and_on_the_ground() {
        let shapes = catalogue();
        assert!(shapes.len() >= 16);
        for (name, make) in shapes {
            let m = make();
            m.validate(name).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(m.normals.len(), m.positions.len(), "{name}");
            let volume = signed_volume(&m);
            assert!(volume > 0.0, "{name}: signed volume {volume} (inward winding?)");
            // Every triangle's winding agrees with its vertices' normals.
            for (k, t) in m.indices.chunks_exact(3).enumerate() {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                let face = (b - a).cross(c - a);
                if face.length() < 1e-7 {
                    continue;
                }
                let n: Vec3 = [t[0], t[1], t[2]].iter().map(|&i| m.normals[i as usize]).sum();
                assert!(face.dot(n) > 0.0, "{name}: triangle {k} faces against its normals");
            }
            let min_y = m.positions.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
            assert!(min_y.abs() < 1e-4, "{name}: lowest point at y = {min_y}, not on the ground");
            for n in &m.normals {
                assert!((n.length() - 1.0).abs() < 1e-3, "{name}: normal {n} is not unit");
            }
        }
    }

    #[test]
    fn ground_faces_up() {
        let g = ground(10.0);
        g.validate("ground").unwrap();
        assert!(g.normals.iter().all(|n| *n == Vec3::Y));
        let [a, b, c] = [0, 1, 2].map(|i| g.positions[g.indices[i] as usize]);
        assert!((b - a).cross(c - a).y > 0.0);
    }

    #[test]
    fn mirrored_append_keeps_outward_winding() {
        let m = combine(&[(cuboid(Vec3::ONE), Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)))]);
        assert!(signed_volume(&m) > 0.0);
    }
}
