//! `plastic_adhesion` against its formula: after loading to delta_max, the contact pulls with
//! lambda F_H(delta_max) on top of the elastic force, until the overlap is gone; the next
//! contact starts from nothing.

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::contact::ModelSpec;

const LAMBDA: f64 = 0.3;

fn hertz_force(delta: f64) -> f64 {
    4.0 / 3.0 * e_eff() * (R / 2.0).sqrt() * delta.max(0.0).powf(1.5)
}

#[test]
fn pull_off_is_lambda_times_the_largest_hertz_load() {
    let spec = ModelSpec {
        extra: vec!["plastic_adhesion".into()],
        ..spec("hertz", None, None, None)
    };
    let m = model(&spec, &[("plastic_adhesion", LAMBDA)]);
    let mut h = vec![0.0; m.history_stride()];
    // Net repulsive normal force on the pair (force on i is -n F, n = +x).
    let f = |delta: f64, h: &mut Vec<f64>| {
        m.evaluate(0, 0, &contact_at(delta, DVec3::ZERO, 1e-6), h)
            .map_or(0.0, |o| -o.force.x)
    };
    let d1 = 3e-5;
    // Loading: the adhesion follows the current (= largest) overlap.
    for k in 1..=10 {
        let d = d1 * k as f64 / 10.0;
        let expected = (1.0 - LAMBDA) * hertz_force(d);
        assert!(
            (f(d, &mut h) - expected).abs() < 1e-12 * hertz_force(d1),
            "{d}"
        );
    }
    // Unloading: the pull-off stays at lambda F_H(delta_max).
    for k in (1..10).rev() {
        let d = d1 * k as f64 / 10.0;
        let expected = hertz_force(d) - LAMBDA * hertz_force(d1);
        assert!(
            (f(d, &mut h) - expected).abs() < 1e-12 * hertz_force(d1),
            "{d}"
        );
    }
    // Separated: no force, and a new contact remembers nothing.
    assert_eq!(f(-1e-7, &mut h), 0.0);
    let d = 0.1 * d1;
    let again = f(d, &mut h);
    assert!((again - (1.0 - LAMBDA) * hertz_force(d)).abs() < 1e-12 * hertz_force(d1));
}

#[test]
fn zero_plastic_adhesion_is_plain_hertz() {
    let spec = ModelSpec {
        extra: vec!["plastic_adhesion".into()],
        ..spec("hertz", None, None, None)
    };
    let m = model(&spec, &[("plastic_adhesion", 0.0)]);
    let mut h = vec![0.0; m.history_stride()];
    for d in [1e-5, 3e-5, 1e-5] {
        let o = m
            .evaluate(0, 0, &contact_at(d, DVec3::ZERO, 1e-6), &mut h)
            .unwrap();
        assert!((-o.force.x - hertz_force(d)).abs() < 1e-12 * hertz_force(d));
    }
}
