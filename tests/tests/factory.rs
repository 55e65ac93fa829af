//! Particle factory: rate, no overlaps, size distribution by number and by mass, one seed.

mod common;
use common::*;
use glam::DVec3;
use tilth_kernel::factory::{Basis, Factory, FactorySpec, Region};
use tilth_kernel::particles::Particles;

fn spec(basis: Basis, rate: f64, count: usize, seed: u64) -> FactorySpec {
    FactorySpec {
        region: Region::Box {
            min: DVec3::splat(-0.05),
            max: DVec3::splat(0.05),
        },
        sizes: vec![(1e-3, 0.5), (0.5e-3, 0.5)],
        basis,
        material: 0,
        density: RHO,
        rate,
        count,
        velocity: DVec3::new(0.0, 0.0, -0.5),
        start_time: 0.0,
        seed,
    }
}

#[test]
fn rate_and_no_overlaps() {
    let mut f = Factory::new(spec(Basis::Number, 20_000.0, 3_000, 1)).unwrap();
    let mut p = Particles::default();
    assert_eq!(f.insert(0.01, &mut p), 200, "20,000/s for 10 ms");
    assert_eq!(f.insert(0.0125, &mut p), 50);
    assert_eq!(f.insert(1.0, &mut p), 2_750, "capped at count");
    assert_eq!(f.insert(2.0, &mut p), 0);
    for i in 0..p.len() {
        assert!(
            p.position[i].abs().max_element() <= 0.05 - p.radius[i],
            "outside region"
        );
        for j in i + 1..p.len() {
            assert!(
                (p.position[i] - p.position[j]).length() >= p.radius[i] + p.radius[j],
                "{i} and {j} overlap"
            );
        }
    }
}

/// Counts of the large class among n draws must be binomial around n q; allow 5 sigma.
fn check_fraction(basis: Basis, q: f64) {
    let n = 4_000;
    let mut f = Factory::new(spec(basis, f64::INFINITY, n, 3)).unwrap();
    let mut p = Particles::default();
    f.insert(0.0, &mut p);
    let big = p.radius.iter().filter(|&&r| r == 1e-3).count() as f64;
    let sigma = (n as f64 * q * (1.0 - q)).sqrt();
    assert!(
        (big - n as f64 * q).abs() < 5.0 * sigma,
        "{basis:?}: {big} large of {n}, expected {}",
        n as f64 * q
    );
}

#[test]
fn size_distribution_by_number_and_by_mass() {
    check_fraction(Basis::Number, 0.5);
    // Equal mass fractions: number weights 1/r^3, so large : small = 1 : 8.
    check_fraction(Basis::Mass, 1.0 / 9.0);
}

#[test]
fn one_seed_fixes_everything() {
    let run = |seed| {
        let mut f = Factory::new(spec(Basis::Number, 1e5, 500, seed)).unwrap();
        let mut p = Particles::default();
        f.insert(1.0, &mut p);
        p.position
    };
    assert_eq!(run(9), run(9));
    assert_ne!(run(9), run(10));
}

#[test]
fn bad_factory_input_is_refused() {
    let mut s = spec(Basis::Number, 1e3, 10, 1);
    s.sizes = vec![(-1e-3, 1.0)];
    let e = Factory::new(s).unwrap_err().to_string();
    assert!(
        e.contains("factory.sizes[0].radius") && e.contains("(0, inf)"),
        "{e}"
    );
    let mut s = spec(Basis::Number, 0.0, 10, 1);
    s.rate = 0.0;
    assert!(
        Factory::new(s)
            .unwrap_err()
            .to_string()
            .contains("factory.rate")
    );
}

/// The half kicks use each particle's own mass and inertia after the factory has added
/// particles and after the simulation has reordered them (every `SORT_EVERY` steps): in free
/// fall every particle, large or small (masses 1 : 8), gains g dt of speed per step.
#[test]
fn created_and_reordered_particles_fall_with_g() {
    let dt = 1e-5;
    let mut s = tilth_kernel::sim::Simulation::new(tilth_kernel::sim::Setup {
        model: model(&common::spec("hertz", None, None, None), &[]),
        particles: Particles::default(),
        walls: vec![],
        factories: vec![Factory::new(spec(Basis::Number, f64::INFINITY, 400, 5)).unwrap()],
        dt,
        gravity: DVec3::new(0.0, 0.0, -9.81),
        skin: 0.2 * R,
        threads: 1,
        domain: domain(1.0),
    })
    .unwrap();
    let by_id = |s: &tilth_kernel::sim::Simulation| {
        let mut v = vec![f64::NAN; s.particles.len()];
        for (k, &id) in s.particles.id.iter().enumerate() {
            v[id as usize] = s.particles.velocity[k].z;
        }
        v
    };
    // Past the first insertion, then across the first reorder.
    let steps = tilth_kernel::sim::SORT_EVERY - 10;
    s.run(steps).unwrap();
    assert_eq!(s.particles.len(), 400, "the factory placed its particles");
    let before = by_id(&s);
    s.run(20).unwrap();
    let after = by_id(&s);
    let reordered = s
        .particles
        .id
        .iter()
        .enumerate()
        .any(|(k, &id)| id as usize != k);
    assert!(reordered, "the reorder changed the particles' order");
    let big = s.particles.radius.iter().filter(|&&r| r == 1e-3).count();
    assert!(big > 100 && big < 300, "both sizes present: {big} large");
    for (id, (b, a)) in before.iter().zip(&after).enumerate() {
        let gain = b - a;
        assert!(
            (gain - 9.81 * 20.0 * dt).abs() < 1e-12,
            "particle {id} gained {gain} m/s in 20 steps, not {}",
            9.81 * 20.0 * dt
        );
    }
}
