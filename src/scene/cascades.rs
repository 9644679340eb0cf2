//! Sun shadow cascades fitted to a camera view: the view's depth range up to a shadow distance
//! is split into slices, and each slice gets an orthographic camera looking along the sun that
//! holds it, to be rendered and culled as one more view.
//!
//! The slices follow the practical split scheme: each split blends the logarithmic split (even
//! texel density in depth) and the uniform one, `lambda` of the first.
//!
//! Each cascade is stabilised so that its shadows do not shimmer as the camera moves or turns:
//! - its extent is the bounding sphere of its slice, which depends only on the view's
//!   projection and the splits, not on where the camera looks, so turning changes no texel
//!   size; the diameter is rounded up to a sixteenth of a unit so rounding never flickers it;
//! - its centre, seen from the sun, is snapped to whole texels, so moving the camera moves the
//!   shadow map's texel grid by whole texels over the world, never a fraction; its distance
//!   along the sun is snapped to a texel too (the far plane reaches a texel further to keep the
//!   slice), so that a small move leaves the farther cascades' cameras, and maps, unchanged.
//!
//! Casters between the sun and a slice must be drawn into its map even when the camera cannot
//! see them (behind it, beyond a side plane, far along the sun): each cascade's camera starts
//! `caster_reach` before the slice's sphere towards the sun.

use super::camera::{Camera, Projection};
use glam::{DVec3, Vec3};

/// How cascades are fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeSettings {
    /// Cascades, 1 to [`MAX_CASCADES`].
    pub count: u32,
    /// How far from the camera (along its view) shadows reach.
    pub distance: f32,
    /// Blend of logarithmic (1) and uniform (0) splits.
    pub lambda: f32,
    /// Texels of a cascade's square shadow map along a side.
    pub resolution: u32,
    /// How far before each slice, towards the sun, casters are drawn.
    pub caster_reach: f32,
}

/// The most cascades.
pub const MAX_CASCADES: u32 = 4;

impl Default for CascadeSettings {
    fn default() -> Self {
        Self { count: 4, distance: 150.0, lambda: 0.75, resolution: 2048, caster_reach: 500.0 }
    }
}

/// One cascade: the slice of the view it covers and the orthographic camera that holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cascade {
    /// Distance range of its slice along the camera's view direction.
    pub near_split: f32,
    /// End of that range.
    pub far_split: f32,
    /// The camera along the sun whose view (aspect 1) holds the slice and its casters.
    pub camera: Camera,
    /// World units a shadow-map texel spans.
    pub texel: f64,
}

/// The cascades of `view` (for an image of `aspect`) under a sun whose light travels along
/// `sun_direction`; an error names what is wrong with the input.
pub fn fit_cascades(
    view: &Camera,
    aspect: f32,
    sun_direction: Vec3,
    settings: &CascadeSettings,
) -> Result<Vec<Cascade>, String> {
    if !sun_direction.is_finite() || sun_direction.length_squared() < 1e-12 {
        return Err(format!("sun direction {sun_direction} must be finite and not zero"));
    }
    if !(1..=MAX_CASCADES).contains(&settings.count) {
        return Err(format!("{} cascades; 1 to {MAX_CASCADES} are possible", settings.count));
    }
    let near = view.near;
    if !(settings.distance.is_finite() && settings.distance > near) {
        return Err(format!("shadow distance {} must be finite and beyond the near plane {near}", settings.distance));
    }
    if !(0.0..=1.0).contains(&settings.lambda) || settings.resolution == 0 {
        return Err("lambda must be in 0..=1 and the resolution at least 1".into());
    }
    if !(settings.caster_reach.is_finite() && settings.caster_reach >= 0.0) {
        return Err(format!("caster reach {} must be finite and at least 0", settings.caster_reach));
    }
    view.validate().map_err(|e| format!("camera: {e}"))?;
    let d = sun_direction.normalize().as_dvec3();
    // A light basis that does not turn with the camera: the sun's own right and up.
    let reference = if d.y.abs() < 0.99 { DVec3::Y } else { DVec3::X };
    let right = reference.cross(d).normalize();
    let up = d.cross(right);
    let rays = corner_rays(view, aspect)?;
    let n = settings.count as usize;
    let splits: Vec<f32> = (0..=n)
        .map(|i| {
            let f = i as f32 / n as f32;
            let log = near * (settings.distance / near).powf(f);
            let uniform = near + (settings.distance - near) * f;
            settings.lambda * log + (1.0 - settings.lambda) * uniform
        })
        .collect();
    let mut cascades = Vec::with_capacity(n);
    for w in splits.windows(2) {
        let corners: Vec<DVec3> = [w[0], w[1]].iter().flat_map(|&z| rays.iter().map(move |r| r.at(z as f64))).collect();
        let center_rel = corners.iter().sum::<DVec3>() / corners.len() as f64;
        let radius = corners.iter().map(|c| c.distance(center_rel)).fold(0.0, f64::max);
        let diameter = ((2.0 * radius) * 16.0).ceil() / 16.0;
        let texel = diameter / settings.resolution as f64;
        // Snapped in the sun's basis, in absolute world coordinates.
        let center = view.eye + center_rel;
        let snap = |v: f64| (v / texel).floor() * texel;
        let (x, y, z) = (snap(center.dot(right)), snap(center.dot(up)), snap(center.dot(d)));
        let snapped = right * x + up * y + d * z;
        let back = diameter * 0.5 + settings.caster_reach as f64;
        let eye = snapped - d * back;
        let camera = Camera {
            eye,
            target: snapped,
            up: up.as_vec3(),
            projection: Projection::Orthographic {
                height: diameter as f32,
                far: (back + diameter * 0.5 + texel) as f32,
            },
            near: 1e-3,
            jitter: glam::Vec2::ZERO,
        };
        cascades.push(Cascade { near_split: w[0], far_split: w[1], camera, texel });
    }
    Ok(cascades)
}

/// A ray from the eye through one corner of the view, parameterised by distance along the
/// view direction: `at(z)` is the corner's point (relative to the eye) at view depth `z`.
struct CornerRay {
    origin: DVec3,
    step: DVec3,
}

impl CornerRay {
    fn at(&self, z: f64) -> DVec3 {
        self.origin + self.step * z
    }
}

/// The four corner rays of `view`: each through the points its projection puts at that corner
/// of the image on two depths, scaled so that a step of 1 advances 1 along the view direction.
fn corner_rays(view: &Camera, aspect: f32) -> Result<Vec<CornerRay>, String> {
    let forward = (view.target - view.eye).normalize();
    let inverse = view.view_projection_rel_eye(aspect).as_dmat4().inverse();
    let unproject = |x: f64, y: f64, depth: f64| {
        let p = inverse * glam::DVec4::new(x, y, depth, 1.0);
        p.truncate() / p.w
    };
    let mut rays = Vec::with_capacity(4);
    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        // Depth 1 is the near plane; 0.5 lies beyond it in every projection.
        let (a, b) = (unproject(x, y, 1.0), unproject(x, y, 0.5));
        let along = (b - a).dot(forward);
        if !a.is_finite() || !b.is_finite() || along <= 0.0 {
            return Err("the view's projection gives no depth range to split".into());
        }
        let step = (b - a) / along;
        let origin = a - step * a.dot(forward);
        rays.push(CornerRay { origin, step });
    }
    Ok(rays)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> Camera {
        Camera {
            eye: DVec3::new(1.0e6 + 3.0, 12.0, -40.0),
            target: DVec3::new(1.0e6 + 20.0, 4.0, -10.0),
            near: 0.2,
            ..Default::default()
        }
    }

    fn sun() -> Vec3 {
        Vec3::new(-0.4, -0.8, -0.3)
    }

    /// Where `p` lands in `cascade`'s view: x, y in -1..1 and depth in 0..1 when inside.
    fn project(cascade: &Cascade, p: DVec3) -> glam::DVec3 {
        let clip = cascade.camera.view_projection_rel_eye(1.0).as_dmat4() * (p - cascade.camera.eye).extend(1.0);
        clip.truncate() / clip.w
    }

    #[test]
    fn every_slice_lies_in_its_cascade_with_room_for_casters_towards_the_sun() {
        let settings = CascadeSettings { count: 4, distance: 100.0, ..Default::default() };
        for view in [
            view(),
            Camera { projection: Projection::Orthographic { height: 30.0, far: 300.0 }, ..view() },
            Camera { projection: Projection::PerspectiveFar { fov_y_deg: 90.0, far: 500.0 }, ..view() },
        ] {
            let cascades = fit_cascades(&view, 16.0 / 9.0, sun(), &settings).unwrap();
            assert_eq!(cascades.len(), 4);
            assert_eq!(cascades[0].near_split, view.near);
            assert!((cascades[3].far_split - 100.0).abs() < 1e-3);
            assert!(cascades.windows(2).all(|w| w[0].far_split == w[1].near_split && w[0].texel <= w[1].texel));
            let rays = corner_rays(&view, 16.0 / 9.0).unwrap();
            for c in &cascades {
                for z in [c.near_split, 0.5 * (c.near_split + c.far_split), c.far_split] {
                    for r in &rays {
                        let p = view.eye + r.at(z as f64);
                        let q = project(c, p);
                        assert!(q.x.abs() <= 1.0 && q.y.abs() <= 1.0 && q.z > 0.0 && q.z <= 1.0, "{q} outside");
                        // A caster 400 units towards the sun still falls in the map.
                        let caster = project(c, p - sun().normalize().as_dvec3() * 400.0);
                        assert!(caster.z > 0.0 && caster.z <= 1.0, "caster depth {caster}");
                    }
                }
            }
        }
    }

    #[test]
    fn cascades_keep_their_size_as_the_camera_turns_and_move_by_whole_texels() {
        let settings = CascadeSettings::default();
        let base = fit_cascades(&view(), 1.5, sun(), &settings).unwrap();
        let turned = Camera { target: DVec3::new(1.0e6 - 30.0, 9.0, 5.0), ..view() };
        let moved = Camera {
            eye: view().eye + DVec3::new(0.37, -0.11, 1.913),
            target: view().target + DVec3::new(0.37, -0.11, 1.913),
            ..view()
        };
        let d = sun().normalize().as_dvec3();
        let right = DVec3::Y.cross(d).normalize();
        let up = d.cross(right);
        for other in [
            fit_cascades(&turned, 1.5, sun(), &settings).unwrap(),
            fit_cascades(&moved, 1.5, sun(), &settings).unwrap(),
        ] {
            for (a, b) in base.iter().zip(&other) {
                assert_eq!(a.camera.projection, b.camera.projection, "the extent stays");
                assert_eq!(a.texel, b.texel);
                let shift = b.camera.target - a.camera.target;
                for axis in [right, up] {
                    let texels = shift.dot(axis) / a.texel;
                    assert!((texels - texels.round()).abs() < 1e-3, "moved by {texels} texels");
                }
            }
        }
    }

    #[test]
    fn bad_input_is_refused() {
        let s = CascadeSettings::default();
        assert!(fit_cascades(&view(), 1.0, Vec3::ZERO, &s).unwrap_err().contains("sun direction"));
        assert!(fit_cascades(&view(), 1.0, Vec3::NAN, &s).is_err());
        let five = CascadeSettings { count: 5, ..s };
        assert!(fit_cascades(&view(), 1.0, sun(), &five).unwrap_err().contains("5 cascades"));
        let zero = CascadeSettings { count: 0, ..s };
        assert!(fit_cascades(&view(), 1.0, sun(), &zero).is_err());
        let short = CascadeSettings { distance: 0.1, ..s };
        assert!(fit_cascades(&view(), 1.0, sun(), &short).unwrap_err().contains("shadow distance"));
        // The sun straight down still has a light basis.
        assert_eq!(fit_cascades(&view(), 1.0, -Vec3::Y, &s).unwrap().len(), 4);
    }
}
