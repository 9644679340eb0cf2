//! Whole-scene checks run after every load, and by engines that build or edit a [`Scene`]
//! themselves before handing it to the GPU. Every error names the offending element
//! (`instance #12: transform is not finite`).

use super::error::SceneError;
use super::{Instance, Scene};

/// Material indices the GPU instance record can hold (24 bits).
pub const MAX_MATERIALS: usize = 1 << 24;
/// The most instances a scene may hold: draws find an instance through `gl_InstanceIndex`, a
/// signed 32-bit integer. A device may allow fewer: one storage buffer binding must hold the
/// instance records ([`crate::passes::shared::instance_ranges::most_instances`]).
pub const MAX_INSTANCES: usize = (1 << 31) - 1;
/// The most vertices of a scene's vertex pool: 2 GiB of 32-byte vertices, so that the pool
/// stays one storage buffer within every target device's `maxStorageBufferRange`.
pub const MAX_VERTICES: usize = 1 << 26;
/// The most indices of a scene's index pool: 2 GiB of `u32`s, for the same reason.
pub const MAX_INDICES: usize = 1 << 29;
/// The most textures a scene may hold: a material names a texture's layer in 16 bits (and the
/// GPU shows at most its size classes' array layers of them, `passes::shared::textures`).
pub const MAX_TEXTURES: usize = 1 << 16;
/// Flag bits a scene's instances may use: the cull records keep 7 bits, and the last of them is
/// [`super::FLAG_EMPTY_SLOT`], which only the renderer sets.
pub const MAX_FLAG_BITS: u32 = 6;

/// Checks cross references and finiteness of a scene: a non-empty instance list, mesh ranges
/// inside the pools, every index inside its mesh, instance mesh/material indices in range,
/// finite transforms, materials, lights, sun and camera.
pub fn validate_scene(scene: &Scene) -> Result<(), SceneError> {
    if scene.instances.is_empty() {
        return Err(SceneError::invalid(scene_place(scene), "scene has no instances"));
    }
    validate_contents(scene)
}

/// [`validate_scene`] but for the instance list's being empty: what a live world starts from,
/// which may be empty until something is streamed in.
pub fn validate_contents(scene: &Scene) -> Result<(), SceneError> {
    if scene.materials.len() > MAX_MATERIALS {
        return Err(SceneError::invalid(
            scene_place(scene),
            format!("{} materials exceed the {MAX_MATERIALS} an instance can address", scene.materials.len()),
        ));
    }
    check_totals(scene)?;
    validate_meshes(scene)?;
    for (i, t) in scene.textures.iter().enumerate() {
        if let Some(e) = texture_problem(t) {
            return Err(SceneError::invalid(format!("texture #{i} '{}'", t.name), e));
        }
    }
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(e) = material_problem(m, scene.textures.len()) {
            return Err(SceneError::invalid(format!("material #{i} '{}'", m.name), e));
        }
    }
    for i in 0..scene.instances.len() {
        scene.validate_instance(i)?;
    }
    for (i, l) in scene.lights.iter().enumerate() {
        let place = format!("light #{i}");
        if let Some(e) = super::position_error("position", l.position) {
            return Err(SceneError::invalid(place, e));
        }
        if !l.color.is_finite() || l.color.min_element() < 0.0 {
            return Err(SceneError::invalid(place, format!("color {} must be finite and non-negative", l.color)));
        }
        if !(l.range.is_finite() && l.range > 0.0) {
            return Err(SceneError::invalid(place, format!("range {} must be positive and finite", l.range)));
        }
        if let Some(e) = l.spot.and_then(|cone| super::spot_cone_error(&cone)) {
            return Err(SceneError::invalid(place, e));
        }
    }
    let sun = &scene.sun;
    if !sun.direction.is_finite() || sun.direction.length_squared() < 1e-12 || !sun.color.is_finite() {
        return Err(SceneError::invalid("sun", "direction must be finite and non-zero, color finite"));
    }
    if let Some(camera) = &scene.camera {
        camera.validate().map_err(|m| SceneError::invalid("camera", m))?;
    }
    Ok(())
}

impl Scene {
    /// Checks one instance: mesh and material in range, transform finite (and its translation
    /// within `f32` range, as the GPU splits it into two floats), flags within the bits the GPU
    /// keeps. Errors name the instance: `instance #12: transform is not finite`.
    pub fn validate_instance(&self, index: usize) -> Result<(), SceneError> {
        let place = || format!("instance #{index}");
        let Some(instance) = self.instances.get(index) else {
            return Err(SceneError::invalid(
                place(),
                format!("does not exist (the scene has {})", self.instances.len()),
            ));
        };
        check_instance(self, instance).map_err(|m| SceneError::invalid(place(), m))
    }

    /// Runs [`validate_scene`] on this scene.
    pub fn validate(&self) -> Result<(), SceneError> {
        validate_scene(self)
    }
}

fn check_instance(scene: &Scene, instance: &Instance) -> Result<(), String> {
    if instance.mesh as usize >= scene.meshes.len() {
        return Err(format!("mesh {} is out of range (the scene has {} meshes)", instance.mesh, scene.meshes.len()));
    }
    if instance.material as usize >= scene.materials.len() {
        return Err(format!(
            "material {} is out of range (the scene has {} materials)",
            instance.material,
            scene.materials.len()
        ));
    }
    if !instance.transform.is_finite() {
        return Err("transform is not finite".into());
    }
    if let Some(e) = super::position_error("translation", instance.transform.translation) {
        return Err(e);
    }
    if let Some(mesh) = scene.meshes.get(instance.mesh as usize).filter(|m| m.bounds.min.cmple(m.bounds.max).all()) {
        if let Some(e) = bounds_error(&format!("mesh '{}'", mesh.name), &mesh.bounds, &instance.transform) {
            return Err(e);
        }
    }
    if instance.flags >> MAX_FLAG_BITS != 0 {
        return Err(format!("flags {:#x} use bits above the {MAX_FLAG_BITS} that instances may use", instance.flags));
    }
    Ok(())
}

/// The scene's instances, vertices, indices and textures against the scene limits.
fn check_totals(scene: &Scene) -> Result<(), SceneError> {
    let totals = [
        (scene.instances.len(), MAX_INSTANCES, "instances"),
        (scene.vertices.len(), MAX_VERTICES, "vertices"),
        (scene.indices.len(), MAX_INDICES, "indices"),
        (scene.textures.len(), MAX_TEXTURES, "textures"),
    ];
    for (count, max, what) in totals {
        if count > max {
            return Err(SceneError::invalid(
                scene_place(scene),
                format!("{count} {what} exceed the {max} a scene may hold"),
            ));
        }
    }
    Ok(())
}

/// Why a mesh with the local `bounds` placed by `transform` is refused, if it is: its world
/// bounds are not finite (a huge scale), or reach beyond [`super::MAX_COORDINATE`], where
/// positions lose their precision on the GPU. `what` names the mesh in the message.
pub(crate) fn bounds_error(what: &str, bounds: &super::Aabb, transform: &super::Transform) -> Option<String> {
    let (min, max) = transform.bounds_of(bounds);
    let max_coordinate = super::MAX_COORDINATE;
    if !(min.is_finite() && max.is_finite()) {
        Some(format!("{what} is placed with world bounds {min}..{max}, which are not finite"))
    } else if min.abs().max_element().max(max.abs().max_element()) > max_coordinate {
        Some(format!(
            "{what} reaches {min}..{max}, beyond ±{max_coordinate:.0} (2^40) units, where positions stop keeping 1/256 unit of precision on the GPU"
        ))
    } else {
        None
    }
}

fn validate_meshes(scene: &Scene) -> Result<(), SceneError> {
    for (i, m) in scene.meshes.iter().enumerate() {
        let place = || format!("mesh #{i} '{}'", m.name);
        if m.index_count == 0 || m.index_count % 3 != 0 {
            return Err(SceneError::invalid(
                place(),
                format!("index count {} is not a positive multiple of 3", m.index_count),
            ));
        }
        let first = m.first_index as usize;
        let Some(indices) = scene.indices.get(first..first + m.index_count as usize) else {
            return Err(SceneError::invalid(
                place(),
                format!(
                    "indices {}..{} lie outside the index pool ({} entries)",
                    first,
                    first + m.index_count as usize,
                    scene.indices.len()
                ),
            ));
        };
        let vertex_end = m.vertex_offset as usize + m.vertex_count as usize;
        if vertex_end > scene.vertices.len() {
            return Err(SceneError::invalid(
                place(),
                format!(
                    "vertices {}..{vertex_end} lie outside the vertex pool ({} entries)",
                    m.vertex_offset,
                    scene.vertices.len()
                ),
            ));
        }
        if let Some((at, bad)) = indices.iter().enumerate().find(|(_, &v)| v >= m.vertex_count) {
            return Err(SceneError::invalid(
                place(),
                format!("index {bad} at element {at} is out of range (the mesh has {} vertices)", m.vertex_count),
            ));
        }
        if let Some(e) = m.deform.as_ref().and_then(|d| d.problem(m.vertex_count as usize)) {
            return Err(SceneError::invalid(place(), format!("deformation: {e}")));
        }
        let b = &m.bounds;
        if !(b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all()) {
            return Err(SceneError::invalid(place(), format!("bounds {}..{} are not a finite box", b.min, b.max)));
        }
        if !(m.sphere.center.is_finite() && m.sphere.radius.is_finite() && m.sphere.radius >= 0.0) {
            return Err(SceneError::invalid(place(), "bounding sphere is not finite"));
        }
    }
    Ok(())
}

fn scene_place(scene: &Scene) -> String {
    if scene.name.is_empty() {
        "scene".into()
    } else {
        format!("scene '{}'", scene.name)
    }
}

/// What is wrong with a texture's pixels, if anything.
pub(crate) fn texture_problem(t: &super::Texture) -> Option<String> {
    if t.width == 0 || t.height == 0 {
        return Some(format!("size {}x{} is empty", t.width, t.height));
    }
    let side = super::gltf_import::MAX_IMAGE_SIDE;
    if t.width > side || t.height > side {
        return Some(format!("size {}x{} exceeds {side} texels a side", t.width, t.height));
    }
    let expected = t.width as usize * t.height as usize * 4;
    (t.rgba.len() != expected)
        .then(|| format!("{} bytes of RGBA8 for {}x{} texels ({expected} expected)", t.rgba.len(), t.width, t.height))
}

/// What is wrong with a material of a scene with `textures` textures, if anything.
pub(crate) fn material_problem(m: &super::Material, textures: usize) -> Option<String> {
    if !m.albedo.is_finite() || m.albedo.min_element() < 0.0 {
        return Some(format!("albedo {} must be finite and non-negative", m.albedo));
    }
    if !m.emissive.is_finite() || m.emissive.min_element() < 0.0 {
        return Some(format!("emissive {} must be finite and non-negative", m.emissive));
    }
    let factors = [m.roughness, m.metallic, m.alpha, m.normal_scale, m.occlusion_strength];
    if !factors.iter().all(|f| f.is_finite()) {
        return Some("roughness, metallic, alpha, normal scale and occlusion strength must be finite".into());
    }
    if let super::AlphaMode::Mask { cutoff } = m.alpha_mode {
        if !cutoff.is_finite() {
            return Some(format!("alpha cutoff {cutoff} must be finite"));
        }
    }
    for (slot, t) in super::TextureSlot::ALL.iter().zip(&m.textures) {
        let Some(t) = t else { continue };
        if t.texture as usize >= textures {
            return Some(format!("{}: texture {} does not exist (the scene has {textures})", slot.name(), t.texture));
        }
        let x = t.transform;
        if !(x.offset.is_finite() && x.scale.is_finite() && x.rotation.is_finite()) {
            return Some(format!("{}: the texture transform must be finite", slot.name()));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::MeshData;
    use crate::scene::{Material, PointLight, Transform};
    use glam::{DVec3, Vec3};

    fn one_triangle() -> Scene {
        let mut s = Scene::default();
        let data = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        let mesh = s.add_mesh("tri", &data, "test").unwrap();
        let material = s.add_material(Material::default());
        s.instances.push(Instance { transform: Transform::default(), mesh, material, flags: 0 });
        s
    }

    #[test]
    fn valid_scene_passes() {
        one_triangle().validate().unwrap();
    }

    #[test]
    fn empty_scene_is_refused() {
        let e = validate_scene(&Scene::default()).unwrap_err().to_string();
        assert!(e.contains("scene has no instances"), "{e}");
    }

    #[test]
    fn errors_name_the_instance() {
        let mut s = one_triangle();
        s.instances.push(s.instances[0]);
        s.instances[1].transform.translation.y = f64::NAN;
        assert_eq!(validate_scene(&s).unwrap_err().to_string(), "instance #1: transform is not finite");
        s.instances[1].transform = Transform::default();
        s.instances[1].transform.linear.x_axis.x = f32::INFINITY;
        assert_eq!(validate_scene(&s).unwrap_err().to_string(), "instance #1: transform is not finite");
        s.instances[1].transform = Transform::default();
        s.instances[1].mesh = 5;
        assert!(validate_scene(&s).unwrap_err().to_string().starts_with("instance #1: mesh 5 is out of range"));
        s.instances[1].mesh = 0;
        s.instances[1].material = 9;
        assert!(validate_scene(&s).unwrap_err().to_string().starts_with("instance #1: material 9 is out of range"));
        s.instances[1].material = 0;
        s.instances[1].flags = 1 << 9;
        assert!(validate_scene(&s).unwrap_err().to_string().starts_with("instance #1: flags"));
        s.instances[1].flags = 0;
        // Beyond f32, and farther than positions keep their precision on the GPU.
        for far in [1e300, 1.1e12] {
            s.instances[1].transform.translation.x = far;
            let e = validate_scene(&s).unwrap_err().to_string();
            assert!(e.starts_with("instance #1: translation") && e.contains("beyond ±1099511627776 (2^40)"), "{e}");
        }
        s.instances[1].transform.translation.x = 1e12;
        assert!(validate_scene(&s).is_ok());
        // Within range itself, but its mesh reaches past it (or to infinity).
        s.instances[1].transform.translation.x = crate::scene::MAX_COORDINATE;
        let e = validate_scene(&s).unwrap_err().to_string();
        assert!(e.starts_with("instance #1: mesh 'tri' reaches") && e.contains("beyond ±1099511627776"), "{e}");
        s.instances[1].transform.translation.x = 0.0;
        s.instances[1].transform.linear = glam::Mat3::from_diagonal(Vec3::splat(3e38));
        let e = validate_scene(&s).unwrap_err().to_string();
        assert!(e.starts_with("instance #1: mesh 'tri' reaches [0, 0, 0]..[3000"), "{e}");
        s.instances[1].transform.linear = glam::Mat3::IDENTITY;
        assert!(s.validate_instance(7).is_err());
    }

    #[test]
    fn broken_pools_and_lights_are_refused() {
        let mut s = one_triangle();
        s.indices[2] = 7;
        assert!(validate_scene(&s).unwrap_err().to_string().starts_with("mesh #0 'tri': index 7"));
        let mut s = one_triangle();
        s.meshes[0].first_index = 3;
        assert!(validate_scene(&s).unwrap_err().to_string().contains("outside the index pool"));
        let mut s = one_triangle();
        s.lights.push(PointLight::point(DVec3::ZERO, Vec3::ONE, 0.0));
        assert!(validate_scene(&s).unwrap_err().to_string().starts_with("light #0: range"));
        s.lights[0] = PointLight::point(DVec3::NAN, Vec3::ONE, 1.0);
        assert!(validate_scene(&s).unwrap_err().to_string().starts_with("light #0: position"));
    }
}
