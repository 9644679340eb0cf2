//! glTF 2.0 import (stub: filled in by the scene work).

use super::error::SceneError;
use super::source::LoadOptions;
use super::Scene;
use std::path::Path;

/// Loads a glTF 2.0 file.
pub fn load(path: &Path, _options: &LoadOptions) -> Result<Scene, SceneError> {
    Err(SceneError::Import { file: path.display().to_string(), message: "glTF import not implemented yet".into() })
}
