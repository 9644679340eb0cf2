//! The dense scene the level-of-detail and cluster tests render, seen from close by.

use cullgraph::render::GraphSpec;
use cullgraph::scene::source::LoadOptions;
use cullgraph::scene::{Camera, Scene, SceneSource};
use glam::DVec3;

/// `builtin:dense` with `instances` props.
pub fn dense(instances: usize) -> Scene {
    SceneSource::Builtin("dense".into())
        .load(&LoadOptions { instances: Some(instances), ..Default::default() })
        .unwrap()
}

/// A camera among the first props, where they are a few hundred pixels tall.
pub fn near_camera() -> Camera {
    Camera { eye: DVec3::new(14.0, 5.0, 14.0), target: DVec3::new(0.0, 1.0, 0.0), ..Default::default() }
}

/// The shipped graph `name` with its `lod_threshold` param at `threshold` pixels.
pub fn graph(name: &str, threshold: f64) -> GraphSpec {
    GraphSpec::builtin(name).unwrap().with_overrides([("lod_threshold".into(), format!("{threshold:?}"))])
}
