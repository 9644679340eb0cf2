//! Traffic for `builtin:city`: cars, vans and buses that drive along the streets of a
//! [`World`] made from the city, leave at the city's edge and are replaced by new ones entering
//! elsewhere, plus a steady churn of vehicles removed and added mid-street. Every step moves
//! every vehicle (one bulk [`World::set_transforms`]), so a renderer of the world sees moved,
//! inserted and removed instances every frame.
//!
//! The same seed and steps give the same traffic.

use super::city::{grid, BLOCK, PITCH, SINK, STREET};
use crate::scene::world::{InstanceHandle, World, WorldError};
use crate::scene::{Instance, Transform};
use glam::{DVec3, Mat3};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::f32::consts::{FRAC_PI_2, PI};

/// Where across its street a lane runs (parked cars use 0.27 and 0.73).
const LANES: [f64; 2] = [0.4, 0.6];

/// One vehicle on the move.
#[derive(Clone, Debug)]
struct Vehicle {
    handle: InstanceHandle,
    /// Runs along z (a north-south street) or along x.
    along_z: bool,
    /// Fixed coordinate of its lane (x for a north-south street, z otherwise).
    lane_at: f64,
    /// Position along the street.
    at: f64,
    /// Meters per second, signed with the direction.
    speed: f64,
}

/// Vehicles driving through a city world.
pub struct Traffic {
    vehicles: Vec<Vehicle>,
    /// Kinds to spawn: mesh and the materials it may take.
    kinds: Vec<(u32, Vec<u32>)>,
    /// First and last coordinate of a street run (the city with a street's margin).
    span: (f64, f64),
    /// Where each street's centre line starts: `origin + i * PITCH + BLOCK` on either axis.
    origin: DVec3,
    streets: usize,
    /// Vehicles removed and added mid-street per second.
    churn_per_second: f64,
    churn_debt: f64,
    rng: SmallRng,
}

impl Traffic {
    /// `count` vehicles in a world made from `builtin:city` generated with `city_instances`
    /// instances (which sets its grid), taking the city's own vehicle meshes and paints, with
    /// `churn_per_second` of them removed and replaced mid-street every second.
    pub fn new(
        world: &mut World,
        city_instances: usize,
        count: usize,
        churn_per_second: f64,
        seed: u64,
    ) -> Result<Self, WorldError> {
        let scene = world.scene();
        let mut kinds = Vec::new();
        for name in ["city/sedan", "city/van", "city/bus"] {
            let Some(mesh) = scene.meshes.iter().position(|m| m.name == name) else { continue };
            let mut paints: Vec<u32> =
                scene.instances.iter().filter(|i| i.mesh == mesh as u32).map(|i| i.material).collect();
            paints.sort_unstable();
            paints.dedup();
            if !paints.is_empty() {
                kinds.push((mesh as u32, paints));
            }
        }
        if kinds.is_empty() {
            return Err(WorldError::Invalid {
                handle: "traffic".into(),
                message: "the world has no parked vehicles to take meshes and paints from (is it builtin:city?)".into(),
            });
        }
        let (origin, g) = grid(city_instances);
        let size = g as f64 * PITCH - STREET;
        let mut traffic = Self {
            vehicles: Vec::new(),
            kinds,
            span: (origin.x - STREET, origin.x + size + STREET),
            origin,
            streets: g,
            churn_per_second,
            churn_debt: 0.0,
            rng: SmallRng::seed_from_u64(seed),
        };
        for _ in 0..count {
            let at = traffic.rng.random_range(traffic.span.0..traffic.span.1);
            traffic.spawn(world, Some(at))?;
        }
        Ok(traffic)
    }

    /// Vehicles on the streets.
    pub fn len(&self) -> usize {
        self.vehicles.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.vehicles.is_empty()
    }

    /// A new vehicle on a random street and lane, at `at` along it (or where its direction
    /// enters the city).
    fn spawn(&mut self, world: &mut World, at: Option<f64>) -> Result<(), WorldError> {
        let rng = &mut self.rng;
        let (mesh, paints) = &self.kinds[rng.random_range(0..self.kinds.len())];
        let material = paints[rng.random_range(0..paints.len())];
        let along_z = rng.random::<bool>();
        let street = rng.random_range(0..self.streets) as f64;
        let lane = rng.random_range(0..2);
        let base = if along_z { self.origin.x } else { self.origin.z };
        let lane_at = base + street * PITCH + BLOCK + LANES[lane] * STREET;
        let speed = rng.random_range(7.0..14.0) * if lane == 0 { 1.0 } else { -1.0 };
        let at = at.unwrap_or(if speed > 0.0 { self.span.0 } else { self.span.1 });
        let transform = Vehicle::place(along_z, lane_at, at, speed);
        let handle = world.insert(Instance { transform, mesh: *mesh, material, flags: 0 })?;
        self.vehicles.push(Vehicle { handle, along_z, lane_at, at, speed });
        Ok(())
    }

    /// Advances the traffic by `seconds`: every vehicle moves; those past the city's edge leave
    /// and as many enter; the churn removes and adds vehicles mid-street.
    pub fn step(&mut self, world: &mut World, seconds: f64) -> Result<(), WorldError> {
        let (lo, hi) = self.span;
        let mut gone = 0;
        let mut kept = Vec::with_capacity(self.vehicles.len());
        for mut v in std::mem::take(&mut self.vehicles) {
            v.at += v.speed * seconds;
            if v.at < lo || v.at > hi {
                world.remove(v.handle)?;
                gone += 1;
            } else {
                kept.push(v);
            }
        }
        self.vehicles = kept;
        self.churn_debt += self.churn_per_second * seconds;
        while self.churn_debt >= 1.0 && !self.vehicles.is_empty() {
            self.churn_debt -= 1.0;
            let v = self.vehicles.swap_remove(self.rng.random_range(0..self.vehicles.len()));
            world.remove(v.handle)?;
            let at = self.rng.random_range(lo..hi);
            self.spawn(world, Some(at))?;
        }
        for _ in 0..gone {
            self.spawn(world, None)?;
        }
        let moves: Vec<(InstanceHandle, Transform)> = self.vehicles.iter().map(|v| (v.handle, v.transform())).collect();
        world.set_transforms(&moves)
    }
}

impl Vehicle {
    /// Where it is, facing where it goes.
    fn transform(&self) -> Transform {
        Self::place(self.along_z, self.lane_at, self.at, self.speed)
    }

    /// The transform of a vehicle at `at` along its street, facing its direction (the vehicle
    /// meshes point along +x).
    fn place(along_z: bool, lane_at: f64, at: f64, speed: f64) -> Transform {
        let forward = speed > 0.0;
        let (translation, yaw) = if along_z {
            (DVec3::new(lane_at, -SINK, at), if forward { -FRAC_PI_2 } else { FRAC_PI_2 })
        } else {
            (DVec3::new(at, -SINK, lane_at), if forward { 0.0 } else { PI })
        };
        Transform { linear: Mat3::from_rotation_y(yaw), translation }
    }
}
