//! glTF materials to cullgraph's untextured metallic-roughness [`Material`]s.

use crate::scene::Material;
use glam::Vec3;
use gltf::Document;

/// One [`Material`] per glTF material, in file order, plus notes on what was ignored.
pub(super) fn convert(document: &Document, notes: &mut Vec<String>) -> Vec<Material> {
    let mut textured = 0;
    let mut out = Vec::with_capacity(document.materials().len());
    for material in document.materials() {
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, _alpha] = pbr.base_color_factor();
        let uses_texture = pbr.base_color_texture().is_some()
            || pbr.metallic_roughness_texture().is_some()
            || material.normal_texture().is_some()
            || material.occlusion_texture().is_some()
            || material.emissive_texture().is_some();
        textured += usize::from(uses_texture);
        let name = match (material.name(), material.index()) {
            (Some(name), _) => name.to_string(),
            (None, Some(i)) => format!("material#{i}"),
            (None, None) => "default".to_string(),
        };
        // The base color factor is linear already; clamp what a broken file might hold.
        let finite = |v: f32, fallback: f32| if v.is_finite() { v } else { fallback };
        out.push(Material {
            name,
            albedo: Vec3::new(finite(r, 0.8), finite(g, 0.8), finite(b, 0.8)).clamp(Vec3::ZERO, Vec3::ONE),
            roughness: finite(pbr.roughness_factor(), 0.6).clamp(0.0, 1.0),
            metallic: finite(pbr.metallic_factor(), 0.0).clamp(0.0, 1.0),
            double_sided: material.double_sided(),
        });
    }
    if textured > 0 || document.textures().len() > 0 {
        notes.push(format!(
            "textures are ignored: {} of {} materials use textures ({} textures, {} images in the file); their base color factors are used",
            textured,
            out.len(),
            document.textures().len(),
            document.images().len()
        ));
    }
    out
}
