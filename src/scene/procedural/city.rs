//! `builtin:city`: a square grid of city blocks separated by streets.
//!
//! Each block is a raised sidewalk slab around a grid of building lots. Buildings are unit
//! meshes (box, chamfered box, setback tower, gabled house, round tower) scaled per instance,
//! 8 to 120 m tall and flagged [`FLAG_OCCLUDER`]. Props stand on the sidewalks (street lamps at
//! regular intervals, benches, trees, bollards, hydrants, ...) and vehicles park in the street
//! lanes. The grid grows with `instances` (about [`INSTANCES_PER_BLOCK`] per block), so the
//! density stays the same from a thousand to millions of instances. Units are meters, y is up,
//! and the scene suggests a street-level camera looking down a street near the center, where
//! buildings hide most of the city.

mod palette;

use super::shapes::lamp_head;
use super::{count_option, instance_storage, lights, MAX_INSTANCES, MAX_LIGHTS};
use crate::scene::camera::{Camera, Projection};
use crate::scene::error::SceneError;
use crate::scene::source::LoadOptions;
use crate::scene::{Instance, PointLight, Scene, Transform, FLAG_OCCLUDER};
use glam::{DVec3, Mat3, Vec3};
use palette::{Kind, Palette};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::f32::consts::{FRAC_PI_2, PI};

/// Instances when [`LoadOptions::instances`] is `None`.
pub const DEFAULT_INSTANCES: usize = 10_000;
/// Street-lamp lights when [`LoadOptions::lights`] is `None`.
pub const DEFAULT_LIGHTS: usize = 32;
/// Side of a block, sidewalk included (m).
pub const BLOCK: f64 = 64.0;
/// Width of a street (m).
pub const STREET: f64 = 14.0;
/// Width of the sidewalk ring around each block (m).
pub const SIDEWALK: f64 = 4.5;
/// Height of the sidewalk slab (m).
pub const CURB: f64 = 0.15;
/// How far every object sinks into what it stands on. Bottom faces are then never coplanar
/// with the surface below them: coplanar faces z-fight, and which one wins would depend on
/// draw order (which culling changes), not on the scene.
pub const SINK: f64 = 0.02;
/// Top of a sidewalk slab (the slab itself sinks into the ground).
const SIDEWALK_TOP: f64 = CURB - SINK;
/// Height at which objects on a sidewalk stand.
const ON_SIDEWALK: f64 = SIDEWALK_TOP - SINK;
/// Average instances per block that sizes the grid.
pub const INSTANCES_PER_BLOCK: f64 = 40.0;
/// Distance from one block to the next (a block and a street).
pub const PITCH: f64 = BLOCK + STREET;
/// Height of the street lamps (m).
const LAMP_HEIGHT: f32 = 6.0;
/// Every `LAMP_EVERY`-th prop of a block is a street lamp.
const LAMP_EVERY: usize = 8;

/// Generates the city.
pub fn generate(options: &LoadOptions) -> Result<Scene, SceneError> {
    let n = count_option("city", "instances", options.instances, DEFAULT_INSTANCES, 1, MAX_INSTANCES)?;
    let light_count = count_option("city", "lights", options.lights, DEFAULT_LIGHTS, 0, MAX_LIGHTS)?;
    let mut scene = Scene { name: "builtin:city".into(), ..Default::default() };
    let palette = palette::palette(&mut scene)?;
    let mut rng = SmallRng::seed_from_u64(options.seed);
    scene.instances = instance_storage("city", n)?;

    // One instance is the ground; the rest is shared out over a g x g grid of blocks.
    let rest = n - 1;
    let (origin, g) = grid(n);
    let blocks = g * g;
    let (per_block, extra) = (rest / blocks, rest % blocks);
    let size = g as f64 * PITCH - STREET;
    let ground_size = size + 2.0 * PITCH;
    push(
        &mut scene.instances,
        &palette.ground,
        &mut rng,
        DVec3::ZERO,
        0.0,
        Vec3::new(ground_size as f32, 1.0, ground_size as f32),
        0,
    );

    // About one lamp per LAMP_EVERY props, and one more per block for the rounding.
    let mut lamps = Vec::new();
    lamps.try_reserve_exact(n / LAMP_EVERY + blocks).map_err(|_| no_memory(n, "street lamps"))?;
    for b in 0..blocks {
        let quota = per_block + usize::from(b < extra);
        let corner = origin + DVec3::new((b % g) as f64 * PITCH, 0.0, (b / g) as f64 * PITCH);
        block(&mut scene.instances, &mut lamps, &palette, &mut rng, corner, quota);
    }
    debug_assert_eq!(scene.instances.len(), n);

    scene.lights = street_lights(&mut lamps, light_count, options.seed, &scene)?;
    scene.camera = Some(street_camera(origin, g));
    Ok(scene)
}

/// The minimum corner and the side (in blocks) of the grid of a city of `instances` instances.
/// Each block is followed by a street on its east and north side.
pub fn grid(instances: usize) -> (DVec3, usize) {
    let rest = instances.saturating_sub(1);
    let g = ((rest as f64 / INSTANCES_PER_BLOCK).sqrt().round() as usize).max(1);
    let size = g as f64 * PITCH - STREET;
    (DVec3::new(-size * 0.5, 0.0, -size * 0.5), g)
}

/// Fills one block whose minimum corner is `corner` with exactly `quota` instances.
fn block(
    out: &mut Vec<Instance>,
    lamps: &mut Vec<DVec3>,
    p: &Palette,
    rng: &mut SmallRng,
    corner: DVec3,
    quota: usize,
) {
    if quota == 0 {
        return;
    }
    let center = corner + DVec3::new(BLOCK * 0.5, 0.0, BLOCK * 0.5);
    push(out, &p.slab, rng, center - DVec3::Y * SINK, 0.0, Vec3::new(BLOCK as f32, CURB as f32, BLOCK as f32), 0);
    let (lx, lz) = (rng.random_range(1..=3usize), rng.random_range(1..=3usize));
    let buildings = (lx * lz).min(quota - 1);
    let inner = BLOCK - 2.0 * SIDEWALK;
    let lot = DVec3::new(inner / lx as f64, 0.0, inner / lz as f64);
    for k in 0..buildings {
        let lot_min =
            corner + DVec3::new(SIDEWALK + (k % lx) as f64 * lot.x, ON_SIDEWALK, SIDEWALK + (k / lx) as f64 * lot.z);
        building(out, p, rng, lot_min, lot);
    }
    let props = quota - 1 - buildings;
    let lamp_count = props.div_ceil(LAMP_EVERY);
    for j in 0..props {
        if j % LAMP_EVERY == 0 {
            // Lamps evenly around the block, near the curb, arm over the street.
            let t = ((j / LAMP_EVERY) as f64 + 0.5) / lamp_count as f64;
            let (pos, yaw) = on_sidewalk(corner, t * 4.0 * BLOCK, 0.7);
            push(out, &p.lamp, rng, pos, yaw, Vec3::ONE, 0);
            let head = Mat3::from_rotation_y(yaw).mul_vec3(lamp_head(LAMP_HEIGHT));
            lamps.push(pos + head.as_dvec3());
        } else if rng.random::<f32>() < 0.22 {
            vehicle(out, p, rng, corner);
        } else {
            let kind = &p.props[rng.random_range(0..p.props.len())];
            let (pos, yaw) =
                on_sidewalk(corner, rng.random_range(0.0..4.0 * BLOCK), rng.random_range(0.6..SIDEWALK - 0.8));
            let yaw = yaw + rng.random_range(-0.3f32..0.3);
            let s = rng.random_range(kind.scale.0..=kind.scale.1);
            push(out, kind, rng, pos, yaw, Vec3::splat(s), 0);
        }
    }
}

/// A point on the sidewalk ring at perimeter distance `along` (0 to 4 * BLOCK, counter-clockwise
/// seen from above, starting at the block's minimum corner) and `inset` meters in from the curb,
/// with the yaw that turns +x towards the street.
fn on_sidewalk(corner: DVec3, along: f64, inset: f64) -> (DVec3, f32) {
    let side = ((along / BLOCK) as usize).min(3);
    let a = along - side as f64 * BLOCK;
    let (x, z, yaw) = match side {
        0 => (a, inset, FRAC_PI_2),
        1 => (BLOCK - inset, a, 0.0),
        2 => (BLOCK - a, BLOCK - inset, -FRAC_PI_2),
        _ => (inset, BLOCK - a, PI),
    };
    (corner + DVec3::new(x, ON_SIDEWALK, z), yaw)
}

/// One building on the lot `lot_min .. lot_min + lot`.
fn building(out: &mut Vec<Instance>, p: &Palette, rng: &mut SmallRng, lot_min: DVec3, lot: DVec3) {
    let pick = rng.random::<f32>();
    let b = p.buildings.iter().find(|b| pick < b.cumulative_weight).unwrap_or(&p.buildings[0]);
    let fx = lot.x * rng.random_range(0.78..0.96);
    let fz = lot.z * rng.random_range(0.78..0.96);
    let u: f64 = rng.random();
    let mut height = 8.0 + 52.0 * u * u;
    if rng.random::<f32>() < 0.05 {
        height *= 2.0;
    }
    let height = height.min(b.max_height);
    let x = lot_min.x + fx * 0.5 + rng.random_range(0.0..=lot.x - fx);
    let z = lot_min.z + fz * 0.5 + rng.random_range(0.0..=lot.z - fz);
    let (fx, fz) = if b.square { (fx.min(fz), fx.min(fz)) } else { (fx, fz) };
    push(
        out,
        &b.kind,
        rng,
        DVec3::new(x, lot_min.y, z),
        0.0,
        Vec3::new(fx as f32, height as f32, fz as f32),
        FLAG_OCCLUDER,
    );
}

/// A vehicle parked in a lane of the street east or north of the block.
fn vehicle(out: &mut Vec<Instance>, p: &Palette, rng: &mut SmallRng, corner: DVec3) {
    let kind = &p.vehicles[rng.random_range(0..p.vehicles.len())];
    let lane = if rng.random::<bool>() { 0.27 } else { 0.73 };
    let along = rng.random_range(3.0..BLOCK - 3.0);
    let flip = if lane < 0.5 { 0.0 } else { PI };
    let (pos, yaw) = if rng.random::<bool>() {
        (corner + DVec3::new(BLOCK + lane * STREET, -SINK, along), FRAC_PI_2 + flip)
    } else {
        (corner + DVec3::new(along, -SINK, BLOCK + lane * STREET), flip)
    };
    let yaw = yaw + rng.random_range(-0.05f32..0.05);
    push(out, kind, rng, pos, yaw, Vec3::ONE, 0);
}

/// Appends an instance of `kind` at `pos`, turned by `yaw` about +y and scaled by `scale`.
fn push(out: &mut Vec<Instance>, kind: &Kind, rng: &mut SmallRng, pos: DVec3, yaw: f32, scale: Vec3, flags: u32) {
    let material = match kind.materials.len() {
        1 => kind.materials[0],
        n => kind.materials[rng.random_range(0..n)],
    };
    let linear = Mat3::from_rotation_y(yaw) * Mat3::from_diagonal(scale);
    out.push(Instance { transform: Transform { linear, translation: pos }, mesh: kind.mesh, material, flags });
}

/// Lights at the `count` street lamps nearest to the city center (where the suggested camera
/// stands), topped up with lights scattered over the city when there are too few lamps.
fn street_lights(
    lamps: &mut Vec<DVec3>,
    count: usize,
    seed: u64,
    scene: &Scene,
) -> Result<Vec<PointLight>, SceneError> {
    let mut chosen: Vec<(usize, DVec3)> = Vec::new();
    chosen.try_reserve_exact(lamps.len()).map_err(|_| no_memory(scene.instances.len(), "street lamps"))?;
    chosen.extend(lamps.drain(..).enumerate());
    let key = |(i, p): &(usize, DVec3)| (p.x * p.x + p.z * p.z, *i);
    if chosen.len() > count {
        chosen.select_nth_unstable_by(count, |a, b| key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal));
        chosen.truncate(count);
    }
    chosen.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal));
    let mut out: Vec<PointLight> = chosen
        .into_iter()
        .map(|(_, head)| lights::light(head - DVec3::new(0.0, 0.3, 0.0), lights::WARM, 1.2, LAMP_HEIGHT, 24.0))
        .collect();
    if out.len() < count {
        if let Some(bounds) = scene.world_bounds() {
            out.extend(lights::scatter(&bounds, count - out.len(), seed));
        }
    }
    Ok(out)
}

/// The error of an allocation for `what` that failed for a city of `n` instances.
fn no_memory(n: usize, what: &str) -> SceneError {
    SceneError::Builtin(format!("builtin:city: cannot allocate memory for the {what} of {n} instances"))
}

/// A camera at eye height in the middle of the north-south street nearest the center, looking
/// down the street.
fn street_camera(origin: DVec3, g: usize) -> Camera {
    let column = (g / 2).saturating_sub(1).min(g.saturating_sub(1));
    let x = origin.x + column as f64 * PITCH + BLOCK + STREET * 0.5;
    let eye = DVec3::new(x, 2.0, origin.z + (g as f64 * PITCH) * 0.5 + 20.0);
    Camera {
        eye,
        target: eye + DVec3::new(-6.0, -0.8, -100.0),
        up: Vec3::Y,
        projection: Projection::Perspective { fov_y_deg: 60.0 },
        near: 0.1,
        ..Default::default()
    }
}
