//! A scene's textures on the GPU, in a form every device we target can sample without
//! descriptor indexing: one 2D array image per size class ([`TEXTURE_CLASSES`] square sides,
//! 16 to 2048 texels), each texture resampled to its class's side and given a layer, with its
//! full mip chain. A material names a texture by class and layer; shaders pick the class's
//! array in a `switch` over constant indices (`shaders/common/textures.glsl`), and the layer as
//! the array coordinate. Lavapipe (no dynamic indexing of sampled-image arrays) and NVIDIA take
//! the same path, so both give the same image.
//!
//! A class holds at most the device's `maxImageArrayLayers` layers (2048 on lavapipe and
//! NVIDIA). A scene with more textures of one class keeps one layer fewer of them, in scene
//! order, and shows the placeholder checker in the last layer for the rest, with a warning
//! naming each of them ([`GpuTextures::placeholder_textures`]). A second array per class is no
//! way out: the arrays take 16 of the 32 push descriptors lavapipe allows a pass already, and
//! 16 more would not fit beside a textured pass's own bindings.
//!
//! Mips are box-filtered on the CPU at upload, in linear light for textures that some material
//! uses as colour (base colour, emissive: sRGB) and in stored values otherwise. The alpha of a
//! masked material's base colour is then scaled per mip so that the share of texels that pass
//! its cutoff stays that of mip 0 (Castaño's coverage-preserving mips): box filtering alone
//! thins foliage and fences until they vanish in the distance.

use crate::gpu::texture_array::TextureArray;
use crate::gpu::{Bind, Edits, GpuContext, Sampler, UploadBatch};
use crate::scene::{Scene, Texture, TextureSlot};
use ash::vk;
use std::sync::Arc;

/// Size classes: sides 16, 32, ..., 2048.
pub const TEXTURE_CLASSES: usize = 8;
/// The smallest class's side (smaller textures are enlarged to it).
pub const MIN_TEXTURE_SIDE: u32 = 16;
/// The largest class's side (larger textures are reduced to it).
pub const MAX_TEXTURE_SIDE: u32 = MIN_TEXTURE_SIDE << (TEXTURE_CLASSES - 1);
/// Where a material has no texture in a slot.
pub const NO_TEXTURE: u32 = u32::MAX;
/// The first binding of the texture arrays (`TEXTURE_BINDING` in `shaders/common/textures.glsl`):
/// per class, its sRGB view then its linear view.
pub const TEXTURE_BINDING: u32 = 16;

/// The class of a `width` x `height` texture: the smallest square side that holds its larger
/// side, within the classes.
pub fn class_of(width: u32, height: u32) -> usize {
    let side = width.max(height).clamp(MIN_TEXTURE_SIDE, MAX_TEXTURE_SIDE).next_power_of_two();
    (side / MIN_TEXTURE_SIDE).trailing_zeros() as usize
}

/// The side of class `class`.
pub fn class_side(class: usize) -> u32 {
    MIN_TEXTURE_SIDE << class
}

/// See the module documentation.
pub struct GpuTextures {
    /// One array per class (a 1x1 array of one layer for a class no texture uses), shared
    /// with the textures that follow these in a changing world where they did not change.
    arrays: Vec<Arc<TextureArray>>,
    /// The sampler the bindings name.
    sampler: Arc<Sampler>,
    /// The arrays' bindings, made once: every geometry pass pushes them per draw list.
    bindings: Vec<Bind>,
    /// Per scene texture: `class << 16 | layer`.
    placement: Vec<u32>,
    /// Scene textures that did not fit their class's array and show the placeholder.
    placeholder_textures: Vec<u32>,
    /// Per scene texture, how its mips were made: (sRGB, mask cutoff).
    made: Vec<MipsMade>,
    /// Per class, the layers given out so far (the next new one), and those given back.
    layers_used: Vec<u32>,
    free_layers: Vec<Vec<u32>>,
}

/// How a texture's mips were made: averaged as sRGB colour or not, with the coverage of which
/// mask cutoff kept (its bits; `None`: no masked material takes it as base colour).
type MipsMade = (bool, Option<u32>);

/// Which layer of which class every texture gets, when a class holds at most `capacity` layers.
#[derive(Debug, PartialEq)]
struct Layout {
    /// Per class, the scene textures that get a layer, in layer order.
    members: Vec<Vec<usize>>,
    /// Per class, whether its last layer is the placeholder of the textures that did not fit.
    placeholder: Vec<bool>,
    /// Per scene texture: `class << 16 | layer`.
    placement: Vec<u32>,
    /// Scene textures that did not fit and show their class's placeholder layer.
    overflow: Vec<usize>,
}

impl Layout {
    /// Textures of the given sizes, in scene order; `capacity` is at least 1.
    fn new(sizes: impl Iterator<Item = (u32, u32)>, capacity: usize) -> Self {
        let classes: Vec<usize> = sizes.map(|(w, h)| class_of(w, h)).collect();
        let mut wanted = [0usize; TEXTURE_CLASSES];
        for &c in &classes {
            wanted[c] += 1;
        }
        // A full class keeps capacity - 1 textures and the placeholder.
        let placeholder: Vec<bool> = wanted.iter().map(|&n| n > capacity).collect();
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); TEXTURE_CLASSES];
        let mut placement = Vec::with_capacity(classes.len());
        let mut overflow = Vec::new();
        for (i, &c) in classes.iter().enumerate() {
            let room = if placeholder[c] { capacity - 1 } else { capacity };
            let layer = if members[c].len() < room {
                members[c].push(i);
                members[c].len() - 1
            } else {
                overflow.push(i);
                room
            };
            placement.push(((c as u32) << 16) | layer as u32);
        }
        Self { members, placeholder, placement, overflow }
    }
}

impl GpuTextures {
    /// Resamples, mips and queues the upload of every texture of `scene`.
    pub fn upload(ctx: &GpuContext, scene: &Scene, batch: &mut UploadBatch) -> crate::Result<Self> {
        let srgb = srgb_uses(scene);
        let cutoffs = mask_cutoffs(scene);
        // The layer is 16 bits of a placement.
        let capacity = (ctx.caps().limits.max_image_array_layers as usize).clamp(1, 1 << 16);
        let placed = Layout::new(scene.textures.iter().map(|t| (t.width, t.height)), capacity);
        if !placed.overflow.is_empty() {
            let names: Vec<String> =
                placed.overflow.iter().map(|&i| format!("texture #{i} '{}'", scene.textures[i].name)).collect();
            tracing::warn!(
                "{} textures did not fit the texture arrays (at most {capacity} layers a size class on this device) and show the placeholder: {}",
                names.len(),
                names.join(", ")
            );
        }
        let placeholder = Texture::placeholder("textures beyond a full size class");
        let mut arrays = Vec::with_capacity(TEXTURE_CLASSES);
        let mut layers_used = Vec::with_capacity(TEXTURE_CLASSES);
        for (class, ids) in placed.members.iter().enumerate() {
            if ids.is_empty() {
                let array = TextureArray::new(ctx, &format!("textures {class} (unused)"), 1, 1)?;
                queue(ctx, batch, &array, &[vec![255u8; 4]])?;
                arrays.push(Arc::new(array));
                layers_used.push(0);
                continue;
            }
            let side = class_side(class);
            let mut layers: Vec<Vec<u8>> = ids
                .iter()
                .map(|&i| mip_chain(&resample(&scene.textures[i], side), side, srgb[i], cutoffs[i]))
                .collect();
            if placed.placeholder[class] {
                layers.push(mip_chain(&resample(&placeholder, side), side, false, None));
            }
            let array = TextureArray::new(ctx, &format!("textures {side}x{side}"), side, layers.len() as u32)?;
            queue(ctx, batch, &array, &layers)?;
            arrays.push(Arc::new(array));
            layers_used.push(layers.len() as u32);
        }
        let sampler = Arc::new(texture_sampler(ctx)?);
        let placeholder_textures = placed.overflow.iter().map(|&i| i as u32).collect();
        let made = srgb.iter().zip(&cutoffs).map(|(&s, c)| (s, c.map(f32::to_bits))).collect();
        Ok(Self {
            bindings: bindings(&arrays, &sampler),
            arrays,
            sampler,
            placement: placed.placement,
            placeholder_textures,
            made,
            layers_used,
            free_layers: vec![Vec::new(); TEXTURE_CLASSES],
        })
    }

    /// Scene textures that did not fit their size class's array (more than the device's
    /// `maxImageArrayLayers` textures of that class) and show the placeholder checker instead.
    pub fn placeholder_textures(&self) -> &[u32] {
        &self.placeholder_textures
    }

    /// Where scene texture `texture` lives: `class << 16 | layer`.
    pub fn placement(&self, texture: u32) -> u32 {
        self.placement.get(texture as usize).copied().unwrap_or(NO_TEXTURE)
    }

    /// Every placement, by scene texture.
    pub fn placements(&self) -> &[u32] {
        &self.placement
    }

    /// The bindings of `shaders/common/textures.glsl` ([`TEXTURE_BINDING`] on).
    pub fn bindings(&self) -> &[Bind] {
        &self.bindings
    }

    /// Device bytes of the texture arrays.
    pub fn bytes(&self) -> u64 {
        self.arrays.iter().map(|a| a.bytes()).sum()
    }

    /// The textures of a changing world after its textures `changed` (registered or removed)
    /// or the materials that use them did: only the textures that changed, and those whose
    /// mips a material now wants made otherwise, are made and queued on `edits`, each into a
    /// layer of its class (its own when it stays in its class, else a free one); a class out
    /// of layers grows, its layers carried over on the GPU. `None` when a class would need
    /// more layers than the device allows (the textures are then laid out anew, with
    /// placeholders, by [`GpuTextures::upload`]).
    pub fn updated(
        &self,
        ctx: &GpuContext,
        scene: &Scene,
        changed: &[u32],
        edits: &mut Edits,
    ) -> crate::Result<Option<Self>> {
        if !self.placeholder_textures.is_empty() {
            return Ok(None);
        }
        let srgb = srgb_uses(scene);
        let cutoffs = mask_cutoffs(scene);
        let wanted = |t: usize| (srgb[t], cutoffs[t].map(f32::to_bits));
        let count = scene.textures.len();
        let mut redo: Vec<usize> = changed.iter().map(|&t| t as usize).filter(|&t| t < count).collect();
        redo.extend((0..count).filter(|&t| self.made.get(t) != Some(&wanted(t))));
        redo.sort_unstable();
        redo.dedup();
        let capacity = (ctx.caps().limits.max_image_array_layers as usize).clamp(1, 1 << 16) as u32;
        let mut next = Self {
            arrays: self.arrays.clone(),
            sampler: self.sampler.clone(),
            bindings: self.bindings.clone(),
            placement: self.placement.clone(),
            placeholder_textures: Vec::new(),
            made: self.made.clone(),
            layers_used: self.layers_used.clone(),
            free_layers: self.free_layers.clone(),
        };
        next.placement.resize(count, NO_TEXTURE);
        next.made.resize(count, (false, None));
        for &t in &redo {
            let texture = &scene.textures[t];
            let class = class_of(texture.width, texture.height);
            let old = next.placement[t];
            if old == NO_TEXTURE || (old >> 16) as usize != class {
                if old != NO_TEXTURE {
                    next.free_layers[(old >> 16) as usize].push(old & 0xFFFF);
                }
                let layer = match next.free_layers[class].pop() {
                    Some(layer) => layer,
                    None => {
                        next.layers_used[class] += 1;
                        next.layers_used[class] - 1
                    }
                };
                if layer >= capacity {
                    return Ok(None);
                }
                next.placement[t] = (class as u32) << 16 | layer;
            }
            next.made[t] = wanted(t);
        }
        let mut grew = false;
        for class in 0..TEXTURE_CLASSES {
            let (side, needed) = (class_side(class), next.layers_used[class]);
            let old = &next.arrays[class];
            // A class no texture used until now holds a 1x1 stand-in, nothing to carry.
            let held = if old.size() == side { old.layers() } else { 0 };
            if needed <= held {
                continue;
            }
            let layers = (needed + needed / 2 + 4).min(capacity);
            let array = TextureArray::new(ctx, &format!("textures {side}x{side}"), side, layers)?;
            edits.carry_layers((held > 0).then(|| old.clone()), &array);
            next.arrays[class] = Arc::new(array);
            grew = true;
        }
        if grew {
            next.bindings = bindings(&next.arrays, &next.sampler);
        }
        for &t in &redo {
            let (class, layer) = ((next.placement[t] >> 16) as usize, next.placement[t] & 0xFFFF);
            let side = class_side(class);
            let chain = mip_chain(&resample(&scene.textures[t], side), side, srgb[t], cutoffs[t]);
            edits.write_layer(&next.arrays[class], layer, &chain);
        }
        Ok(Some(next))
    }

    /// Whether `other` places every texture where these do (materials then need no rewrite).
    pub fn same_placements(&self, other: &GpuTextures) -> bool {
        self.placement == other.placement
    }
}

/// The sampler of every texture array: trilinear, repeating.
fn texture_sampler(ctx: &GpuContext) -> crate::Result<Sampler> {
    // Anisotropic filtering keeps grazing surfaces sharp where the GPU filters in hardware;
    // a CPU rasterizer (lavapipe) takes dozens of times longer per texel with it, so there
    // textures are filtered trilinearly.
    let anisotropic = ctx.caps().kind != vk::PhysicalDeviceType::CPU;
    Ok(Sampler::new(
        ctx,
        &vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .anisotropy_enable(anisotropic)
            .max_anisotropy(ctx.caps().limits.max_sampler_anisotropy.min(8.0))
            .max_lod(vk::LOD_CLAMP_NONE),
    )?)
}

/// The bindings of `shaders/common/textures.glsl`: per class, its sRGB then its linear view.
fn bindings(arrays: &[Arc<TextureArray>], sampler: &Sampler) -> Vec<Bind> {
    let layout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    arrays
        .iter()
        .enumerate()
        .flat_map(|(c, a)| {
            let at = TEXTURE_BINDING + 2 * c as u32;
            [
                Bind::Sampled(at, a.srgb_view(), sampler.handle(), layout),
                Bind::Sampled(at + 1, a.linear_view(), sampler.handle(), layout),
            ]
        })
        .collect()
}

/// Per scene texture, whether a material samples it as sRGB colour.
fn srgb_uses(scene: &Scene) -> Vec<bool> {
    let mut srgb = vec![false; scene.textures.len()];
    for m in &scene.materials {
        for slot in TextureSlot::ALL.into_iter().filter(|s| s.srgb()) {
            if let Some(t) = m.texture(slot).and_then(|t| srgb.get_mut(t.texture as usize)) {
                *t = true;
            }
        }
    }
    srgb
}

/// Per scene texture, the alpha cutoff of the first masked material that takes it as base
/// colour (`None`: no masked material does).
fn mask_cutoffs(scene: &Scene) -> Vec<Option<f32>> {
    let mut cutoffs = vec![None; scene.textures.len()];
    for m in &scene.materials {
        let crate::scene::AlphaMode::Mask { cutoff } = m.alpha_mode else { continue };
        if let Some(c) = m.texture(TextureSlot::BaseColor).and_then(|t| cutoffs.get_mut(t.texture as usize)) {
            c.get_or_insert(cutoff);
        }
    }
    cutoffs
}

/// The share of `rgba`'s texels whose alpha, scaled by `scale`, reaches `cutoff`.
fn coverage(rgba: &[u8], cutoff: f32, scale: f32) -> f32 {
    let texels = rgba.len() / 4;
    let kept = rgba.chunks_exact(4).filter(|t| t[3] as f32 / 255.0 * scale >= cutoff).count();
    kept as f32 / texels.max(1) as f32
}

/// Scales the alpha of `rgba` so that its coverage at `cutoff` is as near `target` as a
/// bisection of the scale finds.
fn preserve_coverage(rgba: &mut [u8], cutoff: f32, target: f32) {
    let (mut low, mut high) = (0.0f32, 4.0f32);
    for _ in 0..16 {
        let mid = (low + high) / 2.0;
        if coverage(rgba, cutoff, mid) < target {
            low = mid;
        } else {
            high = mid;
        }
    }
    let scale = if (coverage(rgba, cutoff, low) - target).abs() < (coverage(rgba, cutoff, high) - target).abs() {
        low
    } else {
        high
    };
    for t in rgba.chunks_exact_mut(4) {
        t[3] = (t[3] as f32 * scale).round().clamp(0.0, 255.0) as u8;
    }
}

/// `texture` as `side` x `side` RGBA8 texels.
fn resample(texture: &Texture, side: u32) -> std::borrow::Cow<'_, [u8]> {
    if texture.width == side && texture.height == side {
        return texture.rgba.as_slice().into();
    }
    let Some(image) =
        image::ImageBuffer::<image::Rgba<u8>, &[u8]>::from_raw(texture.width, texture.height, &texture.rgba)
    else {
        return vec![255; (side * side * 4) as usize].into();
    };
    image::imageops::resize(&image, side, side, image::imageops::FilterType::Triangle).into_raw().into()
}

fn srgb_to_linear(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f32) -> u8 {
    let s = if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Mip 0 (`side` x `side`) followed by every smaller mip down to 1x1, each the 2x2 box average
/// of the one above (colour channels in linear light where `srgb`; alpha always linear), with
/// the alpha of each mip scaled to keep mip 0's coverage at `mask_cutoff` where it is given.
fn mip_chain(level0: &[u8], side: u32, srgb: bool, mask_cutoff: Option<f32>) -> Vec<u8> {
    let target = mask_cutoff.map(|c| (c, coverage(level0, c, 1.0)));
    let mut out = level0.to_vec();
    let mut prev = level0.to_vec();
    let mut size = side;
    while size > 1 {
        let half = size / 2;
        let mut next = vec![0u8; (half * half * 4) as usize];
        for y in 0..half {
            for x in 0..half {
                for c in 0..4 {
                    let at = |dx: u32, dy: u32| prev[(((2 * y + dy) * size + 2 * x + dx) * 4 + c) as usize];
                    let texels = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
                    next[((y * half + x) * 4 + c) as usize] = if srgb && c < 3 {
                        linear_to_srgb(texels.iter().map(|&v| srgb_to_linear(v)).sum::<f32>() / 4.0)
                    } else {
                        ((texels.iter().map(|&v| v as u32).sum::<u32>() + 2) / 4) as u8
                    };
                }
            }
        }
        if let Some((cutoff, target)) = target {
            preserve_coverage(&mut next, cutoff, target);
        }
        out.extend_from_slice(&next);
        prev = next;
        size = half;
    }
    out
}

/// Queues `layers` (each a whole mip chain as [`mip_chain`] lays it out) into `array`.
fn queue(ctx: &GpuContext, batch: &mut UploadBatch, array: &TextureArray, layers: &[Vec<u8>]) -> crate::Result<()> {
    let mut data = Vec::with_capacity(layers.iter().map(Vec::len).sum());
    let mut regions = Vec::new();
    for (layer, chain) in layers.iter().enumerate() {
        regions.extend(array.layer_regions(layer as u32, data.len() as u64));
        data.extend_from_slice(chain);
    }
    batch.image(ctx, "textures", array.handle(), array.range(), &data, regions)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_hold_the_larger_side() {
        assert_eq!(class_of(1, 1), 0);
        assert_eq!(class_of(16, 16), 0);
        assert_eq!(class_of(17, 3), 1);
        assert_eq!(class_of(256, 128), 4);
        assert_eq!(class_of(100_000, 2), TEXTURE_CLASSES - 1);
        assert_eq!(class_side(class_of(512, 512)), 512);
    }

    #[test]
    fn a_full_class_keeps_one_layer_for_the_placeholder_of_the_rest() {
        // Three layers a class: five 16x16 textures and one 32x32 among them.
        let sizes = [(16, 16), (8, 8), (32, 32), (16, 16), (1, 1), (16, 4)];
        let layout = Layout::new(sizes.into_iter(), 3);
        assert_eq!(layout.members[0], vec![0, 1]);
        assert_eq!(layout.members[1], vec![2]);
        assert_eq!(layout.placeholder[..2], [true, false]);
        assert_eq!(layout.overflow, vec![3, 4, 5]);
        assert_eq!(layout.placement, vec![0, 1, 1 << 16, 2, 2, 2]);
        // Exactly full: no placeholder.
        let layout = Layout::new([(16, 16); 3].into_iter(), 3);
        assert_eq!((layout.placeholder[0], layout.overflow.len()), (false, 0));
        assert_eq!(layout.placement, vec![0, 1, 2]);
    }

    #[test]
    fn mips_average_in_linear_light_for_colour() {
        // Black and white texels average to mid-grey light: 188 in sRGB, 128 stored linearly.
        let level0 = [0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255];
        let srgb = mip_chain(&level0, 2, true, None);
        assert_eq!(srgb.len(), 20);
        assert_eq!(&srgb[16..], &[188, 188, 188, 255]);
        assert_eq!(&mip_chain(&level0, 2, false, None)[16..], &[128, 128, 128, 255]);
    }

    #[test]
    fn masked_mips_keep_the_share_of_texels_that_pass_the_cutoff() {
        // Scattered opaque texels, a fifth of them, like leaves against gaps.
        let side = 64u32;
        let level0: Vec<u8> = (0..side * side)
            .flat_map(|i| {
                let hash = i.wrapping_mul(2_654_435_761) >> 16;
                if hash % 5 == 0 {
                    [255, 255, 255, 255]
                } else {
                    [255, 255, 255, 0]
                }
            })
            .collect();
        let mip = |chain: &[u8], level: u32| {
            let start: usize = (0..level).map(|l| ((side >> l) * (side >> l) * 4) as usize).sum();
            let len = ((side >> level) * (side >> level) * 4) as usize;
            chain[start..start + len].to_vec()
        };
        let target = coverage(&level0, 0.5, 1.0);
        let plain = mip_chain(&level0, side, true, None);
        let kept = mip_chain(&level0, side, true, Some(0.5));
        // Box filtering averages towards a fifth of opaque: by mip 3 almost nothing passes.
        assert!(coverage(&mip(&plain, 3), 0.5, 1.0) < target / 4.0);
        for level in 1..=3 {
            let c = coverage(&mip(&kept, level), 0.5, 1.0);
            assert!((c - target).abs() < 0.05, "mip {level}: {c} against {target}");
        }
        // Colour is untouched.
        let colour = |m: Vec<u8>| m.chunks_exact(4).map(|t| [t[0], t[1], t[2]]).collect::<Vec<_>>();
        assert_eq!(colour(mip(&kept, 2)), colour(mip(&plain, 2)));
    }
}
