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

/// A UV sphere of `rings` x `segments` quads (radius 1): a mesh to register at run time.
pub fn sphere(rings: u32, segments: u32) -> cullgraph::scene::MeshData {
    let mut positions = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push(glam::Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    let row = segments + 1;
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            indices.extend([a, a + 1, b, a + 1, b + 1, b]);
        }
    }
    cullgraph::scene::MeshData { normals: positions.clone(), positions, indices, ..Default::default() }
}
