//! Bad input is refused before the run starts, naming the key and the allowed range; a run
//! that blows up stops with the step and the likely cause.

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::contact::{ContactModel, ModelSpec, PairSpec};
use tilth_kernel::material::Material;
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::{Setup, Simulation};

fn build(spec: &ModelSpec, kv: &[(&str, f64)]) -> String {
    let pair = PairSpec {
        materials: ("soil".into(), "soil".into()),
        params: params(kv),
    };
    match ContactModel::build(&[soil()], spec, &[pair]) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn restitution_outside_zero_one_is_refused() {
    let s = spec("hertz", Some("restitution"), None, None);
    for e in [0.0, 1.2, -0.5] {
        let msg = build(&s, &[("restitution", e)]);
        assert!(
            msg.contains("pairs[soil-soil].restitution") && msg.contains("(0, 1]"),
            "{msg}"
        );
    }
    assert_eq!(build(&s, &[("restitution", 1.0)]), "");
}

#[test]
fn negative_friction_is_refused() {
    let msg = build(
        &spec("hertz", None, Some("mindlin"), None),
        &[("friction", -0.1)],
    );
    assert!(
        msg.contains("pairs[soil-soil].friction") && msg.contains("[0, inf)"),
        "{msg}"
    );
}

#[test]
fn unknown_law_and_unknown_key_are_refused() {
    let msg = build(&spec("hertzz", None, None, None), &[]);
    assert!(
        msg.contains("unknown normal law 'hertzz'") && msg.contains("hertz, jkr"),
        "{msg}"
    );
    let msg = build(
        &spec("hertz", Some("restitution"), None, None),
        &[("restitution", 0.5), ("friction", 0.5)],
    );
    assert!(
        msg.contains("unknown key 'friction'") && msg.contains("restitution"),
        "{msg}"
    );
    let msg = build(&spec("hertz", Some("restitution"), None, None), &[]);
    assert!(msg.contains("missing key 'restitution'"), "{msg}");
}

#[test]
fn cohesion_with_a_friction_law_that_cannot_carry_it_is_refused_in_one_sentence() {
    let msg = build(
        &spec("jkr", None, Some("coulomb_viscous"), None),
        &[("surface_energy", 0.3), ("friction", 0.5)],
    );
    assert!(
        msg.contains("'coulomb_viscous' cannot be combined with the cohesive law 'jkr'")
            && msg.contains("mindlin"),
        "{msg}"
    );
    assert!(
        !msg.trim_end_matches('.').contains(". "),
        "one sentence: {msg}"
    );
}

#[test]
fn bad_materials_are_refused() {
    for (e, nu, rho, key) in [
        (0.0, 0.2, 1380.0, "youngs_modulus"),
        (-1.0, 0.2, 1380.0, "youngs_modulus"),
        (1e7, 0.6, 1380.0, "poisson_ratio"),
        (1e7, 0.2, 0.0, "density"),
    ] {
        let msg = Material::new("soil", e, nu, rho).unwrap_err().to_string();
        assert!(
            msg.contains(&format!("materials.soil.{key}")) && msg.contains("allowed"),
            "{msg}"
        );
    }
}

fn setup(p: Particles, dt: f64) -> Setup {
    Setup {
        model: model(
            &spec("hertz", Some("restitution"), None, None),
            &[("restitution", 0.5)],
        ),
        particles: p,
        walls: vec![],
        factories: vec![],
        dt,
        gravity: DVec3::ZERO,
        skin: 1e-4,
        threads: 1,
        domain: domain(0.1),
    }
}

#[test]
fn zero_or_negative_radius_is_refused() {
    for r in [0.0, -1e-3] {
        let mut p = Particles::default();
        p.push(DVec3::ZERO, DVec3::ZERO, r, RHO, 0);
        let msg = Simulation::new(setup(p, 1e-6)).err().unwrap().to_string();
        assert!(
            msg.contains("particles[0].radius") && msg.contains("(0, inf)"),
            "{msg}"
        );
    }
}

#[test]
fn overlapping_initial_particles_are_refused() {
    let mut p = Particles::default();
    p.push(DVec3::ZERO, DVec3::ZERO, R, RHO, 0);
    p.push(DVec3::new(1.5 * R, 0.0, 0.0), DVec3::ZERO, R, RHO, 0);
    let msg = Simulation::new(setup(p, 1e-6)).err().unwrap().to_string();
    assert!(
        msg.contains("particles 0 and 1 overlap by 5.000e-4 m"),
        "{msg}"
    );
}

#[test]
fn time_step_above_forty_percent_of_rayleigh_warns() {
    let s = Simulation::new(setup(head_on_pair(0.1), 3e-5)).unwrap();
    assert!((s.rayleigh_time - 5.4e-5).abs() < 0.1e-5);
    assert!(
        s.warnings.iter().any(|w| w.contains("Rayleigh")),
        "{:?}",
        s.warnings
    );
    let s = Simulation::new(setup(head_on_pair(0.1), 1e-5)).unwrap();
    assert!(s.warnings.is_empty());
}

#[test]
fn blow_up_from_a_huge_time_step_names_the_step_and_the_cause() {
    // dt = 3 T_R: the first contact overshoots and the pair flies apart far too fast.
    let mut s = Simulation::new(setup(head_on_pair(2.0), 1.6e-4)).unwrap();
    let err = s.run(10_000).unwrap_err().to_string();
    assert!(
        err.contains("run stopped at step") && err.contains("Rayleigh time"),
        "{err}"
    );
}

#[test]
fn escaping_particle_names_the_open_geometry() {
    let mut p = Particles::default();
    p.push(DVec3::ZERO, DVec3::ZERO, R, RHO, 0);
    let mut st = setup(p, 1e-5);
    st.gravity = DVec3::new(0.0, 0.0, -9.81);
    let mut s = Simulation::new(st).unwrap();
    let err = s.run(100_000).unwrap_err().to_string();
    assert!(
        err.contains("left the domain") && err.contains("geometry is open"),
        "{err}"
    );
}

#[test]
fn an_escape_is_caught_at_the_step_the_particle_crosses_the_boundary() {
    // Free fall from rest: velocity Verlet is exact under a constant force, so after n steps
    // z_n = -g dt^2 n^2 / 2, and the particle leaves through the floor of the domain at the
    // first n with g dt^2 n^2 / 2 > |z_min|.
    let (g, dt) = (9.81, 1e-5);
    let z_min = domain(0.1).min.z;
    let n = ((2.0 * -z_min / (g * dt * dt)).sqrt().floor() as u64) + 1;
    let mut p = Particles::default();
    p.push(DVec3::ZERO, DVec3::ZERO, R, RHO, 0);
    let mut st = setup(p, dt);
    st.gravity = DVec3::new(0.0, 0.0, -g);
    let mut s = Simulation::new(st).unwrap();
    s.run(n - 1).unwrap();
    let err = s.run(1).unwrap_err().to_string();
    assert!(
        err.contains(&format!("run stopped at step {n} ")) && err.contains("left the domain"),
        "{err}"
    );

    // A position moved out of the domain between steps is caught at the next step.
    let mut p = Particles::default();
    p.push(DVec3::ZERO, DVec3::ZERO, R, RHO, 0);
    let mut s = Simulation::new(setup(p, dt)).unwrap();
    s.run(10).unwrap();
    s.particles.position[0] = DVec3::new(0.0, 0.2, 0.0);
    let err = s.run(1).unwrap_err().to_string();
    assert!(
        err.contains("run stopped at step 11 ") && err.contains("left the domain"),
        "{err}"
    );
}
