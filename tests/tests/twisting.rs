//! `twisting` against its formulas: the spring k_tw = 4 G* a^3 below the cap (2/3) mu_tw a L,
//! and a spinning sphere on a floor decelerating at M_max / I. And why a model needs it: two
//! cohesive grains standing on one floor contact, set turning about the vertical, spin for
//! ever without it (no other law opposes a spin about a contact normal: EPSD's rolling
//! velocity leaves out the normal part), and stop with it. Such pairs are the funnel test's
//! grains that never stop (docs/li2022-compare.md).

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::contact::{Contact, ModelSpec};

const MU_TW: f64 = 0.4;

/// G* of soil on soil: 1/G* = 2 x 2 (2 - nu)(1 + nu) / E.
fn g_eff() -> f64 {
    E / (4.0 * (2.0 - NU) * (1.0 + NU))
}

fn twisting_spec() -> ModelSpec {
    ModelSpec {
        extra: vec!["twisting".into()],
        ..spec("hertz", None, None, None)
    }
}

/// Two spheres along x, overlapping by `delta`, i spinning at `w` about the normal.
fn spinning(delta: f64, w: f64, dt: f64) -> Contact {
    let dist = 2.0 * R - delta;
    Contact::between_spheres(
        DVec3::new(dist, 0.0, 0.0),
        dist,
        (R, R),
        (1.0, 1.0),
        (1e-9, 1e-9),
        (DVec3::ZERO, DVec3::ZERO),
        (DVec3::new(w, 0.0, 0.0), DVec3::ZERO),
        dt,
    )
}

#[test]
fn the_spring_winds_up_at_4_g_a3_then_slips_at_two_thirds_mu_a_load() {
    let m = model(
        &twisting_spec(),
        &[("twisting_friction", MU_TW), ("twisting_damping", 0.0)],
    );
    let (delta, w, dt) = (2e-5, 3.0, 1e-5);
    let r_eff = R / 2.0;
    let a = (r_eff * delta).sqrt();
    let load = 4.0 / 3.0 * e_eff() * r_eff.sqrt() * delta.powf(1.5);
    let k_tw = 4.0 * g_eff() * a.powi(3);
    let cap = 2.0 / 3.0 * MU_TW * a * load;
    let mut h = vec![0.0; m.history_stride()];
    let c = spinning(delta, w, dt);
    let mut slipped = false;
    for step in 1..=4000 {
        let o = m.evaluate(0, 0, &c, &mut h).unwrap();
        let expected = (k_tw * w * dt * step as f64).min(cap);
        // Torque on i opposes its spin (+x); j gets the opposite.
        assert!(
            (o.torque_i.x + expected).abs() <= 1e-9 * cap,
            "step {step}: {} vs {}",
            o.torque_i.x,
            -expected
        );
        assert_eq!(o.torque_j, -o.torque_i);
        assert_eq!(o.torque_i.y, 0.0);
        slipped |= expected == cap;
    }
    assert!(slipped, "the test must reach the cap");
}

#[test]
fn zero_twisting_friction_is_off() {
    let m = model(&twisting_spec(), &[("twisting_friction", 0.0)]);
    let mut h = vec![0.0; m.history_stride()];
    for _ in 0..10 {
        let o = m
            .evaluate(0, 0, &spinning(2e-5, 3.0, 1e-6), &mut h)
            .unwrap();
        assert_eq!(o.torque_i, DVec3::ZERO);
    }
}

/// A sphere at rest on the floor, spinning about the vertical: once the spring has slipped,
/// the spin falls linearly at M_max / I with L = m g.
#[test]
fn a_spinning_sphere_on_a_floor_decelerates_at_the_cap_over_its_inertia() {
    let spec = ModelSpec {
        extra: vec!["twisting".into()],
        ..spec("hertz", Some("restitution"), None, None)
    };
    let m = model(
        &spec,
        &[
            ("restitution", 0.3),
            ("twisting_friction", MU_TW),
            ("twisting_damping", 0.0),
        ],
    );
    let mut p = tilth_kernel::particles::Particles::default();
    p.push(DVec3::new(0.0, 0.0, R), DVec3::ZERO, R, RHO, 0);
    let dt = 2e-7;
    let g = 9.81;
    let mut s = sim(m, p, vec![floor()], dt, DVec3::new(0.0, 0.0, -g), 1);
    // Settle on the floor first.
    s.run(20_000).unwrap();
    assert!(s.particles.velocity[0].length() < 1e-6);
    let w0 = 20.0;
    s.particles.angular_velocity[0] = DVec3::new(0.0, 0.0, w0);
    s.run(2_000).unwrap();
    let (w1, t1) = (s.particles.angular_velocity[0].z, s.time);
    s.run(20_000).unwrap();
    let (w2, t2) = (s.particles.angular_velocity[0].z, s.time);
    let mass = s.particles.mass[0];
    let inertia = s.particles.inertia[0];
    // At rest: overlap from Hertz with the floor (R* = R, E* of soil on a soil wall).
    let delta = (mass * g / (4.0 / 3.0 * e_eff() * R.sqrt())).powf(2.0 / 3.0);
    let a = (R * delta).sqrt();
    let expected = 2.0 / 3.0 * MU_TW * a * mass * g / inertia;
    let measured = (w1 - w2) / (t2 - t1);
    assert!(w2 > 0.0, "still spinning at the end of the window");
    assert!(
        (measured - expected).abs() < 0.01 * expected,
        "deceleration {measured} vs {expected}"
    );
}

/// Two JKR grains of the study's soil (surface energy 0.36 J/m^2, rolling friction 0.15 with
/// EPSD, as models/li2022.toml): one on the floor, one on it leaning 0.2 rad off the
/// vertical, pushed sideways at 0.05 m/s so that the pair turns about the vertical through
/// the lower grain's floor contact. Returns the upper grain's speed at 0.1 s and at 1.1 s.
fn turning_pair(twisting_friction: Option<f64>) -> (f64, f64) {
    let mut spec = spec("jkr", Some("restitution"), Some("mindlin"), Some("epsd"));
    let mut kv = vec![
        ("restitution", 0.45),
        ("friction", 0.8),
        ("rolling_friction", 0.15),
        ("surface_energy", 0.36),
    ];
    if let Some(mu) = twisting_friction {
        spec.extra.push("twisting".into());
        kv.push(("twisting_friction", mu));
    }
    let m = model(&spec, &kv);
    let mut p = tilth_kernel::particles::Particles::default();
    let lean: f64 = 0.2;
    p.push(DVec3::new(0.0, 0.0, R), DVec3::ZERO, R, RHO, 0);
    p.push(
        DVec3::new(2.0 * R * lean.sin(), 0.0, R + 2.0 * R * lean.cos()),
        DVec3::new(0.0, 0.05, 0.0),
        R,
        RHO,
        0,
    );
    let dt = 5e-6;
    let mut s = sim(m, p, vec![floor()], dt, DVec3::new(0.0, 0.0, -9.81), 1);
    let upper = |s: &tilth_kernel::sim::Simulation| {
        let k = s.particles.id.iter().position(|&i| i == 1).unwrap();
        s.particles.velocity[k].length()
    };
    s.run(20_000).unwrap(); // 0.1 s: the push shared out, the pair turning
    let early = upper(&s);
    s.run(200_000).unwrap(); // 1 s more
    (early, upper(&s))
}

#[test]
fn a_cohesive_pair_on_one_floor_contact_turns_for_ever_without_twisting_resistance() {
    let (early, late) = turning_pair(None);
    // Nothing opposes the turn: its speed holds (a rigid turn: no contact slides or rolls).
    assert!(early > 1e-3, "the pair did not turn: {early} m/s at 0.1 s");
    assert!(
        (late - early).abs() < 0.01 * early,
        "the turn slowed from {early} to {late} m/s over 1 s"
    );
}

#[test]
fn twisting_resistance_stops_the_turning_pair() {
    let (early, late) = turning_pair(Some(0.5));
    assert!(
        late < 1e-6,
        "still at {late} m/s after 1.1 s ({early} m/s at 0.1 s)"
    );
}
