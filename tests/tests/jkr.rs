//! JKR against docs/physics.md: the force-overlap curve, the pull-off force, attraction down to the
//! critical negative overlap and no attraction before first contact.

mod common;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;

const GAMMA: f64 = 0.356;

/// Force (N, positive repulsive) the model gives along a quasi-static path of overlaps.
fn path(overlaps: &[f64]) -> Vec<Option<f64>> {
    let m = model(&spec("jkr", None, None, None), &[("surface_energy", GAMMA)]);
    let mut h = vec![0.0; m.history_stride()];
    overlaps
        .iter()
        .map(|&d| {
            let c = contact_at(d, DVec3::ZERO, 1e-6);
            m.evaluate(0, 0, &c, &mut h).map(|o| -o.force.x)
        })
        .collect()
}

#[test]
fn force_overlap_curve_matches_the_parametric_formula() {
    let (e, r) = (e_eff(), R / 2.0);
    // Walk a from large to small along the stable branch (a above the overlap minimum,
    // a^3 = pi gamma R*^2 / (4 E*)), stopping before delta_c:
    // delta(a) = a^2/R - sqrt(4 pi gamma a/E), F(a) = 4E a^3/(3R) - 4 sqrt(pi gamma E) a^1.5.
    let a_c = (9.0 * PI * GAMMA * r * r / (2.0 * e) * (0.75 - 1.0 / 2f64.sqrt())).cbrt();
    let delta_c = a_c * a_c / r - (4.0 * PI * GAMMA * a_c / e).sqrt();
    let a_min = (PI * GAMMA * r * r / (4.0 * e)).cbrt();
    let radii: Vec<f64> = (0..400)
        .map(|k| a_min + (60e-6 - a_min) * (1.0 - k as f64 / 400.0))
        .filter(|a| a * a / r - (4.0 * PI * GAMMA * a / e).sqrt() > delta_c)
        .collect();
    assert!(radii.len() > 300);
    let overlaps: Vec<f64> = radii
        .iter()
        .map(|a| a * a / r - (4.0 * PI * GAMMA * a / e).sqrt())
        .collect();
    let forces = path(&overlaps);
    for ((a, d), f) in radii.iter().zip(&overlaps).zip(&forces) {
        let expected =
            4.0 * e * a.powi(3) / (3.0 * r) - 4.0 * (PI * GAMMA * e).sqrt() * a.powf(1.5);
        let f = f.unwrap_or_else(|| panic!("contact lost at delta = {d}"));
        assert!(
            (f - expected).abs() < 1e-9 * (3.0 * PI * GAMMA * r),
            "a = {a}, delta = {d}: F = {f} vs {expected}"
        );
    }
}

#[test]
fn minimum_force_is_the_pull_off_force() {
    let r = R / 2.0;
    // From 2 um of overlap to 2.7 um of gap, in 0.1 nm steps (delta_c is about -2.76 um).
    let overlaps: Vec<f64> = (0..47_000).map(|k| 2e-6 - k as f64 * 1e-10).collect();
    let forces = path(&overlaps);
    let min = forces
        .iter()
        .flatten()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let pull_off = -3.0 * PI * GAMMA * r;
    assert!(
        (min - pull_off).abs() / pull_off.abs() < 1e-6,
        "minimum force {min} vs -3 pi gamma R* = {pull_off}"
    );
}

#[test]
fn attraction_persists_to_the_critical_overlap_then_stops() {
    let (e, r) = (e_eff(), R / 2.0);
    let a_c = (9.0 * PI * GAMMA * r * r / (2.0 * e) * (0.75 - 1.0 / 2f64.sqrt())).cbrt();
    let delta_c = a_c * a_c / r - (4.0 * PI * GAMMA * a_c / e).sqrt();
    assert!(delta_c < 0.0);
    let overlaps = [
        1e-6,
        0.0,
        0.5 * delta_c,
        0.999 * delta_c,
        1.001 * delta_c,
        0.5 * delta_c,
    ];
    let f = path(&overlaps);
    assert!(
        f[1].unwrap() < 0.0 && f[2].unwrap() < 0.0 && f[3].unwrap() < 0.0,
        "attractive down to delta_c: {f:?}"
    );
    assert_eq!(f[4], None, "broken beyond delta_c");
    // Once broken, no force at a gap until the particles touch again (hysteresis).
    assert_eq!(
        f[5], None,
        "no attraction across a gap before contact re-forms"
    );
    // Approaching from a gap: nothing until touching.
    let g = path(&[0.5 * delta_c, 1e-9]);
    assert_eq!(g[0], None);
    assert!(g[1].is_some());
}

#[test]
fn zero_surface_energy_is_hertz() {
    let r = R / 2.0;
    let f = path(&[1e-6])[0].unwrap();
    let m = model(&spec("jkr", None, None, None), &[("surface_energy", 0.0)]);
    let mut h = vec![0.0; m.history_stride()];
    let f0 = -m
        .evaluate(0, 0, &contact_at(1e-6, DVec3::ZERO, 1e-6), &mut h)
        .unwrap()
        .force
        .x;
    let hertz = 4.0 / 3.0 * e_eff() * r.sqrt() * 1e-6f64.powf(1.5);
    assert!(
        (f0 - hertz).abs() < 1e-10 * hertz,
        "gamma = 0 gives Hertz: {f0} vs {hertz}"
    );
    assert!(f < f0, "adhesion lowers the force");
}

/// The Coulomb load of each convention (docs/physics.md): `jkr` (EDEM) the Hertz part
/// 4 E* a^3 / (3 R*), `jkr_lammps` LAMMPS's |F + 2 F_po|, F_po = 3 pi gamma R*. At the overlap
/// of no net force (a^3 = 9 pi gamma R*^2 / E*) they are 12 and 6 pi gamma R*; in compression
/// they differ by 2 F_po - (Hertz part - F) and at the force minimum `jkr_lammps` still
/// carries F_po.
#[test]
fn each_convention_loads_friction_as_its_code_does() {
    use tilth_kernel::contact::NormalLaw;
    use tilth_kernel::contact::laws::{jkr::Jkr, jkr_lammps::JkrLammps};
    let (e, r) = (e_eff(), R / 2.0);
    let po = 3.0 * PI * GAMMA * r;
    let (edem, lammps) = (Jkr::new(e, GAMMA), JkrLammps(Jkr::new(e, GAMMA)));
    let a0 = (9.0 * PI * GAMMA * r * r / e).cbrt();
    let a_min = (9.0 * PI * GAMMA * r * r / (4.0 * e)).cbrt();
    for (a, what) in [
        (a0, "no net force"),
        (2.0 * a0, "compression"),
        (a_min * 1.0001, "near the minimum"),
    ] {
        let delta = a * a / r - (4.0 * PI * GAMMA * a / e).sqrt();
        let c = contact_at(delta, DVec3::ZERO, 1e-6);
        let (mut h1, mut h2) = ([a.sqrt()], [a.sqrt()]);
        let (f1, f2) = (edem.force(&c, &mut h1), lammps.force(&c, &mut h2));
        let hertz = 4.0 * e * a.powi(3) / (3.0 * r);
        assert!(
            (f1.elastic - f2.elastic).abs() < 1e-12 * po,
            "{what}: one force"
        );
        assert!(
            (f1.friction_load - hertz).abs() < 1e-9 * po,
            "{what}: jkr loads {}",
            f1.friction_load
        );
        let expected = (f2.elastic + 2.0 * po).abs();
        assert!(
            (f2.friction_load - expected).abs() < 1e-9 * po,
            "{what}: jkr_lammps loads {}",
            f2.friction_load
        );
        if what == "no net force" {
            assert!((f1.friction_load - 12.0 * PI * GAMMA * r).abs() < 1e-6 * po);
            assert!((f2.friction_load - 6.0 * PI * GAMMA * r).abs() < 1e-6 * po);
        }
    }
    // Past the force minimum: jkr still pulls, jkr_lammps has let go and loads nothing.
    let delta = 0.5 * (edem.pulloff_overlap(r) + edem.critical_overlap(r));
    let c = contact_at(delta, DVec3::ZERO, 1e-6);
    let a = a_min * 0.9;
    let (mut h1, mut h2) = ([a.sqrt()], [a.sqrt()]);
    assert!(edem.force(&c, &mut h1).elastic < 0.0);
    let gone = lammps.force(&c, &mut h2);
    assert_eq!((gone.elastic, gone.friction_load, h2[0]), (0.0, 0.0, 0.0));
}
