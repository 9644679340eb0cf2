//! Frozen culling: the instances the camera drew at one frame stay, every other one is hidden,
//! and the camera flies on, so that what culling removed shows as holes seen from elsewhere.
//!
//! The drawn set is exact (read back from the frame's draw lists), and hiding goes through the
//! live world (each hidden instance shows an empty mesh until thawed), so the renderer and its
//! graphs stay exactly as they are.

use cullgraph::gpu::ShaderCompiler;
use cullgraph::render::{Renderer, ViewId};
use cullgraph::scene::world::{InstanceHandle, World};
use cullgraph::scene::{Camera, MeshData};
use cullgraph::{Error, Result};
use std::collections::HashSet;

/// What freezing changed, to be put back.
pub struct Frozen {
    /// The hidden instances and the meshes they showed.
    hidden: Vec<(InstanceHandle, u32)>,
    /// The empty mesh they show meanwhile.
    blank: u32,
    kept: usize,
}

impl Frozen {
    /// Renders `camera`'s frame, reads back what it drew, and hides everything else.
    pub fn capture(
        world: &mut World,
        renderer: &mut Renderer,
        shaders: &ShaderCompiler,
        camera: &Camera,
    ) -> Result<Self> {
        renderer.capture_draw_lists(true)?;
        let drawn = renderer.render(camera).and_then(|_| renderer.drawn_handles(ViewId::MAIN));
        renderer.capture_draw_lists(false)?;
        let drawn: HashSet<InstanceHandle> = drawn?
            .ok_or_else(|| Error::Invalid("the frame's draw lists were not captured".into()))?
            .into_iter()
            .collect();
        // One triangle far below a pixel (a mesh needs some area): the hidden instances draw
        // nothing visible, and keep their handles, transforms and materials for the thaw.
        let empty = MeshData {
            positions: vec![glam::Vec3::ZERO, glam::Vec3::X * 1e-6, glam::Vec3::Y * 1e-6],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        let blank = world.add_mesh("view: hidden by frozen culling", &empty)?;
        let mut hidden = Vec::new();
        for handle in world.handles().collect::<Vec<_>>() {
            if !drawn.contains(&handle) {
                hidden.push((handle, world.instance(handle)?.mesh));
            }
        }
        let changes: Vec<(InstanceHandle, u32)> = hidden.iter().map(|&(h, _)| (h, blank)).collect();
        world.set_meshes(&changes)?;
        renderer.sync(shaders, world)?;
        Ok(Self { hidden, blank, kept: drawn.len() })
    }

    /// Instances drawn at the frozen frame.
    pub fn kept(&self) -> usize {
        self.kept
    }

    /// Instances hidden.
    pub fn hidden(&self) -> usize {
        self.hidden.len()
    }

    /// Shows the hidden instances that still exist again; returns how many.
    pub fn thaw(self, world: &mut World) -> Result<usize> {
        let back: Vec<(InstanceHandle, u32)> =
            self.hidden.into_iter().filter(|&(h, _)| world.instance(h).is_ok_and(|i| i.mesh == self.blank)).collect();
        world.set_meshes(&back)?;
        // Instances removed meanwhile leave the blank mesh unused.
        if !world.handles().any(|h| world.instance(h).is_ok_and(|i| i.mesh == self.blank)) {
            world.remove_mesh(self.blank)?;
        }
        Ok(back.len())
    }
}
