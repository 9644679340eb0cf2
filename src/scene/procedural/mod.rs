//! Procedural scene generators (stub: filled in by the scene work).

use super::error::SceneError;
use super::source::LoadOptions;
use super::Scene;

/// Generates `builtin:NAME`.
pub fn generate(name: &str, _options: &LoadOptions) -> Result<Scene, SceneError> {
    Err(SceneError::Builtin(format!("unknown built-in scene 'builtin:{name}'")))
}
