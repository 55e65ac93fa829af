//! `mindlin_incremental` against its definition: at constant contact radius it is Mindlin
//! (F = -8 G* a x, capped at mu F_n); a stiffening contact keeps its force; a shrinking one
//! scales it by a_new / a_old.

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::contact::ContactModel;

const DT: f64 = 1e-6;

fn law() -> ContactModel {
    model(
        &spec("hertz", None, Some("mindlin_incremental"), None),
        &[("friction", 0.5)],
    )
}

fn g_eff() -> f64 {
    1.0 / (2.0 * 2.0 * (2.0 - NU) * (1.0 + NU) / E)
}

#[test]
fn constant_radius_spring_and_cap() {
    let m = law();
    let mut h = vec![0.0; m.history_stride()];
    let delta = 1e-6;
    let a = (R / 2.0 * delta).sqrt();
    let s_t = 8.0 * g_eff() * a;
    let hertz = 4.0 / 3.0 * (e_eff()) * (R / 2.0).sqrt() * delta.powf(1.5);
    let mut shift = 0.0;
    for k in 1..=2000 {
        let out = m
            .evaluate(
                0,
                0,
                &contact_at(delta, DVec3::new(0.0, 1e-3, 0.0), DT),
                &mut h,
            )
            .unwrap();
        shift += 1e-3 * DT;
        let expected = (s_t * shift).min(0.5 * hertz);
        assert!(
            (-out.force.y - expected).abs() < 1e-9 * expected.max(1e-12),
            "step {k}: {} vs {expected}",
            -out.force.y
        );
    }
    assert!(s_t * shift > 0.5 * hertz, "the test reached sliding");
}

#[test]
fn stiffening_keeps_force_and_shrinking_scales_it() {
    let m = law();
    let mut h = vec![0.0; m.history_stride()];
    // Build up a small spring force at overlap 1 um (well below the cap).
    for _ in 0..100 {
        m.evaluate(
            0,
            0,
            &contact_at(1e-6, DVec3::new(0.0, 1e-4, 0.0), DT),
            &mut h,
        )
        .unwrap();
    }
    let f0 = -m
        .evaluate(
            0,
            0,
            &contact_at(1e-6, DVec3::new(0.0, 0.0, 0.0), DT),
            &mut h,
        )
        .unwrap()
        .force
        .y;
    // Load to 4 um: the contact radius doubles, the force stays.
    let f1 = -m
        .evaluate(
            0,
            0,
            &contact_at(4e-6, DVec3::new(0.0, 0.0, 0.0), DT),
            &mut h,
        )
        .unwrap()
        .force
        .y;
    assert!(
        (f1 - f0).abs() < 1e-12 * f0,
        "loading changed the force: {f0} -> {f1}"
    );
    // Unload back to 1 um: a halves, and so does the force.
    let f2 = -m
        .evaluate(
            0,
            0,
            &contact_at(1e-6, DVec3::new(0.0, 0.0, 0.0), DT),
            &mut h,
        )
        .unwrap()
        .force
        .y;
    assert!(
        (f2 - 0.5 * f0).abs() < 1e-12 * f0,
        "unloading: {f2} vs {}",
        0.5 * f0
    );
}
