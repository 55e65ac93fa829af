//! The `capillary_moisture` extra law: Willett's bridge force with the volume from the
//! moisture content, V = share * w * (m_i + m_j) / (rho_w * k), checked against the formula
//! written out here, on grains of the real masses and on a wall.

mod common;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;
use tilth_kernel::contact::{Contact, ContactModel, ModelSpec, PairSpec};

const W: f64 = 0.09; // moisture, kg/kg
const SHARE: f64 = 0.01;
const K: f64 = 5.0; // bridges per grain
const GAMMA: f64 = 0.072;
const THETA_DEG: f64 = 20.0;

fn model_with(moisture: f64) -> ContactModel {
    let spec = ModelSpec {
        extra: vec!["capillary_moisture".into()],
        ..spec("hertz", None, None, None)
    };
    let pair = PairSpec {
        materials: ("soil".into(), "soil".into()),
        params: params(&[
            ("moisture", moisture),
            ("bridge_share", SHARE),
            ("bridges_per_grain", K),
            ("surface_tension", GAMMA),
            ("contact_angle", THETA_DEG),
        ]),
    };
    ContactModel::build(&[soil()], &spec, &[pair]).unwrap()
}

fn mass(r: f64) -> f64 {
    RHO * 4.0 / 3.0 * PI * r.powi(3)
}

/// Two grains of radii `ri`, `rj` at `overlap` (negative: a gap), at rest.
fn grains(ri: f64, rj: f64, overlap: f64) -> Contact {
    let dist = ri + rj - overlap;
    Contact::between_spheres(
        DVec3::new(dist, 0.0, 0.0),
        dist,
        (ri, rj),
        (mass(ri), mass(rj)),
        (1.0, 1.0),
        (DVec3::ZERO, DVec3::ZERO),
        (DVec3::ZERO, DVec3::ZERO),
        1e-6,
    )
}

fn willett(r_eff: f64, v: f64, gap: f64) -> f64 {
    let theta = THETA_DEG.to_radians();
    let s = gap * (r_eff / v).sqrt();
    2.0 * PI * r_eff * GAMMA * theta.cos() / (1.0 + 1.05 * s + 2.5 * s * s)
}

fn rupture(v: f64) -> f64 {
    (1.0 + THETA_DEG.to_radians() / 2.0) * v.cbrt()
}

#[test]
fn unequal_grains_share_their_water_and_rupture_at_lian_distance() {
    let m = model_with(W);
    let (ri, rj) = (R, 0.5 * R);
    let v = SHARE * W * (mass(ri) + mass(rj)) / (1000.0 * K);
    let r_eff = ri * rj / (ri + rj);
    let mut h = vec![0.0; m.history_stride()];
    assert!(m.evaluate(0, 0, &grains(ri, rj, 1e-8), &mut h).is_some());
    for k in 1..10 {
        let gap = rupture(v) * k as f64 / 10.0;
        let f = m
            .evaluate(0, 0, &grains(ri, rj, -gap), &mut h)
            .expect("the bridge holds below its rupture gap")
            .force
            .x;
        // The force on i points to j (+x): attraction.
        let expected = willett(r_eff, v, gap);
        assert!(
            (f - expected).abs() < 1e-12 * expected,
            "gap {gap}: {f} vs {expected}"
        );
    }
    assert!(
        m.evaluate(0, 0, &grains(ri, rj, -1.001 * rupture(v)), &mut h)
            .is_none(),
        "ruptured past S_c"
    );
}

#[test]
fn more_moisture_reaches_further_and_none_pulls_nothing() {
    let gap_of = |w: f64| {
        let m = model_with(w);
        let mut h = vec![0.0; m.history_stride()];
        m.evaluate(0, 0, &grains(R, R, 1e-8), &mut h).unwrap();
        // Walk out until the bridge ruptures.
        let mut gap = 0.0;
        while m.evaluate(0, 0, &grains(R, R, -gap), &mut h).is_some() {
            gap += 1e-7;
        }
        gap
    };
    let v = |w: f64| SHARE * w * 2.0 * mass(R) / (1000.0 * K);
    for w in [0.03, 0.12] {
        assert!((gap_of(w) - rupture(v(w))).abs() <= 1e-7, "w = {w}");
    }
    assert!(gap_of(0.12) > gap_of(0.03));
    let dry = model_with(0.0);
    let mut h = vec![0.0; dry.history_stride()];
    let f = dry
        .evaluate(0, 0, &grains(R, R, 1e-9), &mut h)
        .map_or(0.0, |o| o.force.x);
    // Touching at 1e-9 m: only the Hertz push, no pull.
    assert!(f < 0.0, "dry grains repel only: {f}");
}

#[test]
fn a_wall_adds_no_water_and_the_list_reach_bounds_every_pair() {
    let m = model_with(W);
    // A grain of radius R whose centre is `distance` from a flat wall.
    let at_wall = |distance: f64| {
        Contact::with_wall(
            DVec3::ZERO,
            DVec3::new(distance, 0.0, 0.0),
            R,
            mass(R),
            1.0,
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::ZERO,
            1e-6,
        )
        .unwrap()
    };
    let mut h = vec![0.0; m.history_stride()];
    m.evaluate(0, 0, &at_wall(0.999 * R), &mut h)
        .expect("touching");
    let v = SHARE * W * mass(R) / (1000.0 * K);
    let gap = 0.5 * rupture(v);
    let apart = at_wall(R + gap);
    let f = m.evaluate(0, 0, &apart, &mut h).unwrap().force.x;
    let expected = willett(R, v, gap);
    assert!((f - expected).abs() < 1e-12 * expected, "{f} vs {expected}");
    // Two grains of the largest radius hold the largest bridge: the neighbour list's reach.
    let v_max = SHARE * W * 2.0 * mass(R) / (1000.0 * K);
    assert!((m.max_reach(R) - rupture(v_max)).abs() < 1e-15);
}
