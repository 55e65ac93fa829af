//! Small builders shared by the integration tests.
#![allow(dead_code)]

use glam::DVec3;
use std::collections::BTreeMap;
use tilth_kernel::contact::{Contact, ContactModel, ModelSpec, PairSpec};
use tilth_kernel::material::Material;
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::{Aabb, Setup, Simulation};
use tilth_kernel::wall::{Motion, Wall, plane::Plane};

pub const E: f64 = 13.5e6;
pub const NU: f64 = 0.2;
pub const RHO: f64 = 1380.0;
pub const R: f64 = 1e-3;

/// E* of soil on soil (or on a soil wall): 1/E* = 2 (1 - nu^2) / E, Pa.
pub fn e_eff() -> f64 {
    1.0 / (2.0 * (1.0 - NU * NU) / E)
}

/// A fixed soil floor: the plane z = 0, particles above it.
pub fn floor() -> Wall {
    Wall::new(
        "floor",
        Box::new(Plane::new(DVec3::ZERO, DVec3::Z).unwrap()),
        0,
        Motion::Fixed,
    )
}

pub fn soil() -> Material {
    Material::new("soil", E, NU, RHO).unwrap()
}

pub fn spec(
    normal: &str,
    damping: Option<&str>,
    tangential: Option<&str>,
    rolling: Option<&str>,
) -> ModelSpec {
    ModelSpec {
        normal: normal.into(),
        damping: damping.map(Into::into),
        tangential: tangential.map(Into::into),
        rolling: rolling.map(Into::into),
        extra: vec![],
    }
}

pub fn params(kv: &[(&str, f64)]) -> BTreeMap<String, f64> {
    kv.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

pub fn model(spec: &ModelSpec, kv: &[(&str, f64)]) -> ContactModel {
    ContactModel::build(
        &[soil()],
        spec,
        &[PairSpec {
            materials: ("soil".into(), "soil".into()),
            params: params(kv),
        }],
    )
    .unwrap()
}

pub fn domain(half: f64) -> Aabb {
    Aabb {
        min: DVec3::splat(-half),
        max: DVec3::splat(half),
    }
}

pub fn sim(
    model: ContactModel,
    particles: Particles,
    walls: Vec<Wall>,
    dt: f64,
    gravity: DVec3,
    threads: usize,
) -> Simulation {
    Simulation::new(Setup {
        model,
        particles,
        walls,
        factories: vec![],
        dt,
        gravity,
        skin: 0.2 * R,
        threads,
        domain: domain(1.0),
    })
    .unwrap()
}

/// Two soil spheres of radius R approaching head-on along x at `speed` each.
pub fn head_on_pair(speed: f64) -> Particles {
    let mut p = Particles::default();
    p.push(
        DVec3::new(-1.05 * R, 0.0, 0.0),
        DVec3::new(speed, 0.0, 0.0),
        R,
        RHO,
        0,
    );
    p.push(
        DVec3::new(1.05 * R, 0.0, 0.0),
        DVec3::new(-speed, 0.0, 0.0),
        R,
        RHO,
        0,
    );
    p
}

/// The contact of two spheres of radius R (unit masses and inertias) overlapping by
/// `overlap` along x, sphere i moving at `v_i`, for direct law evaluation.
pub fn contact_at(overlap: f64, v_i: DVec3, dt: f64) -> Contact {
    let dist = 2.0 * R - overlap;
    Contact::between_spheres(
        DVec3::new(dist, 0.0, 0.0),
        dist,
        (R, R),
        (1.0, 1.0),
        (1.0, 1.0),
        (v_i, DVec3::ZERO),
        (DVec3::ZERO, DVec3::ZERO),
        dt,
    )
}
