//! The settling bed: the kernel's speed benchmark scene (`tilth bench settling-bed`,
//! tools/bench/settling-bed/README.md), built in code, and its timed run.
//!
//! A box of four planes (x, y in [-0.03, 0.03] m) on a floor z = 0; N spheres of 2 mm, density
//! 1380, placed at random without overlap in x, y in [-0.028, 0.028], z in [0.002, 0.118] with
//! velocity (0, 0, -0.5) m/s; Hertz-Mindlin with cohesion, restitution 0.45, friction 0.6,
//! constant-torque rolling friction 0.15; dt 5e-6 s, skin 0.4 mm. Only the stepping loop is
//! timed; the last line of stdout is `particle-steps/s: <value>`.
//!
//! The cohesion is chosen with `--cohesion`: `jkr` (the default) makes the normal law full JKR
//! with surface energy 0.356 J/m^2 (as the LAMMPS deck, `bed.lammps`); `sjkr` keeps the normal
//! law Hertz and adds LIGGGHTS's simplified JKR as an extra law with cohesion energy density
//! 0.356 J/m^3 (as the LIGGGHTS deck, `bed.liggghts`). As in the decks, cohesion acts between
//! particles only, and the walls take the particles' elastic constants with their own contact
//! coefficients: with `sjkr` the floor has rolling friction and the side walls none (LIGGGHTS
//! deck); with `jkr` no wall has rolling friction (LAMMPS deck, whose rolling model between
//! particles is a spring-dashpot-slider where tilth keeps CDT).

use crate::progress::Progress;
use anyhow::{Context, Result, bail};
use std::time::{Duration, Instant};
use tilth_kernel::DVec3;
use tilth_kernel::contact::{ContactModel, ModelSpec, PairSpec};
use tilth_kernel::factory::{Basis, Factory, FactorySpec, Region};
use tilth_kernel::material::Material;
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::{Aabb, PairPath, Setup, Simulation};
use tilth_kernel::timing::PhaseTimes;
use tilth_kernel::wall::plane::Plane;
use tilth_kernel::wall::{Motion, Wall};

/// The settling bed's cohesion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cohesion {
    /// Full JKR normal law, surface energy 0.356 J/m^2 (as the LAMMPS deck).
    Jkr,
    /// Hertz plus the extra law `sjkr`, cohesion energy density 0.356 J/m^3 (as the LIGGGHTS
    /// deck).
    Sjkr,
}

/// One settling bed: its size, threads, placement seed and cohesion.
#[derive(Debug, Clone)]
pub struct SettlingBed {
    pub particles: usize,
    pub threads: u64,
    pub seed: u64,
    pub cohesion: Cohesion,
}

/// A stepped settling bed and where its time went.
pub struct TimedRun {
    /// The bed after the last step.
    pub sim: Simulation,
    /// Building the scene and placing the particles, s.
    pub setup_seconds: f64,
    /// The stepping loop alone, s.
    pub stepping_seconds: f64,
    /// The kernel's per-phase times of the stepping loop.
    pub times: PhaseTimes,
}

/// Builds the bed and steps it `steps` times on `pair_path`, timing only the stepping.
pub fn run_timed(
    bed: &SettlingBed,
    steps: u64,
    pair_path: PairPath,
    show_progress: bool,
) -> Result<TimedRun> {
    let t0 = Instant::now();
    let mut sim = Simulation::new(setup(bed)?)?;
    sim.set_pair_path(pair_path);
    let setup_seconds = t0.elapsed().as_secs_f64();
    let n = sim.particles.len();
    eprintln!("settling-bed: placed {n} particles in {setup_seconds:.2} s; stepping {steps} steps");
    for w in &sim.warnings {
        eprintln!("warning: {w}");
    }
    let mut progress = Progress::new(steps, show_progress);
    let mut stepping = Duration::ZERO;
    let times_before = sim.times;
    let chunk = 100;
    while sim.step < steps {
        let k = chunk.min(steps - sim.step);
        let t = Instant::now();
        sim.run(k).context("settling-bed")?;
        stepping += t.elapsed();
        progress.update(&sim);
    }
    progress.finish();
    Ok(TimedRun {
        times: sim.times - times_before,
        sim,
        setup_seconds,
        stepping_seconds: stepping.as_secs_f64(),
    })
}

/// The benchmark scene.
pub fn setup(args: &SettlingBed) -> Result<Setup> {
    // The decks give the walls the particles' elastic material; "floor" and "side" only
    // carry their own contact coefficients.
    let soil = Material::new("soil", 13.5e6, 0.2, 1380.0)?;
    let floor = Material::new("floor", 13.5e6, 0.2, 1380.0)?;
    let side = Material::new("side", 13.5e6, 0.2, 1380.0)?;
    // Cohesion acts between particles only in both decks; rolling friction acts between
    // particles and (LIGGGHTS) on the floor, nowhere on the walls in the LAMMPS deck.
    let (normal, extra, cohesion, floor_rolling) = match args.cohesion {
        Cohesion::Jkr => ("jkr", vec![], "surface_energy", 0.0),
        Cohesion::Sjkr => (
            "hertz",
            vec!["sjkr".to_string()],
            "cohesion_energy_density",
            0.15,
        ),
    };
    let spec = ModelSpec {
        normal: normal.into(),
        damping: Some("restitution".into()),
        tangential: Some("mindlin".into()),
        rolling: Some("cdt".into()),
        extra,
    };
    let pair = |other: &str, rolling: f64, cohesion_value: f64| PairSpec {
        materials: ("soil".into(), other.into()),
        params: [
            ("restitution", 0.45),
            ("friction", 0.6),
            ("rolling_friction", rolling),
            (cohesion, cohesion_value),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
    };
    let model = ContactModel::build(
        &[soil.clone(), floor, side],
        &spec,
        &[
            pair("soil", 0.15, 0.356),
            pair("floor", floor_rolling, 0.0),
            pair("side", 0.0, 0.0),
        ],
    )?;
    let plane = |name: &str, material: u16, point: [f64; 3], normal: [f64; 3]| {
        let shape = Plane::new(DVec3::from_array(point), DVec3::from_array(normal))
            .expect("non-zero normal");
        Wall::new(name, Box::new(shape), material, Motion::Fixed)
    };
    // The deck's box holds 20,000 particles; larger runs widen it (same height, same
    // settling time) so the density per floor area stays the deck's.
    let s = (args.particles as f64 / 20_000.0).max(1.0).sqrt();
    let half = 0.03 * s;
    let walls = vec![
        plane("floor", 1, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        plane("x-", 2, [-half, 0.0, 0.0], [1.0, 0.0, 0.0]),
        plane("x+", 2, [half, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        plane("y-", 2, [0.0, -half, 0.0], [0.0, 1.0, 0.0]),
        plane("y+", 2, [0.0, half, 0.0], [0.0, -1.0, 0.0]),
    ];
    let mut factory = Factory::new(FactorySpec {
        region: Region::Box {
            min: DVec3::new(-(half - 0.002), -(half - 0.002), 0.002),
            max: DVec3::new(half - 0.002, half - 0.002, 0.118),
        },
        sizes: vec![(1e-3, 1.0)],
        basis: Basis::Number,
        material: 0,
        density: soil.density,
        rate: f64::INFINITY,
        count: args.particles,
        velocity: DVec3::new(0.0, 0.0, -0.5),
        start_time: 0.0,
        seed: args.seed,
    })?;
    // All at once, before the simulation is built (the kernel hangs when it starts empty).
    // One `insert` call gives up on the first particle that finds no room in 200 tries, so
    // call it until the bed is complete or no particle fits any more.
    let mut particles = Particles::default();
    while !factory.done() && factory.insert(0.0, &mut particles) > 0 {}
    if !factory.done() {
        bail!(
            "settling-bed: only {} of {} particles fit in the insertion region",
            particles.len(),
            args.particles
        );
    }
    Ok(Setup {
        model,
        particles,
        walls,
        factories: vec![factory],
        dt: 5e-6,
        gravity: DVec3::new(0.0, 0.0, -9.81),
        skin: 4e-4,
        threads: args.threads as usize,
        domain: Aabb {
            min: DVec3::new(-(half + 0.005), -(half + 0.005), -0.005),
            max: DVec3::new(half + 0.005, half + 0.005, 0.125),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(cohesion: Cohesion) -> SettlingBed {
        SettlingBed {
            particles: 300,
            threads: 1,
            seed: 1,
            cohesion,
        }
    }

    /// Both decks' scenes build, give every wall the coefficients of its own material pair,
    /// and run without a failure.
    #[test]
    fn both_cohesions_build_and_run() {
        for c in [Cohesion::Jkr, Cohesion::Sjkr] {
            let mut sim = Simulation::new(setup(&args(c)).unwrap()).unwrap();
            assert_eq!(sim.particles.len(), 300);
            let m = &sim.model;
            let (soil, floor, side) = (
                m.material_index("soil").unwrap(),
                m.material_index("floor").unwrap(),
                m.material_index("side").unwrap(),
            );
            assert!(m.has_pair(soil, floor) && m.has_pair(soil, side));
            assert_eq!(sim.walls[0].material as usize, floor);
            assert!(sim.walls[1..].iter().all(|w| w.material as usize == side));
            sim.run(2_000).unwrap();
        }
    }
}
