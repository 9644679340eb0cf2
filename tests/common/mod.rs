//! Shared helpers of the GPU integration tests: every test runs on lavapipe (unless
//! `CULLGRAPH_TEST_DEVICE` names another device) with the validation layer and synchronization
//! validation on, and any validation message fails it.
#![allow(dead_code)]

pub mod cli;
pub mod dense;

use cullgraph::gpu::{Buffer, BufferDesc, ContextOptions, GpuContext, MemoryLocation, ShaderCompiler, ShaderRoot};
use std::ops::Deref;

/// A validated context; dropping it fails the test if the layer reported anything.
pub struct GpuTest {
    ctx: Option<GpuContext>,
    log: cullgraph::gpu::ValidationLog,
}

impl GpuTest {
    /// Creates the context (panics with a hint when Vulkan or the layer is missing).
    pub fn new() -> Self {
        let device = std::env::var("CULLGRAPH_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
        let options = ContextOptions {
            device: device.parse().unwrap(),
            validation: true,
            app_name: "cullgraph-test".into(),
            ..Default::default()
        };
        let ctx = GpuContext::new(&options)
            .unwrap_or_else(|e| panic!("cannot create a validated Vulkan context ({e}); run scripts/install-deps"));
        let log = ctx.validation_log().clone();
        Self { ctx: Some(ctx), log }
    }

    /// The shader compiler over the repository's `shaders/` directory, one for the whole test
    /// binary: its cache then holds every shader once, where a compiler per renderer compiled
    /// them again (on lavapipe most of a small test's time).
    pub fn shaders(&self) -> &'static ShaderCompiler {
        static SHADERS: std::sync::OnceLock<ShaderCompiler> = std::sync::OnceLock::new();
        SHADERS.get_or_init(|| {
            ShaderCompiler::new(ShaderRoot::Directory(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders").into())).unwrap()
        })
    }

    /// Fails now if any validation message arrived so far.
    pub fn assert_clean(&self) {
        let messages = self.log.messages();
        assert!(messages.is_empty(), "{} validation message(s):\n{}", messages.len(), messages.join("\n"));
    }
}

impl Deref for GpuTest {
    type Target = GpuContext;
    fn deref(&self) -> &GpuContext {
        self.ctx.as_ref().expect("context alive until drop")
    }
}

impl Drop for GpuTest {
    fn drop(&mut self) {
        // Destroy the device first (if nothing else holds it) so that leaks reported by
        // vkDestroyDevice count too.
        drop(self.ctx.take());
        if !std::thread::panicking() {
            self.assert_clean();
        }
    }
}

/// A unit quad in the xy plane facing +z, u along +x and v down (glTF's image orientation).
pub fn quad_mesh() -> cullgraph::scene::MeshData {
    use glam::{Vec2, Vec3};
    cullgraph::scene::MeshData {
        positions: vec![
            Vec3::new(-0.5, -0.5, 0.0),
            Vec3::new(0.5, -0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(-0.5, 0.5, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)],
        indices: vec![0, 1, 2, 0, 2, 3],
        tangents: Vec::new(),
        ..Default::default()
    }
}

/// A camera on the +z axis, 3 units out, looking at the origin (where the quad tests put their
/// quads).
pub fn camera_on_z() -> cullgraph::scene::Camera {
    cullgraph::scene::Camera { eye: glam::DVec3::new(0.0, 0.0, 3.0), target: glam::DVec3::ZERO, ..Default::default() }
}

/// A uniform scale by `scale`, then a move to `translation`.
pub fn scaled_at(translation: glam::DVec3, scale: f64) -> cullgraph::scene::Transform {
    cullgraph::scene::Transform { linear: glam::Mat3::from_diagonal(glam::Vec3::splat(scale as f32)), translation }
}

/// An empty scene lit by white sunlight from the camera's side of [`camera_on_z`], so that
/// surfaces facing the camera keep their hue.
pub fn sunlit_scene(name: &str) -> cullgraph::scene::Scene {
    let mut scene = cullgraph::scene::Scene { name: name.into(), ..Default::default() };
    scene.sun.direction = glam::Vec3::new(0.0, 0.0, -1.0);
    scene
}

/// Adds to `scene` a fence material: `columns` vertical bars of a texture, opaque grey and fully
/// transparent by turns, alpha-masked and double-sided (`nearest` or bilinear filtering); returns
/// its index.
pub fn bars_material(scene: &mut cullgraph::scene::Scene, columns: u32, nearest: bool) -> u32 {
    use cullgraph::scene::{texture::Sampler, AlphaMode, Material, Texture, TextureRef};
    let rgba: Vec<u8> = (0..columns * 2)
        .flat_map(|i| if (i % columns).is_multiple_of(2) { [200, 200, 200, 255] } else { [0, 0, 0, 0] })
        .collect();
    let texture = scene.textures.len() as u32;
    scene.textures.push(std::sync::Arc::new(Texture { name: "bars".into(), width: columns, height: 2, rgba }));
    let sampler = Sampler { nearest_mag: nearest, nearest_min: nearest, ..Default::default() };
    let mut fence = Material {
        name: "fence".into(),
        albedo: glam::Vec3::ONE,
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        ..Default::default()
    };
    fence.textures[0] = Some(TextureRef { sampler, ..TextureRef::new(texture) });
    scene.add_material(fence)
}

/// The rgb of pixel (`x`, `y`).
pub fn rgb(image: &cullgraph::render::output::RgbaImage, x: u32, y: u32) -> [u8; 3] {
    let p = image.get_pixel(x, y).0;
    [p[0], p[1], p[2]]
}

/// A unit cube (-0.5..0.5) with per-face normals.
pub fn cube_mesh() -> cullgraph::scene::MeshData {
    use glam::Vec3;
    let mut m = cullgraph::scene::MeshData::default();
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Y, -Vec3::Z),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::Z, -Vec3::X),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, -Vec3::X, Vec3::Y),
    ];
    for (n, u, v) in faces {
        // u x v == n, so (c-u-v, c+u-v, c+u+v, c-u+v) is counter-clockwise seen from outside.
        let base = m.positions.len() as u32;
        let c = n * 0.5;
        for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
            m.positions.push(c + u * a + v * b);
            m.normals.push(n);
        }
        m.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    m
}

/// A small scene: a ground slab and a few colored boxes, lit by the sun and one point light.
pub fn boxes_scene() -> cullgraph::scene::Scene {
    use cullgraph::scene::*;
    use glam::{DVec3, Mat3, Vec3};
    let mut scene = Scene { name: "test boxes".into(), ..Default::default() };
    let cube = scene.add_mesh("cube", &cube_mesh(), "cube").unwrap();
    let grey = scene.add_material(Material {
        name: "ground".into(),
        albedo: Vec3::splat(0.5),
        roughness: 0.9,
        metallic: 0.0,
        double_sided: false,
        ..Default::default()
    });
    let red = scene.add_material(Material {
        name: "red".into(),
        albedo: Vec3::new(0.8, 0.1, 0.1),
        roughness: 0.4,
        metallic: 0.0,
        double_sided: false,
        ..Default::default()
    });
    let blue = scene.add_material(Material {
        name: "blue".into(),
        albedo: Vec3::new(0.1, 0.2, 0.8),
        roughness: 0.3,
        metallic: 0.5,
        double_sided: false,
        ..Default::default()
    });
    let place = |scale: Vec3, at: DVec3, material| Instance {
        transform: Transform { linear: Mat3::from_diagonal(scale), translation: at },
        mesh: cube,
        material,
        flags: 0,
    };
    scene.instances.push(place(Vec3::new(20.0, 0.2, 20.0), DVec3::new(0.0, -0.1, 0.0), grey));
    scene.instances.push(place(Vec3::ONE, DVec3::new(-1.5, 0.5, 0.0), red));
    scene.instances.push(place(Vec3::new(1.0, 2.0, 1.0), DVec3::new(1.5, 1.0, 0.0), blue));
    scene.instances.push(place(Vec3::splat(0.5), DVec3::new(0.0, 0.25, 1.5), red));
    scene.lights.push(PointLight::point(DVec3::new(0.0, 2.0, 2.0), Vec3::new(4.0, 3.0, 2.0), 8.0));
    scene
}

/// Camera looking at the boxes scene.
pub fn boxes_camera() -> cullgraph::scene::Camera {
    cullgraph::scene::Camera {
        eye: glam::DVec3::new(3.0, 3.0, 6.0),
        target: glam::DVec3::new(0.0, 0.5, 0.0),
        ..Default::default()
    }
}

/// The built-in city with `instances` instances, and its default camera for a `size` image.
pub fn city_view(instances: usize, size: (u32, u32)) -> (cullgraph::scene::Scene, cullgraph::scene::Camera) {
    use cullgraph::scene::{source::LoadOptions, SceneSource};
    let scene = SceneSource::Builtin("city".into())
        .load(&LoadOptions { instances: Some(instances), ..Default::default() })
        .unwrap();
    let camera = scene.default_camera(size.0 as f32 / size.1 as f32);
    (scene, camera)
}

/// A host-readable buffer of `bytes` that copies land in (it may also be bound as storage).
pub fn readback_buffer(ctx: &GpuContext, name: &str, bytes: u64) -> Buffer {
    Buffer::new(
        ctx,
        &BufferDesc {
            name,
            size: bytes,
            usage: ash::vk::BufferUsageFlags::TRANSFER_DST | ash::vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::GpuToCpu,
        },
    )
    .unwrap()
}

/// The buffer of a glTF triangle (three VEC3 positions, 36 bytes: (0,0,0), (1,0,0), (0,1,0)) as
/// a data URI, for small glTF documents written by tests.
pub fn triangle_data_uri() -> String {
    use base64::Engine;
    let bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin))
}

/// One frame of each renderer's views (`ids`, each with the camera at its place in `cameras`):
/// per renderer, each view's stats and RGBA bytes.
pub fn render_each_views(
    renderers: &mut [(cullgraph::render::Renderer, Vec<cullgraph::render::ViewId>)],
    cameras: &[cullgraph::scene::Camera],
) -> Vec<Vec<(cullgraph::stats::FrameStats, Vec<u8>)>> {
    renderers
        .iter_mut()
        .map(|(r, ids)| {
            let frames: Vec<_> = ids.iter().copied().zip(cameras).collect();
            r.render_views_to_rgba8(&frames).unwrap()
        })
        .collect()
}
