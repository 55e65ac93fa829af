//! Contact laws against their formulas: restitution, Coulomb, JKR, rolling resistance.

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::wall::{Motion, Wall, plane::Plane};

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
        let floor = Wall::new(
            "floor",
            Box::new(Plane::new(DVec3::ZERO, DVec3::Z).unwrap()),
            0,
            Motion::Fixed,
        );
        let mut s = sim(m, p, vec![floor], 1e-8, DVec3::ZERO, 1);
        s.run(40_000).unwrap();
        let got = s.particles.velocity[0].z / 0.5;
        eprintln!("wall e = {e}: measured {got}");
        assert!((got - e).abs() / e < 0.01, "e = {e}: measured {got}");
    }
}
