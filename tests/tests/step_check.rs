//! `step_check`: the kernel's bound on the contacts' stiffest mode, against Hertz-Mindlin
//! written out for one pair.

mod common;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;
use tilth_kernel::contact::laws::restitution::beta;
use tilth_kernel::step_check::{loaded_step_warning, packing_frequency};

/// Two grains meeting head on, checked at their deepest overlap: one contact, so each
/// grain's row sum is that contact's omega^2 = max(7 k_t / m, 2 k_n / m) with
/// k_n = 2 E* a, k_t = 8 G* a, a = sqrt(R* delta); and the mode's damping ratio is the
/// restitution law's sqrt(5/6) |beta| sqrt(7/2).
#[test]
fn one_contact_s_frequency_and_damping_are_hertz_mindlin_s() {
    let restitution = 0.45;
    let m = model(
        &spec("hertz", Some("restitution"), Some("mindlin"), None),
        &[("restitution", restitution), ("friction", 0.5)],
    );
    let mut s = sim(m, head_on_pair(0.5), vec![], 1e-7, DVec3::ZERO, 1);
    assert!(
        packing_frequency(&s.particles, &s.model, s.pairs(), s.dt).is_none(),
        "nothing touches yet"
    );
    // Step to the deepest overlap (the grains approach at 1 m/s from a 0.1 mm gap).
    let gap = |s: &tilth_kernel::sim::Simulation| {
        (s.particles.position[1] - s.particles.position[0]).length() - 2.0 * R
    };
    let mut deepest = f64::NEG_INFINITY;
    loop {
        s.run(1).unwrap();
        let overlap = -gap(&s);
        if overlap > 0.0 && overlap < deepest {
            break;
        }
        deepest = overlap;
    }
    let delta = -gap(&s);
    assert!(delta > 1e-6, "overlap {delta}");
    let f = packing_frequency(&s.particles, &s.model, s.pairs(), s.dt).unwrap();
    assert_eq!((f.grains, f.contacts), (2, 1));

    let a = (R / 2.0 * delta).sqrt();
    let g = E / (2.0 * (1.0 + NU));
    let g_star = g / (2.0 * (2.0 - NU));
    let (k_n, k_t) = (2.0 * e_eff() * a, 8.0 * g_star * a);
    let mass = RHO * 4.0 / 3.0 * PI * R.powi(3);
    let omega = ((7.0 * k_t).max(2.0 * k_n) / mass).sqrt();
    assert!(
        (f.omega / omega - 1.0).abs() < 1e-9,
        "{} vs {omega}",
        f.omega
    );
    let zeta = (5.0f64 / 6.0).sqrt() * beta(restitution).abs() * 3.5f64.sqrt();
    assert!((f.zeta / zeta - 1.0).abs() < 1e-9, "{} vs {zeta}", f.zeta);
    let limit = 2.0 * ((1.0 + zeta * zeta).sqrt() - zeta);
    assert!((f.stable_step() - limit / omega).abs() < 1e-12 * f.stable_step());

    // The warning comes just past the limit, not just short of it, and names the step to use.
    assert!(loaded_step_warning(0.99 * f.stable_step(), &f).is_none());
    let w = loaded_step_warning(1.01 * f.stable_step(), &f).unwrap();
    assert!(w.contains(&format!("{:.3e} s", f.stable_step())), "{w}");
}
