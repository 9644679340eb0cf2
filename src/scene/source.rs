//! Where a scene comes from: `builtin:NAME` generators or a glTF file, plus generator options.

use super::error::SceneError;
use super::Scene;
use std::path::PathBuf;
use std::str::FromStr;

/// Options that shape a loaded or generated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Number of instances for generators (each has its own default).
    pub instances: Option<usize>,
    /// Number of distinct mesh kinds for generators that take it.
    pub kinds: Option<usize>,
    /// Number of point lights to place (generators; for files, added only when the file has none).
    pub lights: Option<usize>,
    /// Random seed of generators.
    pub seed: u64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { instances: None, kinds: None, lights: None, seed: 1 }
    }
}

/// A scene to load: a built-in generator or a glTF 2.0 file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneSource {
    /// `builtin:NAME`.
    Builtin(String),
    /// A `.gltf` or `.glb` file.
    File(PathBuf),
}

impl FromStr for SceneSource {
    type Err = SceneError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.strip_prefix("builtin:") {
            Some(name) => Ok(SceneSource::Builtin(name.to_string())),
            None if s.is_empty() => Err(SceneError::Builtin("empty scene name".into())),
            None => Ok(SceneSource::File(PathBuf::from(s))),
        }
    }
}

impl SceneSource {
    /// Loads or generates the scene, then validates it.
    pub fn load(&self, options: &LoadOptions) -> Result<Scene, SceneError> {
        let scene = match self {
            SceneSource::Builtin(name) => super::procedural::generate(name, options)?,
            SceneSource::File(path) => super::gltf_import::load(path, options)?,
        };
        super::validate::validate_scene(&scene)?;
        Ok(scene)
    }
}
