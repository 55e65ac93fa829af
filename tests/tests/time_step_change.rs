//! `Simulation::set_dt`: a time step changed between steps (a specimen prepared at the
//! contacts' step, then bonded at a shorter one).

mod common;

use common::*;
use glam::DVec3;
use tilth_kernel::particles::Particles;

fn falling(threads: usize, dt: f64) -> tilth_kernel::sim::Simulation {
    let mut p = Particles::default();
    p.push(
        DVec3::new(0.0, 0.0, 0.5),
        DVec3::new(0.1, 0.0, 0.2),
        R,
        RHO,
        0,
    );
    sim(
        model(&spec("hertz", None, None, None), &[]),
        p,
        vec![],
        dt,
        DVec3::new(0.0, 0.0, -9.81),
        threads,
    )
}

/// Velocity Verlet is exact for a constant force, whatever the steps: a free flight with a
/// step change midway lands where z0 + v0 t - g t^2 / 2 says, and the clock reads the sum
/// of the steps taken.
#[test]
fn a_free_flight_through_a_step_change_follows_the_parabola() {
    let (dt1, dt2) = (1e-4, 2.5e-5);
    let mut s = falling(1, dt1);
    s.run(1000).unwrap();
    s.set_dt(dt2).unwrap();
    s.run(2000).unwrap();
    let t = 1000.0 * dt1 + 2000.0 * dt2;
    assert!((s.time - t).abs() < 1e-12, "time {} against {t}", s.time);
    assert_eq!(s.step, 3000);
    let x = s.particles.position[0];
    let v = s.particles.velocity[0];
    let z = 0.5 + 0.2 * t - 0.5 * 9.81 * t * t;
    assert!((x.z - z).abs() < 1e-12, "z {} against {z}", x.z);
    assert!((x.x - 0.1 * t).abs() < 1e-12);
    assert!((v.z - (0.2 - 9.81 * t)).abs() < 1e-12);
}

/// Setting the step it already has changes nothing, to the bit; the clock of a run
/// without a change is the step count times the step, as before.
#[test]
fn the_same_step_set_again_changes_no_bit() {
    let mut a = falling(1, 1e-4);
    let mut b = falling(1, 1e-4);
    a.run(500).unwrap();
    b.run(250).unwrap();
    b.set_dt(1e-4).unwrap();
    b.run(250).unwrap();
    assert_eq!(a.state_hash(), b.state_hash());
    assert_eq!(a.time.to_bits(), b.time.to_bits());
    assert_eq!(a.time.to_bits(), (500.0 * 1e-4_f64).to_bits());
}

/// A step that is not a positive number is refused with the key and the range, and the
/// simulation keeps its step.
#[test]
fn a_bad_step_is_refused() {
    let mut s = falling(1, 1e-4);
    for bad in [0.0, -1e-5, f64::NAN, f64::INFINITY] {
        let e = s.set_dt(bad).unwrap_err().to_string();
        assert!(e.contains("dt") && e.contains("(0, inf)"), "{e}");
        assert_eq!(s.dt, 1e-4);
    }
}

/// A step above 40 % of the Rayleigh time is warned about when set, as at the start.
#[test]
fn a_step_too_long_for_the_contacts_is_warned_about() {
    let mut s = falling(1, 1e-7);
    assert!(s.warnings.is_empty());
    let long = 0.5 * s.rayleigh_time;
    s.set_dt(long).unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("Rayleigh"), "{}", s.warnings[0]);
}

/// A pile settling through a step change gives the same bits on 1 and 2 threads.
#[test]
fn a_step_change_keeps_one_and_two_threads_identical() {
    let run = |threads: usize| {
        let mut p = Particles::default();
        let mut k = 0;
        for ix in 0..6 {
            for iy in 0..6 {
                for iz in 0..6 {
                    let jitter = 1e-5 * ((k * 7919) % 13) as f64;
                    p.push(
                        DVec3::new(
                            2.2 * R * ix as f64 + jitter,
                            2.2 * R * iy as f64,
                            R + 2.2 * R * iz as f64,
                        ),
                        DVec3::ZERO,
                        R,
                        RHO,
                        0,
                    );
                    k += 1;
                }
            }
        }
        let m = model(
            &spec("hertz", Some("restitution"), Some("mindlin"), None),
            &[("restitution", 0.5), ("friction", 0.5)],
        );
        let mut s = sim(
            m,
            p,
            vec![floor()],
            2e-6,
            DVec3::new(0.0, 0.0, -9.81),
            threads,
        );
        s.run(3000).unwrap();
        s.set_dt(5e-7).unwrap();
        s.run(3000).unwrap();
        (s.state_hash(), s.time.to_bits())
    };
    assert_eq!(run(1), run(2));
}
