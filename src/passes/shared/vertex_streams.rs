//! The vertex pool on the GPU as three streams, so that a pass fetches only what it reads:
//! positions (every pass), octahedral normals (shading), and the surface: texture coordinates
//! and tangents, read only where some material samples a texture. A depth-only pass reads 12
//! bytes a vertex and the shading of an untextured scene 16, rather than the 32 of the host's
//! interleaved [`Vertex`].

use crate::gpu::{Buffer, VertexAttribute};
use crate::scene::Vertex;
use ash::vk;
use std::sync::Arc;

/// The vertex buffer binding of each stream, as `gbuffer.vert` and every pass drawing the pool
/// bind them.
pub const POSITIONS: u32 = 0;
/// See [`POSITIONS`].
pub const NORMALS: u32 = 1;
/// See [`POSITIONS`].
pub const SURFACE: u32 = 2;

/// Bytes a vertex of each stream, by binding.
pub const VERTEX_STRIDES: [u32; 3] = [12, 4, std::mem::size_of::<SurfaceVertex>() as u32];

/// A vertex's texture coordinates and tangent, as the surface stream holds them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SurfaceVertex {
    /// [`Vertex::uv`].
    pub uv: [f32; 2],
    /// [`Vertex::tangent`].
    pub tangent: [i16; 4],
}

/// The position attribute (location 0).
pub const POSITION_ATTRIBUTE: VertexAttribute =
    VertexAttribute { location: 0, binding: POSITIONS, format: vk::Format::R32G32B32_SFLOAT, offset: 0 };
/// The octahedral normal attribute (location 1).
pub const NORMAL_ATTRIBUTE: VertexAttribute =
    VertexAttribute { location: 1, binding: NORMALS, format: vk::Format::R16G16_SNORM, offset: 0 };
/// The texture coordinate attribute (location 2).
pub const UV_ATTRIBUTE: VertexAttribute =
    VertexAttribute { location: 2, binding: SURFACE, format: vk::Format::R32G32_SFLOAT, offset: 0 };
/// The tangent attribute (location 3).
pub const TANGENT_ATTRIBUTE: VertexAttribute =
    VertexAttribute { location: 3, binding: SURFACE, format: vk::Format::R16G16B16A16_SNORM, offset: 8 };

/// What a pass fetches of each vertex beyond its position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexFetch {
    /// The normal stream.
    pub normals: bool,
    /// The surface stream (texture coordinates and tangents).
    pub surface: bool,
}

impl VertexFetch {
    /// Every stream.
    pub const ALL: Self = Self { normals: true, surface: true };
    /// Positions alone.
    pub const POSITIONS: Self = Self { normals: false, surface: false };

    /// The attributes `gbuffer.vert` reads with [`VertexFetch::defines`].
    pub fn attributes(self) -> Vec<VertexAttribute> {
        let mut attributes = vec![POSITION_ATTRIBUTE];
        if self.normals {
            attributes.push(NORMAL_ATTRIBUTE);
        }
        if self.surface {
            attributes.extend([UV_ATTRIBUTE, TANGENT_ATTRIBUTE]);
        }
        attributes
    }

    /// `gbuffer.vert`'s defines for what it does not fetch (it then writes a normal of +z, and
    /// texture coordinates of 0 and a tangent of +x, which no shading of such a scene reads).
    pub fn defines(self) -> Vec<(&'static str, &'static str)> {
        let mut defines = Vec::new();
        if !self.normals {
            defines.push(("NO_NORMALS", "1"));
        }
        if !self.surface {
            defines.push(("NO_SURFACE", "1"));
        }
        defines
    }
}

/// The pool's streams on the device, each indexed as the pool is (a mesh's vertex offset is the
/// same in all three).
#[derive(Clone)]
pub struct VertexStreams {
    /// `vec3` positions.
    pub positions: Arc<Buffer>,
    /// Octahedral normals, two snorm16 each.
    pub normals: Arc<Buffer>,
    /// [`SurfaceVertex`]s.
    pub surface: Arc<Buffer>,
}

impl VertexStreams {
    /// The streams by binding.
    pub fn buffers(&self) -> [&Arc<Buffer>; 3] {
        [&self.positions, &self.normals, &self.surface]
    }

    /// Binds the streams at their bindings (a pipeline reads those its attributes name).
    pub fn bind(&self, device: &ash::Device, cmd: vk::CommandBuffer) {
        let handles = self.buffers().map(|b| b.handle());
        // SAFETY: cmd is recording; the buffers live as long as the scene that records with them.
        unsafe { device.cmd_bind_vertex_buffers(cmd, 0, &handles, &[0; 3]) };
    }

    /// Device bytes of the three streams.
    pub fn bytes(&self) -> u64 {
        self.buffers().iter().map(|b| b.size()).sum()
    }
}

/// `vertices` split into the three streams' contents.
pub fn split(vertices: &[Vertex]) -> (Vec<[f32; 3]>, Vec<[i16; 2]>, Vec<SurfaceVertex>) {
    let positions = vertices.iter().map(|v| v.position).collect();
    let normals = vertices.iter().map(|v| v.normal).collect();
    let surface = vertices.iter().map(|v| SurfaceVertex { uv: v.uv, tangent: v.tangent }).collect();
    (positions, normals, surface)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_streams_hold_every_field_of_a_vertex_at_the_attributes_offsets() {
        let v = Vertex { position: [1.0, 2.0, 3.0], normal: [4, -5], uv: [0.25, 0.75], tangent: [6, 7, -8, 32767] };
        let (p, n, s) = split(&[v]);
        assert_eq!((p[0], n[0], s[0].uv, s[0].tangent), (v.position, v.normal, v.uv, v.tangent));
        assert_eq!(std::mem::size_of::<SurfaceVertex>(), 16);
        assert_eq!(VERTEX_STRIDES.iter().sum::<u32>() as usize, std::mem::size_of::<Vertex>());
        let attributes = VertexFetch::ALL.attributes();
        assert_eq!(attributes.len(), 4);
        assert_eq!(VertexFetch::POSITIONS.attributes(), vec![POSITION_ATTRIBUTE]);
        assert_eq!(VertexFetch::POSITIONS.defines().len(), 2);
    }
}
