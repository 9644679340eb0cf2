//! Procedural scene generators, deterministic for a given [`LoadOptions::seed`]:
//!
//! - `builtin:city`: a grid of city blocks and streets with occluding buildings, street
//!   furniture, cars and street lamps ([`city`]).
//! - `builtin:field`: many distinct mesh kinds scattered with random rotations and scales,
//!   mirrored ones included ([`field`]).
//! - `builtin:crowd`: skinned stalks swaying through a clip, for posed instances ([`crowd`]).
//! - `builtin:dense`: sculpted props of 50 000 to 100 000 triangles each, for levels of
//!   detail ([`dense`]).
//!
//! [`traffic`] drives vehicles through a world made from the city.
//!
//! Instances share a few dozen meshes (or `kinds` meshes for the field), so generation is O(n)
//! in the instance count with little work per instance.

pub mod city;
pub mod crowd;
pub mod dense;
pub mod field;
pub mod lights;
pub mod shapes;
pub mod traffic;

use super::error::SceneError;
use super::source::LoadOptions;
use super::{Instance, Material, Scene};
use glam::Vec3;

/// Names of the built-in scenes.
pub const AVAILABLE: &[&str] = &["builtin:city", "builtin:field", "builtin:crowd", "builtin:dense"];
/// Largest accepted `instances` option: the most a scene may hold.
pub const MAX_INSTANCES: usize = super::validate::MAX_INSTANCES;
/// Largest accepted `kinds` option.
pub const MAX_KINDS: usize = 100_000;
/// Largest accepted `lights` option.
pub const MAX_LIGHTS: usize = 1_000_000;

/// Generates `builtin:NAME` (`name` with or without the `builtin:` prefix).
pub fn generate(name: &str, options: &LoadOptions) -> Result<Scene, SceneError> {
    match name.strip_prefix("builtin:").unwrap_or(name) {
        "city" => city::generate(options),
        "field" => field::generate(options),
        "crowd" => crowd::generate(options),
        "dense" => dense::generate(options),
        other => Err(SceneError::Builtin(format!(
            "unknown built-in scene 'builtin:{other}'; available: {}",
            AVAILABLE.join(", ")
        ))),
    }
}

/// Reads a count option: `value` or `default`, refused outside `min..=max` with a message that
/// names the parameter and the scene.
pub(crate) fn count_option(
    scene: &str,
    parameter: &str,
    value: Option<usize>,
    default: usize,
    min: usize,
    max: usize,
) -> Result<usize, SceneError> {
    let v = value.unwrap_or(default);
    if v < min || v > max {
        return Err(SceneError::Builtin(format!(
            "builtin:{scene}: {parameter} = {v} is out of range (it must be between {min} and {max})"
        )));
    }
    Ok(v)
}

/// Room for `n` instances, refused with an error instead of aborting when memory is short.
pub(crate) fn instance_storage(scene: &str, n: usize) -> Result<Vec<Instance>, SceneError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| SceneError::Builtin(format!("builtin:{scene}: cannot allocate memory for {n} instances")))?;
    Ok(v)
}

/// A material shorthand.
pub(crate) fn material(name: &str, albedo: [f32; 3], roughness: f32, metallic: f32) -> Material {
    Material { name: name.into(), albedo: Vec3::from_array(albedo), roughness, metallic, ..Default::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_list_the_available_scenes() {
        let e = generate("x", &LoadOptions::default()).unwrap_err().to_string();
        assert_eq!(
            e,
            "unknown built-in scene 'builtin:x'; available: builtin:city, builtin:field, builtin:crowd, builtin:dense"
        );
        let e = generate("builtin:nope", &LoadOptions::default()).unwrap_err().to_string();
        assert!(e.contains("'builtin:nope'"), "{e}");
    }
}
