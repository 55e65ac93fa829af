//! Contact laws against their formulas: restitution, Coulomb, JKR, rolling resistance.

mod common;
use common::*;
use glam::DVec3;

fn restitution_pp(e: f64) -> f64 {
    let m = model(
        &spec("hertz", Some("restitution"), Some("mindlin"), None),
        &[("restitution", e), ("friction", 0.3)],
    );
    let mut s = sim(m, head_on_pair(0.5), vec![], 1e-8, DVec3::ZERO, 1);
    s.run(40_000).unwrap();
    let v = &s.particles.velocity;
    (v[1].x - v[0].x) / 1.0
}

#[test]
fn head_on_restitution_particle_particle() {
    for e in [0.2, 0.45, 0.9] {
        let got = restitution_pp(e);
        eprintln!("e = {e}: measured {got}");
        assert!((got - e).abs() / e < 0.01, "e = {e}: measured {got}");
    }
}

#[test]
fn head_on_restitution_particle_wall() {
    for e in [0.2, 0.45, 0.9] {
        let m = model(
            &spec("hertz", Some("restitution"), Some("mindlin"), None),
            &[("restitution", e), ("friction", 0.3)],
        );
        let mut p = tilth_kernel::particles::Particles::default();
        p.push(
            DVec3::new(0.0, 0.0, 1.05 * R),
            DVec3::new(0.0, 0.0, -0.5),
            R,
            RHO,
            0,
        );
        let floor = floor();
        let mut s = sim(m, p, vec![floor], 1e-8, DVec3::ZERO, 1);
        s.run(40_000).unwrap();
        let got = s.particles.velocity[0].z / 0.5;
        eprintln!("wall e = {e}: measured {got}");
        assert!((got - e).abs() / e < 0.01, "e = {e}: measured {got}");
    }
}

/// Equilibrium overlap of a sphere resting on a plane: m g = 4/3 E* sqrt(R) delta^1.5.
#[test]
fn hertz_static_overlap_under_gravity() {
    let m = model(
        &spec("hertz", Some("restitution"), Some("mindlin"), None),
        &[("restitution", 0.2), ("friction", 0.5)],
    );
    let mut p = tilth_kernel::particles::Particles::default();
    p.push(DVec3::new(0.0, 0.0, R), DVec3::ZERO, R, RHO, 0);
    let mass = p.mass[0];
    let floor = floor();
    let mut s = sim(m, p, vec![floor], 1e-6, DVec3::new(0.0, 0.0, -9.81), 1);
    s.run(20_000).unwrap();
    // Wall and particle both soil: 1/E* = 2 (1 - nu^2) / E.
    let expected = (3.0 * mass * 9.81 / (4.0 * e_eff() * R.sqrt())).powf(2.0 / 3.0);
    let got = R - s.particles.position[0].z;
    assert!(
        (got - expected).abs() / expected < 1e-3,
        "overlap {got} vs Hertz {expected}"
    );
    // The floor carries the weight.
    assert!(
        (s.walls[0].force.z + mass * 9.81).abs() / (mass * 9.81) < 1e-3,
        "floor force {:?}",
        s.walls[0].force
    );
}

/// Hertz law evaluated directly against F = 4/3 E* sqrt(R*) delta^1.5 for several overlaps.
#[test]
fn hertz_force_versus_overlap() {
    use tilth_kernel::contact::Contact;
    let m = model(&spec("hertz", None, None, None), &[]);
    let r_eff = R / 2.0;
    for delta in [1e-8, 1e-7, 1e-6, 1e-5, 5e-5] {
        let dist = 2.0 * R - delta;
        let c = Contact::between_spheres(
            DVec3::new(dist, 0.0, 0.0),
            dist,
            (R, R),
            (1.0, 1.0),
            (1.0, 1.0),
            (DVec3::ZERO, DVec3::ZERO),
            (DVec3::ZERO, DVec3::ZERO),
            1e-6,
        );
        let mut h = vec![0.0; m.history_stride()];
        let out = m.evaluate(0, 0, &c, &mut h).unwrap();
        let delta = 2.0 * R - dist; // the overlap as represented after rounding
        let expected = 4.0 / 3.0 * e_eff() * r_eff.sqrt() * delta.powf(1.5);
        assert!(
            (-out.force.x - expected).abs() <= 1e-12 * expected,
            "delta {delta}: {} vs {expected}",
            -out.force.x
        );
    }
}

/// A sphere held against rolling (large EPSD rolling friction) on an incline sticks when
/// tan(theta) < mu and slides with a = g (sin theta - mu cos theta) when tan(theta) > mu.
#[test]
fn coulomb_cap_on_inclined_plane() {
    let mu: f64 = 0.5;
    let run = |theta_deg: f64| {
        let th = theta_deg.to_radians();
        let m = model(
            &spec("hertz", Some("restitution"), Some("mindlin"), Some("epsd")),
            &[
                ("restitution", 0.2),
                ("friction", mu),
                ("rolling_friction", 20.0),
            ],
        );
        let mut p = tilth_kernel::particles::Particles::default();
        let mass = 4.0 / 3.0 * std::f64::consts::PI * R.powi(3) * RHO;
        let delta = (3.0 * mass * 9.81 * th.cos() / (4.0 * e_eff() * R.sqrt())).powf(2.0 / 3.0);
        p.push(DVec3::new(0.0, 0.0, R - delta), DVec3::ZERO, R, RHO, 0);
        let floor = floor();
        let g = DVec3::new(9.81 * th.sin(), 0.0, -9.81 * th.cos());
        let mut s = sim(m, p, vec![floor], 1e-6, g, 1);
        s.run(20_000).unwrap(); // 0.02 s to settle
        let (x0, v0) = (s.particles.position[0].x, s.particles.velocity[0].x);
        s.run(50_000).unwrap(); // 0.05 s of measurement
        let t = 0.05;
        let x1 = s.particles.position[0].x;
        let accel = 2.0 * (x1 - x0 - v0 * t) / (t * t);
        (x1 - x0, accel, 9.81 * (th.sin() - mu * th.cos()))
    };
    let critical = mu.atan().to_degrees();
    let (dx, _, _) = run(critical - 2.0);
    assert!(
        dx.abs() < 1e-7,
        "below atan(mu) the sphere must stick, moved {dx} m"
    );
    let (dx, accel, expected) = run(critical + 2.0);
    assert!(
        dx > 1e-4,
        "above atan(mu) the sphere must slide, moved {dx} m"
    );
    assert!(
        (accel - expected).abs() / expected < 0.02,
        "sliding acceleration {accel} vs {expected}"
    );
}

/// Without rolling resistance a sphere rolls without slipping down a gentle slope with
/// a = 5/7 g sin(theta) (tan(theta) < 7/2 mu).
#[test]
fn rolling_without_slip_on_incline() {
    let th: f64 = 10f64.to_radians();
    let m = model(
        &spec("hertz", Some("restitution"), Some("mindlin"), None),
        &[("restitution", 0.2), ("friction", 0.5)],
    );
    let mut p = tilth_kernel::particles::Particles::default();
    p.push(DVec3::new(0.0, 0.0, R), DVec3::ZERO, R, RHO, 0);
    let floor = floor();
    let g = DVec3::new(9.81 * th.sin(), 0.0, -9.81 * th.cos());
    let mut s = sim(m, p, vec![floor], 1e-6, g, 1);
    s.run(5_000).unwrap();
    let (x0, v0) = (s.particles.position[0].x, s.particles.velocity[0].x);
    s.run(50_000).unwrap();
    let t = 0.05;
    let accel = 2.0 * (s.particles.position[0].x - x0 - v0 * t) / (t * t);
    let expected = 5.0 / 7.0 * 9.81 * th.sin();
    assert!(
        (accel - expected).abs() / expected < 0.01,
        "rolling acceleration {accel} vs {expected}"
    );
    // Rolling, not sliding: contact point velocity ~ 0.
    let slip = s.particles.velocity[0].x - s.particles.angular_velocity[0].y * R;
    assert!(
        slip.abs() < 1e-3 * s.particles.velocity[0].x,
        "slip velocity {slip}"
    );
}

/// A sphere rolling on a plane decelerates at 5/7 mu_r g under CDT and (once the spring has
/// yielded) EPSD, whose torque cap mu_r R F_n equals CDT's torque on a wall.
fn rolling_deceleration(law: &str) -> (f64, f64, tilth_kernel::sim::Simulation) {
    let mu_r = 0.1;
    let m = model(
        &spec("hertz", Some("restitution"), Some("mindlin"), Some(law)),
        &[
            ("restitution", 0.2),
            ("friction", 0.5),
            ("rolling_friction", mu_r),
        ],
    );
    let mut p = tilth_kernel::particles::Particles::default();
    let v0 = 0.1;
    p.push(DVec3::new(0.0, 0.0, R), DVec3::new(v0, 0.0, 0.0), R, RHO, 0);
    p.angular_velocity[0] = DVec3::new(0.0, v0 / R, 0.0);
    let floor = floor();
    let mut s = sim(m, p, vec![floor], 1e-6, DVec3::new(0.0, 0.0, -9.81), 1);
    s.run(2_000).unwrap();
    let v1 = s.particles.velocity[0].x;
    s.run(20_000).unwrap();
    let v2 = s.particles.velocity[0].x;
    let decel = (v1 - v2) / 0.02;
    (decel, 5.0 / 7.0 * mu_r * 9.81, s)
}

#[test]
fn cdt_decelerates_rolling_sphere_as_predicted() {
    let (decel, expected, _) = rolling_deceleration("cdt");
    assert!(
        (decel - expected).abs() / expected < 0.02,
        "CDT deceleration {decel} vs {expected}"
    );
}

#[test]
fn epsd_decelerates_rolling_sphere_and_stops() {
    let (decel, expected, mut s) = rolling_deceleration("epsd");
    assert!(
        (decel - expected).abs() / expected < 0.02,
        "EPSD deceleration {decel} vs {expected}"
    );
    // v0 = 0.1 m/s stops after v0 / a ~ 0.2 s; run 0.4 s more and check it stays at rest.
    s.run(400_000).unwrap();
    let v = s.particles.velocity[0].length();
    let w = s.particles.angular_velocity[0].length();
    assert!(
        v < 1e-5 && w * R < 1e-5,
        "EPSD sphere must come to rest: v = {v}, omega R = {}",
        w * R
    );
}
