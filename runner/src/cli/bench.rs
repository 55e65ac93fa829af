//! `tilth bench settling-bed`: the kernel's speed benchmark
//! (tools/bench/settling-bed/README.md); the scene is `lab::settling_bed`.

use crate::lab::settling_bed::{self, SettlingBed};
use anyhow::Result;
use clap::{Args, Subcommand, ValueEnum};
use std::io::Write;
use tilth_kernel::sim::PairPath;

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

/// `--cohesion`: the settling bed's [`settling_bed::Cohesion`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Cohesion {
    /// Full JKR normal law, surface energy 0.356 J/m^2 (as the LAMMPS deck).
    Jkr,
    /// Hertz plus the extra law `sjkr`, cohesion energy density 0.356 J/m^3 (as the LIGGGHTS
    /// deck).
    Sjkr,
}

impl From<Cohesion> for settling_bed::Cohesion {
    fn from(c: Cohesion) -> settling_bed::Cohesion {
        match c {
            Cohesion::Jkr => settling_bed::Cohesion::Jkr,
            Cohesion::Sjkr => settling_bed::Cohesion::Sjkr,
        }
    }
}

pub fn bench(which: &Bench, out: &mut dyn Write) -> Result<()> {
    match which {
        Bench::SettlingBed(args) => settling_bed(args, out),
    }
}

/// The benchmark scene.
fn settling_bed(args: &SettlingBedArgs, out: &mut dyn Write) -> Result<()> {
    let bed = SettlingBed {
        particles: args.particles,
        threads: args.threads,
        seed: args.seed,
        cohesion: args.cohesion.into(),
    };
    let run = settling_bed::run_timed(&bed, args.steps, args.pair_path.into(), !args.quiet)?;
    let (mut sim, setup, secs) = (run.sim, run.setup_seconds, run.stepping_seconds);
    let n = sim.particles.len();
    let n_div = n.max(1) as f64;
    writeln!(out, "particles: {n}")?;
    writeln!(out, "steps: {}", sim.step)?;
    writeln!(out, "threads: {}", args.threads)?;
    writeln!(out, "setup seconds: {setup:.3}")?;
    writeln!(out, "wall seconds: {secs:.3}")?;
    // As LIGGGHTS's "Pair / Neigh / Other time (%)" after its loop.
    writeln!(out, "time per part of the stepping loop:")?;
    let parts = crate::sweep::report::time_breakdown(&run.times, secs);
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
