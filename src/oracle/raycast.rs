//! Exact visibility by ray casting: which instance each pixel sample sees, without any culling.
//!
//! All instances' triangles are placed in world space in `f64`, made relative to the camera eye
//! and cast to `f32` (as the GPU sees them after the hi/lo subtraction), and put into one
//! `obvhs` compressed wide BVH. Each pixel sample casts a primary ray through the same projection
//! the rasterizer uses, off-centre offset and jitter included ([`CullView::from_camera`]):
//! perspective rays start at the eye and are parameterised by view distance `d` (direction with
//! view-space `z = −1`), so `t ∈ [near, far]` (`far` infinite or not) is exactly the unclipped
//! range; orthographic rays start on the eye plane and run over `t ∈ [near, far]`.
//!
//! The ray–triangle test is watertight (Woop, Benthin & Wald 2013, with the `f64` fallback for
//! edge functions that round to zero), so a ray through a shared edge never slips between two
//! triangles. Triangles of zero area and non-finite ones are skipped (the rasterizer draws
//! nothing for them), and so are the faces the rasterizer culls: back faces of one-sided
//! materials, with the winding flipped for mirrored instances ([`FaceCull`]). Transparent
//! (alphaMode BLEND) triangles are skipped too: they occlude nothing, and this oracle reports
//! only opaque surfaces (the GPU id oracle, `oracle::visibility`, reports transparent
//! instances seen in front of them). Limits of
//! "exact": a sample within the rasterizer's sub-pixel snapping distance of an edge may resolve
//! differently, and exact depth ties between instances go to whichever the traversal meets
//! first, where the rasterizer would follow draw order.

use crate::cull::CullView;
use crate::passes::shared::face_cull::FaceCull;
use crate::scene::Scene;
use crate::{Error, Result};
use glam::{DMat3, DVec3, Vec3A};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::collections::BTreeSet;
use std::time::{Duration, Instant};

/// Sample id of a sample that hits nothing.
pub const NO_INSTANCE: u32 = u32::MAX;

/// Vulkan's standard 4× sample positions within a pixel.
pub const STANDARD_4X: [(f32, f32); 4] = [(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)];

/// Where in each pixel rays are cast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplePattern {
    /// One ray through the pixel center (0.5, 0.5), as 1× rasterization samples.
    Center,
    /// Four rays at [`STANDARD_4X`], as 4× MSAA samples.
    Standard4x,
}

impl SamplePattern {
    /// Sample positions within the pixel, in pixel units.
    pub fn positions(&self) -> &'static [(f32, f32)] {
        match self {
            SamplePattern::Center => &[(0.5, 0.5)],
            SamplePattern::Standard4x => &STANDARD_4X,
        }
    }
}

/// Per-sample visibility of one view.
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityImage {
    /// Pixels per row.
    pub width: u32,
    /// Rows (row 0 at the top).
    pub height: u32,
    /// Samples per pixel.
    pub samples: u32,
    /// Instance seen by each sample, `[(y·width + x)·samples + s]`; [`NO_INSTANCE`] for none.
    pub ids: Vec<u32>,
    /// Reversed-Z depth of each sample's hit (0 where nothing is hit), same layout.
    pub depth: Vec<f32>,
    /// Every instance seen by at least one sample.
    pub visible: BTreeSet<u32>,
}

impl VisibilityImage {
    /// The instance seen by sample `s` of pixel `(x, y)`.
    pub fn sample(&self, x: u32, y: u32, s: u32) -> Option<u32> {
        let id = self.ids[((y * self.width + x) * self.samples + s) as usize];
        (id != NO_INSTANCE).then_some(id)
    }
}

/// A BVH over every instance's world-space triangles, relative to one eye position.
pub struct RaycastOracle {
    eye: DVec3,
    bvh: Option<CwBvh>,
    /// Triangles in BVH primitive order.
    tris: Vec<[Vec3A; 3]>,
    /// Instance of each triangle, same order.
    tri_instance: Vec<u32>,
    /// Which faces of each triangle are culled, same order.
    tri_face_cull: Vec<FaceCull>,
    build_time: Duration,
}

impl RaycastOracle {
    /// Builds the BVH over `scene`'s triangles placed relative to `eye`.
    pub fn new(scene: &Scene, eye: DVec3) -> Self {
        let start = Instant::now();
        let mut tris = Vec::new();
        let mut tri_instance = Vec::new();
        let mut tri_face_cull = Vec::new();
        for (id, instance) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[instance.mesh as usize];
            let face_cull = FaceCull::of(scene, instance);
            let linear = instance.transform.linear.as_dmat3();
            let offset = instance.transform.translation - eye;
            let indices = &scene.indices[mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
            for t in indices.chunks_exact(3) {
                let v = |i: u32| {
                    let p = scene.vertices[(mesh.vertex_offset + i) as usize].position;
                    let world = linear * DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) + offset;
                    Vec3A::from(world.as_vec3())
                };
                let tri = [v(t[0]), v(t[1]), v(t[2])];
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                if !(tri.iter().all(|p| p.is_finite()) && n.length_squared() > 0.0) {
                    continue;
                }
                tris.push(tri);
                tri_instance.push(id as u32);
                tri_face_cull.push(face_cull);
            }
        }
        if tris.is_empty() {
            return Self { eye, bvh: None, tris, tri_instance, tri_face_cull, build_time: start.elapsed() };
        }
        let input: Vec<Triangle> = tris.iter().map(|t| Triangle { v0: t[0], v1: t[1], v2: t[2] }).collect();
        let mut core = Duration::ZERO;
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(&input, BvhBuildParams::fast_build(), &mut core);
        // Reorder so that the traversal's primitive index addresses the arrays directly.
        let tris: Vec<[Vec3A; 3]> = bvh.primitive_indices.iter().map(|&i| tris[i as usize]).collect();
        let tri_instance: Vec<u32> = bvh.primitive_indices.iter().map(|&i| tri_instance[i as usize]).collect();
        let tri_face_cull = bvh.primitive_indices.iter().map(|&i| tri_face_cull[i as usize]).collect();
        Self { eye, bvh: Some(bvh), tris, tri_instance, tri_face_cull, build_time: start.elapsed() }
    }

    /// The eye the triangles are relative to.
    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    /// Triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Time spent gathering triangles and building the BVH.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The nearest hit along `origin + t·direction` (eye-relative), `t ∈ [t_min, t_max]`:
    /// `(instance, t)`.
    pub fn closest_hit(&self, origin: Vec3A, direction: Vec3A, t_min: f32, t_max: f32) -> Option<(u32, f32)> {
        let bvh = self.bvh.as_ref()?;
        let shear = Shear::new(direction);
        let ray = Ray::new(origin, direction, t_min, t_max);
        let mut hit = RayHit::none();
        let hit_if_drawn = |ray: &Ray, id: usize| {
            if self.is_culled(id, direction) {
                f32::INFINITY
            } else {
                intersect_watertight(&self.tris[id], ray, &shear)
            }
        };
        if bvh.ray_traverse(ray, &mut hit, hit_if_drawn) {
            Some((self.tri_instance[hit.primitive_id as usize], hit.t))
        } else {
            None
        }
    }

    /// Whether the rasterizer culls triangle `id` seen along `direction`. Its counter-clockwise
    /// side, the front of a pipeline, is the one whose normal (by the right-hand rule over the
    /// world-space vertices) points against the view direction (`lighting_visibility.comp`
    /// derives `gl_FrontFacing` the same way). Edge-on triangles cover no sample either way.
    fn is_culled(&self, id: usize, direction: Vec3A) -> bool {
        let t = &self.tris[id];
        let toward = (t[1] - t[0]).cross(t[2] - t[0]).dot(direction);
        match self.tri_face_cull[id] {
            FaceCull::Back | FaceCull::MaskedBack => toward >= 0.0,
            FaceCull::Front | FaceCull::MaskedFront => toward <= 0.0,
            FaceCull::None | FaceCull::MaskedNone => false,
            // Transparent surfaces hide nothing; the rays pass through them.
            FaceCull::Blended => true,
        }
    }

    /// Casts `pattern`'s rays through every pixel of a `width × height` view of `camera`.
    ///
    /// `camera.eye` must be the eye the oracle was built for. Rows are split across the available
    /// cores.
    pub fn cast(
        &self,
        camera: &crate::scene::Camera,
        width: u32,
        height: u32,
        pattern: SamplePattern,
    ) -> Result<VisibilityImage> {
        if camera.eye != self.eye {
            return Err(Error::Invalid(format!(
                "the ray-cast oracle was built for eye {} but the camera is at {}",
                self.eye, camera.eye
            )));
        }
        camera.validate().map_err(Error::Invalid)?;
        if width == 0 || height == 0 {
            return Err(Error::Invalid(format!("image size {width}x{height} is empty")));
        }
        let view = CullView::from_camera(camera, width, height);
        let to_world = view.rotation.as_dmat3().transpose();
        let positions = pattern.positions();
        let samples = positions.len() as u32;
        let per_row = (width * samples) as usize;
        let mut ids = vec![NO_INSTANCE; per_row * height as usize];
        let mut depth = vec![0.0f32; per_row * height as usize];
        let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1).min(height as usize);
        let rows_per_thread = (height as usize).div_ceil(threads);
        std::thread::scope(|scope| {
            for (chunk, (id_rows, depth_rows)) in
                ids.chunks_mut(per_row * rows_per_thread).zip(depth.chunks_mut(per_row * rows_per_thread)).enumerate()
            {
                let view = &view;
                let to_world = &to_world;
                scope.spawn(move || {
                    let first_row = chunk * rows_per_thread;
                    for (i, (id, z)) in id_rows.iter_mut().zip(depth_rows.iter_mut()).enumerate() {
                        let y = first_row + i / per_row;
                        let x = (i % per_row) / samples as usize;
                        let (ox, oy) = positions[i % samples as usize];
                        let (origin, dir, t_max) =
                            primary_ray(view, to_world, x as f64 + ox as f64, y as f64 + oy as f64);
                        if let Some((instance, t)) = self.closest_hit(origin, dir, view.near, t_max) {
                            *id = instance;
                            *z = if view.orthographic {
                                (view.far - t) / (view.far - view.near)
                            } else if view.far.is_finite() {
                                view.near * (view.far - t) / (t * (view.far - view.near))
                            } else {
                                view.near / t
                            };
                        }
                    }
                });
            }
        });
        let visible = ids.iter().copied().filter(|&i| i != NO_INSTANCE).collect();
        Ok(VisibilityImage { width, height, samples, ids, depth, visible })
    }
}

/// The primary ray through framebuffer position `(fx, fy)` (pixels): `(origin, direction, t_max)`.
fn primary_ray(view: &CullView, to_world: &DMat3, fx: f64, fy: f64) -> (Vec3A, Vec3A, f32) {
    let ndc_x = 2.0 * fx / view.viewport.x as f64 - 1.0;
    let ndc_y = 2.0 * fy / view.viewport.y as f64 - 1.0;
    let (sx, sy) = (view.scale.x as f64, view.scale.y as f64);
    // ndc = (sx·t − cx, cy − sy·u), t and u per unit distance (perspective) or view x, y.
    let t = (ndc_x + view.offset.x as f64) / sx;
    let u = (view.offset.y as f64 - ndc_y) / sy;
    if view.orthographic {
        let origin = *to_world * DVec3::new(t, u, 0.0);
        let dir = *to_world * DVec3::NEG_Z;
        (Vec3A::from(origin.as_vec3()), Vec3A::from(dir.as_vec3()), view.far)
    } else {
        let dir = *to_world * DVec3::new(t, u, -1.0);
        (Vec3A::ZERO, Vec3A::from(dir.as_vec3()), view.far)
    }
}

/// Per-ray constants of the watertight test: the axis permutation and shear.
struct Shear {
    k: [usize; 3],
    s: [f32; 3],
}

impl Shear {
    fn new(d: Vec3A) -> Self {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self { k: [kx, ky, kz], s: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]] }
    }
}

/// Watertight ray–triangle intersection (Woop, Benthin & Wald, JCGT 2013): `t`, or infinity.
fn intersect_watertight(tri: &[Vec3A; 3], ray: &Ray, sh: &Shear) -> f32 {
    let [kx, ky, kz] = sh.k;
    let [sx, sy, sz] = sh.s;
    let a = tri[0] - ray.origin;
    let b = tri[1] - ray.origin;
    let c = tri[2] - ray.origin;
    let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
    let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
    let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let f = |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
        u = f(cx, by, cy, bx);
        v = f(ax, cy, ay, cx);
        w = f(bx, ay, by, ax);
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return f32::INFINITY;
    }
    let det = u + v + w;
    if det == 0.0 {
        return f32::INFINITY;
    }
    let t_scaled = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
    let t = t_scaled / det;
    if t >= ray.tmin && t <= ray.tmax {
        t
    } else {
        f32::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Instance, MeshData, Projection, Transform};
    use glam::{Mat3, Vec3};

    fn cube() -> MeshData {
        let mut m = MeshData::default();
        let faces = [
            (Vec3::X, Vec3::Y, Vec3::Z),
            (-Vec3::X, Vec3::Y, -Vec3::Z),
            (Vec3::Y, Vec3::Z, Vec3::X),
            (-Vec3::Y, Vec3::Z, -Vec3::X),
            (Vec3::Z, Vec3::X, Vec3::Y),
            (-Vec3::Z, -Vec3::X, Vec3::Y),
        ];
        for (n, u, v) in faces {
            let base = m.positions.len() as u32;
            for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                m.positions.push(n * 0.5 + u * a + v * b);
                m.normals.push(n);
            }
            m.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
        m
    }

    /// A 2x2 quad in the z = 0 plane, two triangles sharing the diagonal, counter-clockwise
    /// seen from +z.
    fn quad() -> MeshData {
        MeshData {
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            normals: vec![],
            indices: vec![0, 1, 2, 0, 2, 3],
            ..Default::default()
        }
    }

    /// Boxes of the given (scale, translation) along the −Z axis, camera at the origin.
    fn boxes(placements: &[(Vec3, DVec3)]) -> Scene {
        let mut scene = Scene::default();
        let mesh = scene.add_mesh("cube", &cube(), "cube").unwrap();
        for &(scale, at) in placements {
            scene.instances.push(Instance {
                transform: Transform { linear: Mat3::from_diagonal(scale), translation: at },
                mesh,
                material: 0,
                flags: 0,
            });
        }
        scene
    }

    fn camera(eye: DVec3, projection: Projection, near: f32) -> Camera {
        Camera { eye, target: eye + DVec3::NEG_Z, up: Vec3::Y, projection, near, ..Default::default() }
    }

    #[test]
    fn a_box_hidden_behind_another_is_not_visible() {
        let eye = DVec3::new(1.0e7, -3.0e6, 2.5e6);
        let scene = boxes(&[
            (Vec3::splat(2.0), eye + DVec3::new(0.0, 0.0, -5.0)),
            (Vec3::ONE, eye + DVec3::new(0.0, 0.0, -10.0)),
        ]);
        let oracle = RaycastOracle::new(&scene, eye);
        assert_eq!(oracle.triangle_count(), 24);
        let cam = camera(eye, Projection::Perspective { fov_y_deg: 30.0 }, 0.1);
        let image = oracle.cast(&cam, 33, 17, SamplePattern::Standard4x).unwrap();
        assert_eq!(image.visible, BTreeSet::from([0]));
        // The center sample sees the front face at distance 4: depth 0.1 / 4.
        let c = image.sample(16, 8, 0).unwrap();
        assert_eq!(c, 0);
        let z = image.depth[((8 * 33 + 16) * 4) as usize];
        assert!((z - 0.025).abs() < 1e-6, "{z}");
        // Corners see nothing.
        assert_eq!(image.sample(0, 0, 0), None);
    }

    #[test]
    fn a_box_straddling_the_near_plane_shows_its_far_part_when_double_sided() {
        // Box from z = -0.5 to -1.5 with near 1: the part beyond the near plane is seen from
        // inside, where only its back faces are (the one at distance 1.5 in the middle).
        let mut scene = boxes(&[(Vec3::ONE, DVec3::new(0.0, 0.0, -1.0))]);
        let cam = camera(DVec3::ZERO, Projection::Perspective { fov_y_deg: 60.0 }, 1.0);
        // One-sided (no material: glTF's default): the rasterizer culls back faces, so nothing.
        let one_sided = RaycastOracle::new(&scene, DVec3::ZERO).cast(&cam, 8, 8, SamplePattern::Center).unwrap();
        assert!(one_sided.visible.is_empty());
        scene.add_material(crate::scene::Material { double_sided: true, ..Default::default() });
        let oracle = RaycastOracle::new(&scene, DVec3::ZERO);
        let image = oracle.cast(&cam, 8, 8, SamplePattern::Center).unwrap();
        assert_eq!(image.visible, BTreeSet::from([0]));
        let z = image.depth[(4 * 8 + 4) as usize];
        assert!((z - 1.0 / 1.5).abs() < 1e-5, "{z}");
        // With near 2 the box is entirely clipped.
        let cam = camera(DVec3::ZERO, Projection::Perspective { fov_y_deg: 60.0 }, 2.0);
        assert!(oracle.cast(&cam, 8, 8, SamplePattern::Center).unwrap().visible.is_empty());
    }

    #[test]
    fn back_faces_of_one_sided_triangles_are_not_hit_and_mirroring_flips_the_front() {
        let quad = quad();
        let sees = |linear: Mat3, double_sided: bool| {
            let mut scene = Scene::default();
            let mesh = scene.add_mesh("quad", &quad, "quad").unwrap();
            let material = scene.add_material(crate::scene::Material { double_sided, ..Default::default() });
            let translation = DVec3::new(0.0, 0.0, -5.0);
            scene.instances.push(Instance { transform: Transform { linear, translation }, mesh, material, flags: 0 });
            let cam = camera(DVec3::ZERO, Projection::Perspective { fov_y_deg: 60.0 }, 0.1);
            !RaycastOracle::new(&scene, DVec3::ZERO).cast(&cam, 8, 8, SamplePattern::Center).unwrap().visible.is_empty()
        };
        let turned = Mat3::from_rotation_y(std::f32::consts::PI);
        let mirror_x = Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
        let mirror_z = Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0));
        assert!(sees(Mat3::IDENTITY, false), "front face toward the eye");
        assert!(!sees(turned, false), "back face toward the eye");
        assert!(sees(turned, true), "double-sided");
        // Mirrored in x: same plane, reversed winding, but glTF keeps the front toward +z.
        assert!(sees(mirror_x, false), "mirrored, front toward the eye");
        assert!(!sees(mirror_z, false), "mirrored through its plane: front away from the eye");
        assert!(sees(mirror_z, true), "mirrored, double-sided");
    }

    #[test]
    fn orthographic_sees_boxes_side_by_side_and_respects_far() {
        let scene = boxes(&[
            (Vec3::ONE, DVec3::new(-2.0, 0.0, -5.0)),
            (Vec3::ONE, DVec3::new(2.0, 0.0, -5.0)),
            (Vec3::ONE, DVec3::new(0.0, 0.0, -50.0)),
        ]);
        let oracle = RaycastOracle::new(&scene, DVec3::ZERO);
        let cam = camera(DVec3::ZERO, Projection::Orthographic { height: 8.0, far: 20.0 }, 0.5);
        let image = oracle.cast(&cam, 16, 16, SamplePattern::Standard4x).unwrap();
        assert_eq!(image.visible, BTreeSet::from([0, 1]));
        // Box 0 spans x in [-2.5, -1.5]: columns 3 and 4 (8 units over 16 pixels).
        assert_eq!(image.sample(3, 8, 0), Some(0));
        assert_eq!(image.sample(12, 8, 0), Some(1));
        assert_eq!(image.sample(8, 8, 0), None);
        // Depth (far - 4.5) / (far - near).
        let z = image.depth[((8 * 16 + 3) * 4) as usize];
        assert!((z - 15.5 / 19.5).abs() < 1e-6, "{z}");
    }

    #[test]
    fn shared_edges_are_watertight() {
        // A big quad (two triangles sharing the diagonal) in front of a far box; rays aimed at the
        // diagonal must all hit the quad.
        let mut scene = boxes(&[(Vec3::splat(100.0), DVec3::new(0.0, 0.0, -200.0))]);
        let quad = quad();
        let mesh = scene.add_mesh("quad", &quad, "quad").unwrap();
        scene.instances.push(Instance {
            transform: Transform {
                linear: Mat3::from_diagonal(Vec3::splat(3.7)),
                translation: DVec3::new(0.0, 0.0, -10.0),
            },
            mesh,
            material: 0,
            flags: 0,
        });
        let oracle = RaycastOracle::new(&scene, DVec3::ZERO);
        for i in 0..2000 {
            let s = -3.6 + 7.2 * i as f32 / 1999.0;
            let dir = Vec3A::new(s, s, -10.0);
            assert_eq!(oracle.closest_hit(Vec3A::ZERO, dir, 0.1, f32::INFINITY).map(|h| h.0), Some(1), "s = {s}");
        }
    }

    #[test]
    fn camera_at_another_eye_is_refused() {
        let scene = boxes(&[(Vec3::ONE, DVec3::new(0.0, 0.0, -5.0))]);
        let oracle = RaycastOracle::new(&scene, DVec3::ZERO);
        let cam = camera(DVec3::X, Projection::Perspective { fov_y_deg: 60.0 }, 0.1);
        assert!(oracle.cast(&cam, 4, 4, SamplePattern::Center).is_err());
    }
}
