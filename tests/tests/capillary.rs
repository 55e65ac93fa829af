//! The worked example of kernel/ADDING_A_LAW.md: the `capillary` extra law against the
//! Willett et al. (2000) closed form and the Lian et al. (1993) rupture distance.

mod common;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;
use tilth_kernel::contact::{ContactModel, ModelSpec, PairSpec};

const V: f64 = 1e-11; // bridge volume, m^3 (about 0.3 % of a 2 mm sphere)
const GAMMA: f64 = 0.072;
const THETA_DEG: f64 = 20.0;

fn capillary_model() -> ContactModel {
    let spec = ModelSpec {
        extra: vec!["capillary".into()],
        ..spec("hertz", None, None, None)
    };
    let pair = PairSpec {
        materials: ("soil".into(), "soil".into()),
        params: params(&[
            ("bridge_volume", V),
            ("surface_tension", GAMMA),
            ("contact_angle", THETA_DEG),
        ]),
    };
    ContactModel::build(&[soil()], &spec, &[pair]).unwrap()
}

#[test]
fn bridge_force_follows_willett_and_ruptures_at_lian_distance() {
    let m = capillary_model();
    let mut h = vec![0.0; m.history_stride()];
    let r_eff = R / 2.0;
    let theta = THETA_DEG.to_radians();
    let rupture = (1.0 + theta / 2.0) * V.cbrt();
    // Forms on contact.
    assert!(
        m.evaluate(0, 0, &contact_at(1e-7, DVec3::ZERO, 1e-6), &mut h)
            .is_some()
    );
    for k in 1..20 {
        let gap = rupture * k as f64 / 20.0;
        let f = -m
            .evaluate(0, 0, &contact_at(-gap, DVec3::ZERO, 1e-6), &mut h)
            .expect("bridge holds below the rupture gap")
            .force
            .x;
        let s = gap * (r_eff / V).sqrt();
        let expected = -2.0 * PI * r_eff * GAMMA * theta.cos() / (1.0 + 1.05 * s + 2.5 * s * s);
        assert!(
            (f - expected).abs() < 1e-12 * expected.abs(),
            "gap {gap}: {f} vs {expected}"
        );
    }
    assert!(
        m.evaluate(
            0,
            0,
            &contact_at(-1.001 * rupture, DVec3::ZERO, 1e-6),
            &mut h
        )
        .is_none(),
        "ruptured beyond S_c"
    );
    assert!(
        m.evaluate(0, 0, &contact_at(-0.5 * rupture, DVec3::ZERO, 1e-6), &mut h)
            .is_none(),
        "no bridge across a gap before contact"
    );
}

#[test]
fn bridge_reach_keeps_pairs_in_the_neighbour_list() {
    let m = capillary_model();
    let rupture = (1.0 + THETA_DEG.to_radians() / 2.0) * V.cbrt();
    assert!((m.max_reach(R) - rupture).abs() < 1e-15);
}

/// JKR and a liquid bridge together: the bridge outreaches the JKR neck. Past the neck's
/// breaking overlap delta_c only the bridge pulls (no JKR force from beyond its stable
/// branch), and the neck does not re-form at a gap when the particles come back.
#[test]
fn a_bridge_outlasting_a_jkr_neck_pulls_alone_past_its_break() {
    let spec = ModelSpec {
        extra: vec!["capillary".into()],
        ..spec("jkr", None, None, None)
    };
    let pair = PairSpec {
        materials: ("soil".into(), "soil".into()),
        params: params(&[
            ("surface_energy", 0.356),
            ("bridge_volume", V),
            ("surface_tension", GAMMA),
            ("contact_angle", THETA_DEG),
        ]),
    };
    let m = ContactModel::build(&[soil()], &spec, &[pair]).unwrap();
    let jkr = tilth_kernel::contact::laws::jkr::Jkr::new(e_eff(), 0.356);
    let r_eff = R / 2.0;
    let delta_c = jkr.critical_overlap(r_eff);
    let theta = THETA_DEG.to_radians();
    let rupture = (1.0 + theta / 2.0) * V.cbrt();
    assert!(
        rupture > -delta_c,
        "the bridge must outreach the neck for this test"
    );
    let bridge = |gap: f64| {
        let s = gap * (r_eff / V).sqrt();
        2.0 * PI * r_eff * GAMMA * theta.cos() / (1.0 + 1.05 * s + 2.5 * s * s)
    };
    let mut h = vec![0.0; m.history_stride()];
    let at = |d: f64, h: &mut Vec<f64>| {
        m.evaluate(0, 0, &contact_at(d, DVec3::ZERO, 1e-6), h)
            .map(|o| -o.force.x)
    };
    at(1e-7, &mut h).expect("forms on touching");
    // Inside the neck's range: JKR plus bridge (JKR attracts here, so more than the bridge).
    let inside = 0.5 * delta_c;
    let f_in = at(inside, &mut h).unwrap();
    assert!(f_in < -bridge(-inside), "{f_in}");
    // Past delta_c: the bridge alone, exactly.
    for k in [1.01, 1.5, 3.0] {
        let d = k * delta_c;
        if -d >= rupture {
            continue;
        }
        let f = at(d, &mut h).unwrap();
        assert!(
            (f + bridge(-d)).abs() < 1e-12 * bridge(-d),
            "{d}: {f} vs {}",
            -bridge(-d)
        );
    }
    // Back inside the neck's range without touching: still the bridge alone.
    let f_back = at(inside, &mut h).unwrap();
    assert!(
        (f_back + bridge(-inside)).abs() < 1e-12 * bridge(-inside),
        "{f_back}"
    );
}
