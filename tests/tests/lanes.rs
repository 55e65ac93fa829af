//! The pair phase evaluates touching contacts [`LANES`] at a time through the laws' lane
//! forms. Each must give its scalar form's bits: checked here for every registered contact
//! law, in the whole pipeline, on random touching contacts with random history, and on
//! whole runs with and without lanes.

mod common;
use common::*;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tilth_kernel::contact::contact_lanes::SpheresLanes;
use tilth_kernel::contact::laws::REGISTRY;
use tilth_kernel::contact::{
    Contact, ContactLanes, ContactModel, ContactOut, F, LANES, LaneLaws, ModelSpec, Slot,
};

/// Models that together use every registered contact law (the bond law runs in the scalar
/// pipeline only), with coefficients that give contacts force.
fn models() -> Vec<(String, ContactModel)> {
    let with = |normal: &str, tangential: &str, rolling: Option<&str>, extra: &[&str]| ModelSpec {
        normal: normal.into(),
        damping: Some("restitution".into()),
        tangential: Some(tangential.into()),
        rolling: rolling.map(Into::into),
        extra: extra.iter().map(|x| x.to_string()).collect(),
    };
    let coefficients = [
        ("restitution", 0.45),
        ("friction", 0.6),
        ("rolling_friction", 0.15),
        ("surface_energy", 0.356),
        ("cohesion_energy_density", 3.0e4),
        ("bridge_volume", 2.0e-12),
        ("moisture", 0.1),
        ("bridge_share", 0.5),
        ("twisting_friction", 0.1),
        ("plastic_adhesion", 0.3),
    ];
    let specs = [
        with("hertz", "mindlin", Some("cdt"), &["sjkr"]),
        with("jkr", "mindlin", Some("epsd"), &[]),
        with("jkr_lammps", "mindlin", Some("cdt"), &[]),
        with(
            "hertz",
            "mindlin_incremental",
            Some("cdt"),
            &["capillary", "twisting"],
        ),
        with(
            "hertz",
            "mindlin",
            Some("epsd"),
            &["capillary_moisture", "plastic_adhesion"],
        ),
        with("hertz", "coulomb_viscous", None, &[]),
    ];
    specs
        .iter()
        .map(|s| {
            let used: Vec<&str> = [&s.normal, s.tangential.as_ref().unwrap()]
                .into_iter()
                .chain(s.rolling.as_ref())
                .chain(&s.extra)
                .map(|x| x.as_str())
                .collect();
            let names: Vec<&str> = coefficients.iter().map(|(k, _)| *k).collect();
            // Each model takes the coefficients its laws declare.
            let mut kv = vec![];
            for e in REGISTRY
                .iter()
                .filter(|e| used.contains(&e.name) || e.name == "restitution")
            {
                for p in e.params {
                    if let Some(i) = names.iter().position(|n| *n == p.key) {
                        kv.push(coefficients[i]);
                    }
                }
            }
            (used.join("+"), model(s, &kv))
        })
        .collect()
}

/// A random touching contact's bodies: spheres of 0.5-1.5 mm overlapping by up to 5 % of
/// the smaller radius, moving and spinning.
fn random_spheres(rng: &mut ChaCha8Rng) -> (DVec3, f64, [f64; 6], [DVec3; 4]) {
    let r: (f64, f64) = (
        rng.random_range(0.5e-3..1.5e-3),
        rng.random_range(0.5e-3..1.5e-3),
    );
    let overlap = rng.random_range(1e-9..0.05) * r.0.min(r.1);
    let dir = DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize();
    let d = dir * (r.0 + r.1 - overlap);
    let m = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) * RHO;
    let bodies = [
        r.0,
        r.1,
        m(r.0),
        m(r.1),
        0.4 * m(r.0) * r.0 * r.0,
        0.4 * m(r.1) * r.1 * r.1,
    ];
    let mut vec3 = |s: f64| {
        DVec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let motion = [vec3(0.5), vec3(0.5), vec3(200.0), vec3(200.0)];
    (d, d.length(), bodies, motion)
}

fn same_bits(a: DVec3, b: DVec3) -> bool {
    a.to_array()
        .iter()
        .zip(b.to_array())
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// An established contact's history or a new one's. The values span the scales the laws
/// keep (springs of nm to mm, JKR's sqrt(a) ~ 1e-3 m^(1/2)), so contacts stick and slide,
/// and JKR's Newton starts from its last root or from its own guess.
fn random_history(rng: &mut ChaCha8Rng, stride: usize) -> Vec<f64> {
    let mut row = vec![0.0; stride];
    if rng.random_bool(0.7) {
        row[0] = 1.0;
        for x in &mut row[1..] {
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            *x = sign * 10f64.powf(rng.random_range(-9.0..-1.0));
        }
    }
    row
}

/// Evaluates `lanes` (lanes `0..scalar.len()` are the contacts `scalar`, histories `rows`)
/// in lanes and each contact alone, and asserts the same bits for the geometry, the
/// outputs and the histories written. Returns how many contacts carried force.
fn same_as_scalar(
    name: &str,
    m: &ContactModel,
    lanes: &ContactLanes,
    scalar: &[Contact],
    rows: &[Vec<f64>],
) -> usize {
    let stride = m.history_stride();
    let mut history: Vec<F> = (0..stride)
        .map(|v| F(std::array::from_fn(|l| rows[l.min(rows.len() - 1)][v])))
        .collect();
    let out = m.evaluate_lanes(0, 0, lanes, &mut history).unwrap();
    let mut forces = 0;
    for (l, c) in scalar.iter().enumerate() {
        assert_eq!(
            format!("{:?}", lanes.lane(l)),
            format!("{c:?}"),
            "{name}: geometry"
        );
        let mut row = rows[l].clone();
        let want: ContactOut = m.evaluate(0, 0, c, &mut row).unwrap();
        let got = (
            out.force.lane(l),
            out.torque_i.lane(l),
            out.torque_j.lane(l),
        );
        assert!(
            same_bits(got.0, want.force)
                && same_bits(got.1, want.torque_i)
                && same_bits(got.2, want.torque_j),
            "{name}, lane {l} of {}: lanes {got:?}, scalar {want:?}",
            scalar.len()
        );
        for (v, x) in row.iter().enumerate() {
            assert_eq!(
                history[v].0[l].to_bits(),
                x.to_bits(),
                "{name}, lane {l}: history value {v}"
            );
        }
        forces += (want.force != DVec3::ZERO) as usize;
    }
    forces
}

#[test]
fn every_contact_law_in_lanes_gives_its_scalar_bits() {
    let models = models();
    // Every registered contact law is in one of the models.
    for e in REGISTRY.iter().filter(|e| e.slot != Slot::Bond) {
        assert!(
            models
                .iter()
                .any(|(name, _)| name.split('+').any(|n| n == e.name))
                || e.name == "restitution",
            "law '{}' is in none of the models: add it, so its lane form is checked",
            e.name
        );
    }
    let dt = 5e-6;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (name, m) in &models {
        let stride = m.history_stride();
        let mut forces = 0;
        for round in 0..400 {
            let count = 1 + round % LANES;
            let mut s = SpheresLanes::ZERO;
            let mut scalar = vec![];
            let mut rows = vec![];
            for l in 0..LANES {
                let (d, dist, b, w) = random_spheres(&mut rng);
                s.d.set_lane(l, d);
                s.dist.0[l] = dist;
                (s.r.0.0[l], s.r.1.0[l]) = (b[0], b[1]);
                (s.m.0.0[l], s.m.1.0[l]) = (b[2], b[3]);
                (s.inertia.0.0[l], s.inertia.1.0[l]) = (b[4], b[5]);
                (s.v.0, s.v.1, s.w.0, s.w.1) = {
                    let (mut v0, mut v1, mut w0, mut w1) = (s.v.0, s.v.1, s.w.0, s.w.1);
                    v0.set_lane(l, w[0]);
                    v1.set_lane(l, w[1]);
                    w0.set_lane(l, w[2]);
                    w1.set_lane(l, w[3]);
                    (v0, v1, w0, w1)
                };
                let c = Contact::between_spheres(
                    d,
                    dist,
                    (b[0], b[1]),
                    (b[2], b[3]),
                    (b[4], b[5]),
                    (w[0], w[1]),
                    (w[2], w[3]),
                    dt,
                );
                scalar.push(c);
                rows.push(random_history(&mut rng, stride));
            }
            let lanes = ContactLanes::between_spheres(&s, dt, count);
            forces += same_as_scalar(name, m, &lanes, &scalar[..count], &rows);
        }
        assert!(
            forces > 1000,
            "{name}: only {forces} contacts carried force"
        );
    }
}

/// A random touching contact of a sphere of 0.5-1.5 mm and a wall, pressed in by up to 5 %
/// of its radius, moving and spinning against a wall that moves too.
fn random_wall_contact(rng: &mut ChaCha8Rng, dt: f64) -> Contact {
    let r: f64 = rng.random_range(0.5e-3..1.5e-3);
    let overlap = rng.random_range(1e-9..0.05) * r;
    let mut vec3 = |s: f64| {
        DVec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let x = vec3(0.1);
    let towards_wall = vec3(1.0).normalize();
    let m = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) * RHO;
    let (v, w, wall_velocity) = (vec3(0.5), vec3(200.0), vec3(0.05));
    Contact::with_wall(
        x,
        x + towards_wall * (r - overlap),
        r,
        m,
        0.4 * m * r * r,
        v,
        w,
        wall_velocity,
        dt,
    )
    .expect("the centre is off the wall")
}

#[test]
fn every_contact_law_on_a_wall_in_lanes_gives_its_scalar_bits() {
    // A wall is a body of infinite radius, mass and inertia: the lane forms must treat the
    // infinities as the scalar forms do (sjkr's flat-wall area, rolling torques on i only).
    let dt = 5e-6;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for (name, m) in &models() {
        let stride = m.history_stride();
        let mut forces = 0;
        for round in 0..400 {
            let count = 1 + round % LANES;
            let scalar: Vec<Contact> = (0..count)
                .map(|_| random_wall_contact(&mut rng, dt))
                .collect();
            let rows: Vec<Vec<f64>> = (0..LANES)
                .map(|_| random_history(&mut rng, stride))
                .collect();
            let lanes = ContactLanes::gather(&scalar);
            forces += same_as_scalar(name, m, &lanes, &scalar, &rows);
        }
        assert!(
            forces > 1000,
            "{name}: only {forces} wall contacts carried force"
        );
    }
}
