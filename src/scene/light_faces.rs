//! The shadow views of spot and point lights: which lights of a scene cast shadows in a view
//! (a budget of them, by their importance to the camera), and the perspective cameras their
//! maps are drawn from. A spot light whose cone fits one view (outer angle up to 60°) is one
//! face along its cone; a point light, or a wider spot light, is six faces, a cube around it.

use super::camera::{Camera, Projection};
use super::PointLight;
use glam::Vec3;

/// The widest spot cone (outer angle, radians) drawn as one face; wider ones take a cube.
pub const ONE_FACE_MAX_ANGLE: f32 = std::f32::consts::FRAC_PI_3;

/// A light chosen to cast shadows, with the cameras of its faces.
#[derive(Clone, Debug, PartialEq)]
pub struct LightFaces {
    /// Its index in the scene's lights.
    pub light: usize,
    /// One camera along its cone, or six (+x, -x, +y, -y, +z, -z) around it.
    pub faces: Vec<Camera>,
    /// The world size of a texel of its maps one unit from the light (at distance `d`, `d`
    /// times this).
    pub texel_per_unit: f32,
}

/// How much light `light` brings to what `camera` sees within `reach`: 0 when its sphere of
/// influence lies behind the camera or beyond `reach`, else its brightest channel weighted by
/// how close its sphere comes to the eye relative to its range.
pub fn importance(light: &PointLight, camera: &Camera, reach: f64) -> f64 {
    let range = light.range as f64;
    let to_light = light.position - camera.eye;
    let forward = (camera.target - camera.eye).normalize_or_zero();
    let distance = to_light.length();
    if to_light.dot(forward) < -range || distance - range > reach {
        return 0.0;
    }
    let gap = (distance - range).max(0.0);
    light.color.max_element() as f64 * range * range / (gap * gap + range * range)
}

/// The lights of `lights` that cast shadows in `camera`'s view: at most `budget`, the most
/// important first (ties by index), those of no importance left out, each with its faces' cameras
/// for maps of `resolution` texels a side.
pub fn shadowed_lights(
    lights: &[PointLight],
    camera: &Camera,
    reach: f64,
    budget: usize,
    resolution: u32,
) -> Vec<LightFaces> {
    let mut ranked: Vec<(f64, usize)> =
        lights.iter().enumerate().map(|(i, l)| (importance(l, camera, reach), i)).filter(|(w, _)| *w > 0.0).collect();
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    ranked.truncate(budget);
    ranked.into_iter().map(|(_, i)| faces_of(i, &lights[i], resolution)).collect()
}

/// The faces of light `index`.
pub fn faces_of(index: usize, light: &PointLight, resolution: u32) -> LightFaces {
    // The faces reach a few texels past their edges, so that the filter's taps near an edge
    // stay inside the face that holds the point.
    let margin = 4.0 / resolution.max(1) as f32;
    let near = (light.range * 1e-3).max(1e-3);
    let far = light.range;
    let at = |direction: Vec3, half_tan: f32| {
        let up = if direction.y.abs() > 0.9 { Vec3::Z } else { Vec3::Y };
        Camera {
            eye: light.position,
            target: light.position + direction.as_dvec3(),
            up,
            projection: Projection::PerspectiveFar { fov_y_deg: 2.0 * half_tan.atan().to_degrees(), far },
            near,
            jitter: glam::Vec2::ZERO,
        }
    };
    match light.spot.filter(|cone| cone.outer_angle <= ONE_FACE_MAX_ANGLE) {
        Some(cone) => {
            let half_tan = cone.outer_angle.tan() * (1.0 + margin) + margin;
            LightFaces {
                light: index,
                faces: vec![at(cone.direction, half_tan)],
                texel_per_unit: 2.0 * half_tan / resolution as f32,
            }
        }
        None => {
            let half_tan = 1.0 + margin;
            let directions = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
            LightFaces {
                light: index,
                faces: directions.iter().map(|&d| at(d, half_tan)).collect(),
                texel_per_unit: 2.0 * half_tan / resolution as f32,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SpotCone;
    use glam::DVec3;

    fn camera() -> Camera {
        Camera { eye: DVec3::ZERO, target: DVec3::new(0.0, 0.0, -1.0), ..Default::default() }
    }

    #[test]
    fn the_brightest_nearest_lights_in_front_are_chosen_within_the_budget() {
        let lights = vec![
            PointLight::point(DVec3::new(0.0, 0.0, 30.0), Vec3::splat(100.0), 5.0), // behind
            PointLight::point(DVec3::new(0.0, 0.0, -10.0), Vec3::splat(1.0), 5.0),
            PointLight::point(DVec3::new(0.0, 0.0, -10.0), Vec3::splat(5.0), 5.0),
            PointLight::point(DVec3::new(0.0, 0.0, -500.0), Vec3::splat(100.0), 5.0), // beyond reach
            PointLight::point(DVec3::new(0.0, 0.0, -40.0), Vec3::splat(5.0), 5.0),
        ];
        let chosen: Vec<usize> = shadowed_lights(&lights, &camera(), 100.0, 2, 256).iter().map(|l| l.light).collect();
        assert_eq!(chosen, [2, 1]);
        assert_eq!(shadowed_lights(&lights, &camera(), 100.0, 9, 256).len(), 3);
        assert!(shadowed_lights(&lights, &camera(), 100.0, 0, 256).is_empty());
    }

    #[test]
    fn a_narrow_spot_is_one_face_and_a_point_light_a_cube_that_holds_every_direction() {
        let mut spot = PointLight::point(DVec3::new(1.0, 2.0, 3.0), Vec3::ONE, 10.0);
        spot.spot = Some(SpotCone { direction: Vec3::NEG_Y, inner_angle: 0.2, outer_angle: 0.5 });
        let faces = faces_of(0, &spot, 512);
        assert_eq!(faces.faces.len(), 1);
        // The cone's edge lies inside the face.
        let edge = Vec3::new(0.5f32.sin(), -0.5f32.cos(), 0.0);
        let clip = faces.faces[0].view_projection_rel_eye(1.0) * (edge * 5.0).extend(1.0);
        assert!((clip.x / clip.w).abs() < 1.0 && (clip.y / clip.w).abs() < 1.0, "{clip}");
        let point = PointLight::point(DVec3::ZERO, Vec3::ONE, 10.0);
        let cube = faces_of(0, &point, 512);
        assert_eq!(cube.faces.len(), 6);
        for d in [Vec3::new(0.3, -0.9, 0.1), Vec3::new(1.0, 1.0, 1.0), Vec3::new(-0.2, 0.1, -0.99)] {
            let v = d.normalize() * 4.0;
            let a = v.abs();
            let face = if a.x >= a.y && a.x >= a.z {
                if v.x >= 0.0 {
                    0
                } else {
                    1
                }
            } else if a.y >= a.z {
                if v.y >= 0.0 {
                    2
                } else {
                    3
                }
            } else if v.z >= 0.0 {
                4
            } else {
                5
            };
            let clip = cube.faces[face].view_projection_rel_eye(1.0) * v.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && ndc.z > 0.0 && ndc.z <= 1.0, "{d}: face {face}, {ndc}");
        }
    }
}
