//! `sjkr` (LIGGGHTS's simplified JKR) against its formula: an attraction k A in contact, A the
//! area where the undeformed spheres intersect, for unequal spheres and against a wall; none
//! across a gap; and, in a full model, the normal force is Hertz minus k A.

mod common;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;
use tilth_kernel::contact::laws::sjkr::ENTRY;
use tilth_kernel::contact::{AnyExtra, BuiltLaw, Contact, ExtraLaw, LawInput, ModelSpec};
use tilth_kernel::param::Params;

const K: f64 = 0.356e5;

/// The intersection area of two spheres as LIGGGHTS writes it, from the centre distance d.
fn area_spheres(d: f64, ri: f64, rj: f64) -> f64 {
    -PI / 4.0 * ((d - ri - rj) * (d + ri - rj) * (d - ri + rj) * (d + ri + rj)) / (d * d)
}

/// The same area from the circle's radius a: a^2 = ri^2 - x^2, with x the distance from
/// centre i to the plane of the circle, x = (d^2 + ri^2 - rj^2) / (2 d).
fn area_from_circle(d: f64, ri: f64, rj: f64) -> f64 {
    let x = (d * d + ri * ri - rj * rj) / (2.0 * d);
    PI * (ri * ri - x * x)
}

/// Sphere against a flat wall, LIGGGHTS's wall branch: pi (ri^2 - d^2), d = ri - delta.
fn area_wall(delta: f64, ri: f64) -> f64 {
    let d = ri - delta;
    PI * (ri * ri - d * d)
}

/// The law on its own, built as the model builder builds it.
fn law(k: f64) -> AnyExtra {
    let given = params(&[("cohesion_energy_density", k)]);
    let input = LawInput {
        material_i: &soil(),
        material_j: &soil(),
        e_eff: e_eff(),
        g_eff: 1.0,
        params: Params::new(&given),
    };
    match (ENTRY.build)(&input) {
        BuiltLaw::Extra(x) => x,
        _ => panic!("sjkr is not an extra law"),
    }
}

fn spheres(ri: f64, rj: f64, overlap: f64) -> Contact {
    let dist = ri + rj - overlap;
    Contact::between_spheres(
        DVec3::new(dist, 0.0, 0.0),
        dist,
        (ri, rj),
        (1.0, 1.0),
        (1.0, 1.0),
        (DVec3::ZERO, DVec3::ZERO),
        (DVec3::ZERO, DVec3::ZERO),
        1e-6,
    )
}

fn wall(r: f64, overlap: f64) -> Contact {
    Contact::with_wall(
        DVec3::new(0.0, 0.0, r - overlap),
        DVec3::ZERO,
        r,
        1.0,
        1.0,
        DVec3::ZERO,
        DVec3::ZERO,
        DVec3::ZERO,
        1e-6,
    )
    .unwrap()
}

#[test]
fn the_two_area_formulas_agree() {
    // The test's own check that its reference is the circle of intersection.
    for (ri, rj) in [(1e-3, 1e-3), (1e-3, 0.5e-3), (0.3e-3, 2e-3)] {
        for delta in [1e-7, 1e-6, 1e-5, 1e-4] {
            let d = ri + rj - delta;
            let (a, b) = (area_spheres(d, ri, rj), area_from_circle(d, ri, rj));
            assert!((a - b).abs() < 1e-9 * a, "{ri} {rj} {delta}: {a} vs {b}");
        }
    }
}

#[test]
fn sphere_sphere_force_is_minus_k_times_the_intersection_area() {
    let x = law(K);
    let mut h: Vec<f64> = vec![];
    for (ri, rj) in [(1e-3, 1e-3), (1e-3, 0.5e-3), (0.5e-3, 1e-3), (0.3e-3, 2e-3)] {
        for delta in [1e-8, 1e-7, 1e-6, 5e-6, 2e-5, 1e-4] {
            let c = spheres(ri, rj, delta);
            let expected = -K * area_spheres(ri + rj - delta, ri, rj);
            let f = x.force(&c, &mut h);
            assert!(
                (f - expected).abs() < 1e-9 * expected.abs(),
                "ri {ri}, rj {rj}, delta {delta}: {f} vs {expected}"
            );
            // Small overlaps: A -> 2 pi R* delta.
            if delta <= 1e-7 {
                let r_eff = ri * rj / (ri + rj);
                let small = -K * 2.0 * PI * r_eff * delta;
                assert!((f - small).abs() < 1e-3 * small.abs());
            }
        }
    }
}

#[test]
fn wall_force_is_minus_k_pi_2r_delta_minus_delta_squared() {
    let x = law(K);
    let mut h: Vec<f64> = vec![];
    for r in [1e-3, 0.4e-3] {
        for delta in [1e-8, 1e-6, 1e-5, 1e-4] {
            let c = wall(r, delta);
            assert!(c.radius_j.is_infinite());
            let f = x.force(&c, &mut h);
            let expected = -K * area_wall(delta, r);
            assert!(
                (f - expected).abs() < 1e-9 * expected.abs(),
                "r {r}, delta {delta}: {f} vs {expected}"
            );
            let brief = -K * PI * (2.0 * r * delta - delta * delta);
            assert!((f - brief).abs() < 1e-9 * brief.abs());
        }
    }
}

#[test]
fn no_force_without_overlap_or_with_zero_k() {
    let x = law(K);
    let mut h: Vec<f64> = vec![];
    for delta in [0.0, -1e-9, -1e-6, -1e-4] {
        assert_eq!(x.force(&spheres(1e-3, 0.5e-3, delta), &mut h), 0.0);
        assert_eq!(x.force(&wall(1e-3, delta), &mut h), 0.0);
    }
    assert_eq!(x.reach(1e-3), 0.0);
    let off = law(0.0);
    assert_eq!(off.force(&spheres(1e-3, 1e-3, 1e-5), &mut h), 0.0);
    assert_eq!(off.force(&wall(1e-3, 1e-5), &mut h), 0.0);
}

#[test]
fn registry_entry() {
    assert_eq!(ENTRY.name, "sjkr");
    const { assert!(ENTRY.cohesive) };
    assert!(ENTRY.history.is_empty());
    let p = &ENTRY.params[0];
    assert_eq!((p.key, p.unit), ("cohesion_energy_density", "J/m^3"));
    assert!(p.contains(0.0) && p.contains(1e6) && !p.contains(-1e-9));
}

#[test]
fn in_a_model_the_normal_force_is_hertz_minus_k_a() {
    let spec = ModelSpec {
        extra: vec!["sjkr".into()],
        ..spec("hertz", Some("restitution"), Some("mindlin"), None)
    };
    let m = model(
        &spec,
        &[
            ("restitution", 0.45),
            ("friction", 0.6),
            ("cohesion_energy_density", K),
        ],
    );
    let r_eff = R / 2.0;
    let mut h = vec![0.0; m.history_stride()];
    // At rest (no damping, no tangential motion), loading then unloading.
    for delta in [1e-7, 1e-6, 5e-6, 2e-5, 5e-6, 1e-7] {
        let o = m
            .evaluate(0, 0, &contact_at(delta, DVec3::ZERO, 1e-6), &mut h)
            .unwrap();
        // Force on i is -n F_n with n = +x.
        let f_n = -o.force.x;
        let hertz = 4.0 / 3.0 * e_eff() * r_eff.sqrt() * delta.powf(1.5);
        let expected = hertz - K * area_spheres(2.0 * R - delta, R, R);
        let scale = hertz.abs() + K * area_spheres(2.0 * R - delta, R, R);
        assert!(
            (f_n - expected).abs() < 1e-9 * scale,
            "delta {delta}: {f_n} vs {expected}"
        );
        assert_eq!(o.force.y, 0.0);
        assert_eq!(o.force.z, 0.0);
    }
    // At small overlaps the cohesion wins: the net force pulls.
    let o = m
        .evaluate(0, 0, &contact_at(1e-9, DVec3::ZERO, 1e-6), &mut h)
        .unwrap();
    assert!(-o.force.x < 0.0);
    // Separated: the contact ends, no force across the gap.
    assert!(
        m.evaluate(0, 0, &contact_at(-1e-7, DVec3::ZERO, 1e-6), &mut h)
            .is_none()
    );
}

#[test]
fn a_negative_cohesion_energy_density_is_refused() {
    let spec = ModelSpec {
        extra: vec!["sjkr".into()],
        ..spec("hertz", None, None, None)
    };
    let err = tilth_kernel::contact::ContactModel::build(
        &[soil()],
        &spec,
        &[tilth_kernel::contact::PairSpec {
            materials: ("soil".into(), "soil".into()),
            params: params(&[("cohesion_energy_density", -1.0)]),
        }],
    );
    assert!(err.is_err());
}
