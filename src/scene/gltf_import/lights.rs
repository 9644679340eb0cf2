//! `KHR_lights_punctual`: the file's first directional light becomes the sun, and its point and
//! spot lights the scene's lights. Intensities are taken as they are (lux for the sun, candela
//! for the others, times the light's colour), and a light without a range ends where its
//! radiance falls below [`RANGE_CUTOFF`].

use super::nodes::{self, Placed};
use crate::scene::{DirectionalLight, PointLight, SpotCone};
use glam::Vec3;
use gltf::khr_lights_punctual::Kind;

/// Radiance below which a light without a range is taken to end (1/100 of the default sun's).
pub const RANGE_CUTOFF: f32 = 0.02;

/// The lights placed at `placed`'s nodes: the sun (the first directional light) and the point
/// and spot lights; notes for what is left out.
pub(super) fn import(
    document: &gltf::Document,
    placed: &[Placed<'_>],
    notes: &mut Vec<String>,
) -> (Option<DirectionalLight>, Vec<PointLight>) {
    let count = document.lights().map_or(0, |l| l.len());
    let (mut sun, mut lights) = (None, Vec::new());
    let mut extra_suns = 0;
    for p in placed {
        let json = &document.as_json().nodes[p.node.index()];
        let Some(index) =
            json.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()).map(|l| l.light.value())
        else {
            continue;
        };
        if index >= count {
            notes.push(format!("{}: light {index} ignored: the file has {count} lights", nodes::node_label(&p.node)));
            continue;
        }
        let Some(light) = p.node.light() else { continue };
        let color = Vec3::from(light.color()) * light.intensity();
        // Lights shine along the node's local -Z.
        let direction = (p.world.linear * Vec3::NEG_Z).normalize_or_zero();
        let unusable = |why: &str| format!("{}: light {index} ignored: {why}", nodes::node_label(&p.node));
        if !color.is_finite() || color.min_element() < 0.0 {
            notes.push(unusable("its colour times intensity is not finite and non-negative"));
            continue;
        }
        match light.kind() {
            Kind::Directional => {
                if direction == Vec3::ZERO {
                    notes.push(unusable("its node's transform gives it no direction"));
                } else if sun.is_none() {
                    sun = Some(DirectionalLight { direction, color });
                } else {
                    extra_suns += 1;
                }
            }
            kind => {
                let range = light.range().unwrap_or_else(|| (color.max_element() / RANGE_CUTOFF).sqrt().max(1e-3));
                let spot = match kind {
                    Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                        Some(SpotCone { direction, inner_angle: inner_cone_angle, outer_angle: outer_cone_angle })
                    }
                    _ => None,
                };
                let light = PointLight { position: p.world.translation, color, range, spot };
                let error = crate::scene::position_error("position", light.position)
                    .or_else(|| {
                        (!(range.is_finite() && range > 0.0)).then(|| format!("range {range} must be positive"))
                    })
                    .or_else(|| spot.and_then(|c| crate::scene::spot_cone_error(&c)));
                match error {
                    Some(e) => notes.push(unusable(&e)),
                    None => lights.push(light),
                }
            }
        }
    }
    if extra_suns > 0 {
        notes.push(format!("{extra_suns} more directional light(s) ignored: the first is the sun"));
    }
    (sun, lights)
}
