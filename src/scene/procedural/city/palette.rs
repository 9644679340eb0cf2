//! The city's meshes and materials: building kinds, street furniture and vehicles, each with
//! the materials it may take.

use super::super::material;
use super::super::shapes;
use super::LAMP_HEIGHT;
use crate::scene::error::SceneError;
use crate::scene::mesh::MeshData;
use crate::scene::Scene;
use glam::Vec3;

/// A placeable kind: its mesh, the materials it may take, and its random scale range.
#[derive(Clone)]
pub(super) struct Kind {
    pub(super) mesh: u32,
    pub(super) materials: Vec<u32>,
    pub(super) scale: (f32, f32),
}

/// A building kind with its cumulative pick weight, its height limit, and whether its footprint
/// must be square (round towers).
pub(super) struct BuildingKind {
    pub(super) kind: Kind,
    pub(super) cumulative_weight: f32,
    pub(super) max_height: f64,
    pub(super) square: bool,
}

/// The meshes and materials of the city, added to the scene once.
pub(super) struct Palette {
    pub(super) ground: Kind,
    pub(super) slab: Kind,
    pub(super) buildings: Vec<BuildingKind>,
    pub(super) lamp: Kind,
    pub(super) props: Vec<Kind>,
    pub(super) vehicles: Vec<Kind>,
}

/// Adds the city's materials and meshes to `scene`.
pub(super) fn palette(scene: &mut Scene) -> Result<Palette, SceneError> {
    let mut mat = |name: &str, albedo: [f32; 3], roughness: f32, metallic: f32| {
        scene.materials.push(material(name, albedo, roughness, metallic));
        scene.materials.len() as u32 - 1
    };
    let asphalt = mat("asphalt", [0.07, 0.07, 0.08], 0.9, 0.0);
    let concrete = mat("concrete", [0.42, 0.41, 0.39], 0.85, 0.0);
    let facades: Vec<u32> = [
        ("brick", [0.45, 0.16, 0.11]),
        ("sandstone", [0.66, 0.55, 0.38]),
        ("plaster", [0.78, 0.76, 0.7]),
        ("slate", [0.27, 0.3, 0.34]),
        ("terracotta", [0.62, 0.3, 0.18]),
        ("ochre", [0.7, 0.52, 0.2]),
        ("glass_blue", [0.2, 0.3, 0.42]),
        ("soot", [0.16, 0.15, 0.15]),
    ]
    .iter()
    .map(|(n, c)| mat(n, *c, 0.7, 0.0))
    .collect();
    let metal = mat("painted_metal", [0.12, 0.13, 0.14], 0.45, 0.8);
    let wood = mat("wood", [0.42, 0.27, 0.14], 0.75, 0.0);
    let foliage = mat("foliage", [0.12, 0.34, 0.1], 0.9, 0.0);
    let pine = mat("pine", [0.06, 0.22, 0.1], 0.9, 0.0);
    let stone = mat("stone", [0.55, 0.53, 0.5], 0.8, 0.0);
    let red = mat("signal_red", [0.7, 0.06, 0.04], 0.5, 0.0);
    let orange = mat("safety_orange", [0.9, 0.35, 0.04], 0.55, 0.0);
    let paints: Vec<u32> = [
        ("paint_red", [0.55, 0.04, 0.04], 0.0),
        ("paint_blue", [0.05, 0.12, 0.45], 0.0),
        ("paint_white", [0.85, 0.85, 0.83], 0.0),
        ("paint_black", [0.03, 0.03, 0.03], 0.0),
        ("paint_yellow", [0.85, 0.65, 0.05], 0.0),
        ("paint_silver", [0.6, 0.6, 0.62], 0.9),
    ]
    .iter()
    .map(|(n, c, m)| mat(n, *c, 0.35, *m))
    .collect();

    let mut mesh = |name: &str, data: MeshData| {
        scene.add_mesh(&format!("city/{name}"), &data, &format!("builtin:city mesh '{name}'"))
    };
    let kind = |mesh: u32, materials: &[u32], scale: (f32, f32)| Kind { mesh, materials: materials.to_vec(), scale };
    let unit_box = mesh("box", shapes::cuboid(Vec3::ONE))?;
    let ground = kind(mesh("ground", shapes::ground(1.0))?, &[asphalt], (1.0, 1.0));
    let slab = kind(unit_box, &[concrete], (1.0, 1.0));
    let building = |mesh: u32, cumulative_weight: f32, max_height: f64, square: bool| BuildingKind {
        kind: kind(mesh, &facades, (1.0, 1.0)),
        cumulative_weight,
        max_height,
        square,
    };
    let buildings = vec![
        building(unit_box, 0.5, 200.0, false),
        building(mesh("building_chamfered", shapes::chamfered_box(Vec3::ONE, 0.06))?, 0.65, 200.0, false),
        building(mesh("building_stepped", shapes::building_stepped(3))?, 0.8, 200.0, false),
        building(mesh("building_roofed", shapes::building_roofed(0.3))?, 0.9, 24.0, false),
        building(mesh("building_round", shapes::cylinder(0.5, 1.0, 24))?, 1.01, 200.0, true),
    ];
    let lamp = kind(mesh("lamp_post", shapes::lamp_post(LAMP_HEIGHT, 10))?, &[metal], (1.0, 1.0));
    let props = vec![
        kind(mesh("bench", shapes::bench(1.8))?, &[wood], (0.9, 1.1)),
        kind(mesh("tree_conifer", shapes::tree_conifer(7.0, 10))?, &[pine], (0.7, 1.3)),
        kind(mesh("tree_round", shapes::tree_round(6.0, 1))?, &[foliage], (0.7, 1.3)),
        kind(mesh("bollard", shapes::bollard(0.12, 0.9, 10))?, &[metal, stone], (0.9, 1.1)),
        kind(mesh("post", shapes::capsule(0.1, 1.2, 8, 2))?, &[metal, orange], (0.9, 1.1)),
        kind(mesh("crate_stack", shapes::crate_stack(3))?, &[wood], (0.8, 1.2)),
        kind(mesh("hydrant", shapes::hydrant(10))?, &[red], (1.0, 1.0)),
        kind(mesh("trash_can", shapes::trash_can(12))?, &[metal, concrete], (0.9, 1.1)),
        kind(mesh("planter", shapes::planter(1.4, 14))?, &[stone], (0.8, 1.3)),
        kind(mesh("street_sign", shapes::street_sign(2.6))?, &[metal], (1.0, 1.0)),
        kind(mesh("traffic_cone", shapes::traffic_cone(10))?, &[orange], (0.9, 1.1)),
        kind(mesh("fence", shapes::fence(3.0, 4))?, &[wood, metal], (0.8, 1.2)),
        kind(mesh("kiosk", shapes::kiosk(6))?, &[red, paints[1], stone], (0.8, 1.0)),
        kind(mesh("gate_arch", shapes::arch(3.0, 3.5, 0.6, 9))?, &[stone], (0.9, 1.1)),
        kind(mesh("ramp", shapes::wedge(Vec3::new(1.2, 0.4, 1.6)))?, &[concrete], (0.8, 1.2)),
        kind(mesh("barrier", shapes::chamfered_box(Vec3::new(2.0, 0.8, 0.5), 0.1))?, &[concrete, stone], (0.9, 1.1)),
        kind(mesh("stoop", shapes::stairs(4, 1.6, 0.17, 0.3))?, &[stone], (0.9, 1.1)),
        kind(mesh("fountain", shapes::torus(1.1, 0.25, 20, 8))?, &[stone], (0.8, 1.2)),
    ];
    let vehicles = vec![
        kind(mesh("sedan", shapes::car(4.4, 1.8, 1.45, 12))?, &paints, (1.0, 1.0)),
        kind(mesh("van", shapes::car(5.3, 2.0, 2.3, 12))?, &paints, (1.0, 1.0)),
        kind(mesh("bus", shapes::car(11.5, 2.5, 3.1, 14))?, &paints[..3], (1.0, 1.0)),
    ];
    Ok(Palette { ground, slab, buildings, lamp, props, vehicles })
}
