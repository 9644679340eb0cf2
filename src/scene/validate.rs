//! Whole-scene checks run after every load (stub: filled in by the scene work).

use super::error::SceneError;
use super::Scene;

/// Checks cross references and finiteness of a scene.
pub fn validate_scene(_scene: &Scene) -> Result<(), SceneError> {
    Ok(())
}
