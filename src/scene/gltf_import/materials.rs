//! glTF materials to cullgraph's metallic-roughness [`Material`]s, with their textures,
//! samplers, `KHR_texture_transform` and alpha modes.

use crate::scene::texture::{Sampler, UvTransform, Wrap};
use crate::scene::{AlphaMode, Material, TextureRef, TextureSlot};
use glam::{Vec2, Vec3};
use gltf::texture::{MagFilter, MinFilter, WrappingMode};
use gltf::Document;

/// One [`Material`] per glTF material, in file order. `placeholder[i]` says whether glTF image
/// `i` could not be used (scene texture `i` is then the placeholder); every material that shows
/// it gets a note naming the material and the image.
pub(super) fn convert(document: &Document, placeholder: &[bool], notes: &mut Vec<String>) -> Vec<Material> {
    let mut out = Vec::with_capacity(document.materials().len());
    let mut other_sets = 0usize;
    for material in document.materials() {
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let name = match (material.name(), material.index()) {
            (Some(name), _) => name.to_string(),
            (None, Some(i)) => format!("material#{i}"),
            (None, None) => "default".to_string(),
        };
        // Factors are linear already; clamp what a broken file might hold.
        let finite = |v: f32, fallback: f32| if v.is_finite() { v } else { fallback };
        let unit = |v: f32, fallback: f32| finite(v, fallback).clamp(0.0, 1.0);
        let mut textures = [None; 5];
        let mut set = |slot: TextureSlot, info: Option<(gltf::Texture<'_>, u32, Option<UvTransform>)>| {
            let Some((texture, tex_coord, transform)) = info else { return };
            if tex_coord != 0 {
                other_sets += 1;
            }
            let image = texture.source().index();
            if placeholder.get(image).copied().unwrap_or(true) {
                notes.push(format!(
                    "material '{name}': its {} ({}) shows the placeholder",
                    slot.name(),
                    super::images::label(document, &texture.source())
                ));
            }
            textures[slot as usize] = Some(TextureRef {
                texture: image as u32,
                sampler: sampler(&texture.sampler()),
                transform: transform.unwrap_or_default(),
            });
        };
        set(TextureSlot::BaseColor, pbr.base_color_texture().map(info));
        set(TextureSlot::MetallicRoughness, pbr.metallic_roughness_texture().map(info));
        set(TextureSlot::Emissive, material.emissive_texture().map(info));
        let normal = material.normal_texture();
        let normal_scale = normal.as_ref().map_or(1.0, |n| finite(n.scale(), 1.0));
        set(TextureSlot::Normal, normal.map(|n| (n.texture(), n.tex_coord(), None)));
        let occlusion = material.occlusion_texture();
        let occlusion_strength = occlusion.as_ref().map_or(1.0, |o| unit(o.strength(), 1.0));
        set(TextureSlot::Occlusion, occlusion.map(|o| (o.texture(), o.tex_coord(), None)));
        let [er, eg, eb] = material.emissive_factor();
        let alpha_mode = match material.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => {
                AlphaMode::Mask { cutoff: unit(material.alpha_cutoff().unwrap_or(0.5), 0.5) }
            }
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        out.push(Material {
            name,
            albedo: Vec3::new(unit(r, 0.8), unit(g, 0.8), unit(b, 0.8)),
            alpha: unit(a, 1.0),
            roughness: unit(pbr.roughness_factor(), 0.6),
            metallic: unit(pbr.metallic_factor(), 0.0),
            emissive: Vec3::new(finite(er, 0.0), finite(eg, 0.0), finite(eb, 0.0)).max(Vec3::ZERO),
            double_sided: material.double_sided(),
            alpha_mode,
            textures,
            normal_scale,
            occlusion_strength,
        });
    }
    if other_sets > 0 {
        notes.push(format!(
            "{other_sets} texture references use a texture coordinate set other than TEXCOORD_0; TEXCOORD_0 is used"
        ));
    }
    out
}

/// The glTF sampler as ours (glTF's defaults: repeat, linear).
fn sampler(s: &gltf::texture::Sampler<'_>) -> Sampler {
    let wrap = |w: WrappingMode| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    Sampler {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        nearest_mag: s.mag_filter() == Some(MagFilter::Nearest),
        nearest_min: matches!(
            s.min_filter(),
            Some(MinFilter::Nearest | MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear)
        ),
    }
}

/// `KHR_texture_transform` (non-finite values fall back to the identity's).
fn uv_transform(t: &gltf::texture::TextureTransform<'_>) -> UvTransform {
    let v2 = |v: [f32; 2], d: f32| {
        Vec2::new(if v[0].is_finite() { v[0] } else { d }, if v[1].is_finite() { v[1] } else { d })
    };
    let rotation = t.rotation();
    UvTransform {
        offset: v2(t.offset(), 0.0),
        rotation: if rotation.is_finite() { rotation } else { 0.0 },
        scale: v2(t.scale(), 1.0),
    }
}

/// A texture reference's texture, coordinate set and transform.
fn info(i: gltf::texture::Info<'_>) -> (gltf::Texture<'_>, u32, Option<UvTransform>) {
    let transform = i.texture_transform().map(|t| uv_transform(&t));
    (i.texture(), i.tex_coord(), transform)
}
