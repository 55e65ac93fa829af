//! `tilth bench settling-bed`: the kernel's speed benchmark
//! (tools/bench/settling-bed/README.md), built in code.
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
use clap::{Args, Subcommand, ValueEnum};
use std::io::Write;
use std::time::{Duration, Instant};
use tilth_kernel::DVec3;
use tilth_kernel::contact::{ContactModel, ModelSpec, PairSpec};
use tilth_kernel::factory::{Basis, Factory, FactorySpec, Region};
use tilth_kernel::material::Material;
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::{Aabb, PairPath, Setup, Simulation};
use tilth_kernel::wall::plane::Plane;
use tilth_kernel::wall::{Motion, Wall};

#[derive(Debug, Subcommand)]
pub enum Bench {
    /// Spheres falling into a box and settling into a bed (compare with LIGGGHTS and LAMMPS).
    SettlingBed(SettlingBedArgs),
}

#[derive(Debug, Args)]
pub struct SettlingBedArgs {
    /// Number of particles.
    #[arg(long, default_value_t = 20_000)]
    pub particles: usize,
    /// Number of time steps (5e-6 s each).
    #[arg(long, default_value_t = 20_000)]
    pub steps: u64,
    /// Worker threads.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: u64,
    /// Seed of the random placement.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Cohesion law.
    #[arg(long, value_enum, default_value_t = Cohesion::Jkr)]
    pub cohesion: Cohesion,
    /// After the run, time the pair phase alone this many times on the final state, on the
    /// run's threads (a diagnostic for comparing pair-phase code; BENCHMARKS.md).
    #[arg(long, default_value_t = 0)]
    pub pair_phase_reps: usize,
    /// How the pair phase and the wall contacts evaluate touching contacts (every path
    /// gives the same bits; for timing one against another).
    #[arg(long, value_enum, default_value_t = PairPathArg::Lanes)]
    pub pair_path: PairPathArg,
}

/// `--pair-path`: the kernel's [`PairPath`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PairPathArg {
    /// 8 contacts at a time, on the widest vector instructions the CPU has, through the
    /// model's compiled law set if it has one.
    Lanes,
    /// As `lanes`, through the slots' enums even for a compiled law set.
    Enums,
    /// 8 at a time, on AVX2 at most.
    Avx2,
    /// 8 at a time, on SSE2 (every x86-64 CPU).
    Baseline,
    /// One at a time, through the laws' scalar forms.
    OneByOne,
}

impl From<PairPathArg> for PairPath {
    fn from(p: PairPathArg) -> PairPath {
        match p {
            PairPathArg::Lanes => PairPath::Lanes,
            PairPathArg::Enums => PairPath::LanesEnums,
            PairPathArg::Avx2 => PairPath::LanesAvx2,
            PairPathArg::Baseline => PairPath::LanesBaseline,
            PairPathArg::OneByOne => PairPath::OneByOne,
        }
    }
}

/// The settling bed's cohesion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Cohesion {
    /// Full JKR normal law, surface energy 0.356 J/m^2 (as the LAMMPS deck).
    Jkr,
    /// Hertz plus the extra law `sjkr`, cohesion energy density 0.356 J/m^3 (as the LIGGGHTS
    /// deck).
    Sjkr,
}

pub fn bench(which: &Bench, out: &mut dyn Write) -> Result<()> {
    match which {
        Bench::SettlingBed(args) => settling_bed(args, out),
    }
}

/// The benchmark scene.
pub fn settling_bed_setup(args: &SettlingBedArgs) -> Result<Setup> {
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

fn settling_bed(args: &SettlingBedArgs, out: &mut dyn Write) -> Result<()> {
    let t0 = Instant::now();
    let mut sim = Simulation::new(settling_bed_setup(args)?)?;
    sim.set_pair_path(args.pair_path.into());
    let setup = t0.elapsed().as_secs_f64();
    let n = sim.particles.len();
    eprintln!(
        "settling-bed: placed {n} particles in {setup:.2} s; stepping {} steps",
        args.steps
    );
    for w in &sim.warnings {
        eprintln!("warning: {w}");
    }
    let mut progress = Progress::new(args.steps, !args.quiet);
    let mut stepping = Duration::ZERO;
    let times_before = sim.times;
    let chunk = 100;
    while sim.step < args.steps {
        let k = chunk.min(args.steps - sim.step);
        let t = Instant::now();
        sim.run(k).context("settling-bed")?;
        stepping += t.elapsed();
        progress.update(&sim);
    }
    progress.finish();
    let secs = stepping.as_secs_f64();
    let n = sim.particles.len();
    let n_div = n.max(1) as f64;
    writeln!(out, "particles: {n}")?;
    writeln!(out, "steps: {}", sim.step)?;
    writeln!(out, "threads: {}", args.threads)?;
    writeln!(out, "setup seconds: {setup:.3}")?;
    writeln!(out, "wall seconds: {secs:.3}")?;
    // As LIGGGHTS's "Pair / Neigh / Other time (%)" after its loop.
    writeln!(out, "time per part of the stepping loop:")?;
    let parts = crate::sweep::report::time_breakdown(&(sim.times - times_before), secs);
    crate::sweep::report::write_time_breakdown(out, &parts, "  ")?;
    writeln!(out, "neighbour rebuilds: {}", sim.rebuilds)?;
    let (touching, _) = sim.contact_counts();
    writeln!(
        out,
        "pairs at the end: {} listed, {touching} carrying force",
        sim.pair_count()
    )?;
    writeln!(
        out,
        "final kinetic energy: {:.4e} J",
        sim.particles.kinetic_energy()
    )?;
    // The bits of the final state: equal on 1 and 2 threads, and a check that a change
    // meant to be pure speed changed nothing.
    writeln!(out, "state hash: {:016x}", sim.state_hash())?;
    writeln!(
        out,
        "heap bytes per particle: {:.0}",
        sim.heap_bytes() as f64 / n_div
    )?;
    match peak_rss_kb() {
        Some(kb) => writeln!(
            out,
            "peak RSS per particle: {:.3} kB ({kb} kB total)",
            kb as f64 / n_div
        )?,
        None => writeln!(out, "peak RSS per particle: unknown (no /proc/self/status)")?,
    }
    if args.pair_phase_reps > 0 {
        let t = sim.time_pair_phase(args.pair_phase_reps) / args.pair_phase_reps as f64;
        writeln!(
            out,
            "pair phase alone: {:.3} ms per step, {:.2} ns per listed pair, {:.2} ns per pair carrying force",
            t * 1e3,
            t * 1e9 / sim.pair_count().max(1) as f64,
            t * 1e9 / touching.max(1) as f64
        )?;
    }
    writeln!(
        out,
        "particle-steps/s: {:.3e}",
        n as f64 * sim.step as f64 / secs.max(1e-12)
    )?;
    Ok(())
}

/// VmHWM (peak resident set) in kB, from /proc/self/status.
fn peak_rss_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(cohesion: Cohesion) -> SettlingBedArgs {
        SettlingBedArgs {
            particles: 300,
            steps: 0,
            threads: 1,
            seed: 1,
            quiet: true,
            cohesion,
            pair_phase_reps: 0,
            pair_path: PairPathArg::Lanes,
        }
    }

    /// Both decks' scenes build, give every wall the coefficients of its own material pair,
    /// and run without a failure.
    #[test]
    fn both_cohesions_build_and_run() {
        for c in [Cohesion::Jkr, Cohesion::Sjkr] {
            let mut sim = Simulation::new(settling_bed_setup(&args(c)).unwrap()).unwrap();
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
