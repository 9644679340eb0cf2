//! Textures of a scene and how materials refer to them.
//!
//! A [`Texture`] is decoded RGBA8 pixels, whatever the file held (RGB and grey images are
//! expanded: the devices we run on cannot sample RGB8). Whether its texels are sRGB or linear is
//! not the texture's property but its use's: a material's base colour and emissive textures are
//! sRGB, the others linear ([`TextureSlot::srgb`]), and the GPU samples one image through both
//! kinds of view.

use glam::{Vec2, Vec4};

/// Decoded pixels of one image, RGBA8, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Name for messages (the glTF image's name or URI, or its index).
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

impl Texture {
    /// The texture shown where an image could not be used: an 8x8 magenta and black checker,
    /// unmistakable in any lighting.
    pub fn placeholder(name: &str) -> Self {
        let rgba = (0..64u32)
            .flat_map(|i| if (i % 8 + i / 8) % 2 == 0 { [255, 0, 255, 255] } else { [0, 0, 0, 255] })
            .collect();
        Self { name: format!("{name} (placeholder)"), width: 8, height: 8, rgba }
    }

    /// A texture of one colour (1x1).
    pub fn solid(name: &str, rgba: [u8; 4]) -> Self {
        Self { name: name.into(), width: 1, height: 1, rgba: rgba.to_vec() }
    }

    /// The texel at (`x`, `y`).
    pub fn texel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [self.rgba[i], self.rgba[i + 1], self.rgba[i + 2], self.rgba[i + 3]]
    }
}

/// How texture coordinates outside [0, 1] are brought back (glTF sampler wrap modes). The
/// discriminants are what the shaders read (`shaders/common/textures.glsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u32)]
pub enum Wrap {
    /// Tiles.
    #[default]
    Repeat = 0,
    /// Tiles, every other tile mirrored.
    MirroredRepeat = 1,
    /// Takes the edge texel.
    ClampToEdge = 2,
}

/// How a texture is filtered and wrapped (a glTF sampler).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    /// Wrap of u.
    pub wrap_u: Wrap,
    /// Wrap of v.
    pub wrap_v: Wrap,
    /// Nearest texel when magnified (otherwise bilinear).
    pub nearest_mag: bool,
    /// Nearest texel and mip when minified (otherwise trilinear, anisotropic where the device
    /// has it).
    pub nearest_min: bool,
}

impl Default for Sampler {
    fn default() -> Self {
        Self { wrap_u: Wrap::Repeat, wrap_v: Wrap::Repeat, nearest_mag: false, nearest_min: false }
    }
}

/// An affine map of texture coordinates (`KHR_texture_transform`): scale, then rotate, then
/// offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Added last.
    pub offset: Vec2,
    /// Counter-clockwise rotation in radians (in uv space, v pointing down).
    pub rotation: f32,
    /// Applied first.
    pub scale: Vec2,
}

impl Default for UvTransform {
    fn default() -> Self {
        Self { offset: Vec2::ZERO, rotation: 0.0, scale: Vec2::ONE }
    }
}

impl UvTransform {
    /// The two rows of the 2x3 matrix the extension defines: `uv' = (row0 . (u, v, 1), row1 .
    /// (u, v, 1))`.
    pub fn rows(&self) -> [Vec4; 2] {
        let (s, c) = self.rotation.sin_cos();
        [
            Vec4::new(c * self.scale.x, s * self.scale.y, self.offset.x, 0.0),
            Vec4::new(-s * self.scale.x, c * self.scale.y, self.offset.y, 0.0),
        ]
    }

    /// Applied to `uv`.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [r0, r1] = self.rows();
        Vec2::new(r0.x * uv.x + r0.y * uv.y + r0.z, r1.x * uv.x + r1.y * uv.y + r1.z)
    }
}

/// A material's use of a texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::scene::Scene::textures`].
    pub texture: u32,
    /// Filtering and wrapping.
    pub sampler: Sampler,
    /// Texture-coordinate transform.
    pub transform: UvTransform,
}

impl TextureRef {
    /// `texture` with the default sampler and no transform.
    pub fn new(texture: u32) -> Self {
        Self { texture, sampler: Sampler::default(), transform: UvTransform::default() }
    }
}

/// The five textures of a glTF metallic-roughness material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSlot {
    /// Base colour (sRGB) and alpha.
    BaseColor,
    /// Roughness in G, metalness in B (linear).
    MetallicRoughness,
    /// Tangent-space normal (linear).
    Normal,
    /// Ambient occlusion in R (linear).
    Occlusion,
    /// Emitted colour (sRGB).
    Emissive,
}

impl TextureSlot {
    /// Every slot, in the order the GPU material lists them.
    pub const ALL: [TextureSlot; 5] = [
        TextureSlot::BaseColor,
        TextureSlot::MetallicRoughness,
        TextureSlot::Normal,
        TextureSlot::Occlusion,
        TextureSlot::Emissive,
    ];

    /// Whether the slot's texels are sRGB-encoded colour.
    pub fn srgb(self) -> bool {
        matches!(self, TextureSlot::BaseColor | TextureSlot::Emissive)
    }

    /// The glTF name, for messages.
    pub fn name(self) -> &'static str {
        match self {
            TextureSlot::BaseColor => "baseColorTexture",
            TextureSlot::MetallicRoughness => "metallicRoughnessTexture",
            TextureSlot::Normal => "normalTexture",
            TextureSlot::Occlusion => "occlusionTexture",
            TextureSlot::Emissive => "emissiveTexture",
        }
    }
}

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// Fragments with alpha below the cutoff are discarded (foliage, fences).
    Mask {
        /// `alphaCutoff` (glTF default 0.5).
        cutoff: f32,
    },
    /// Blended over what is behind (glass, smoke).
    Blend,
}
