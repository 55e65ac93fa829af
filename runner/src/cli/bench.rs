//! `tilth bench settling-bed`: the kernel's speed benchmark
//! (tools/bench/settling-bed/README.md); the scene is `lab::settling_bed`, the run and its
//! report `sweep::bench`.

use crate::lab::settling_bed::{self, SettlingBed};
use crate::sweep::bench;
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
    let text = match which {
        Bench::SettlingBed(args) => bench::settling_bed(&bench::SettlingBedRun {
            bed: SettlingBed {
                particles: args.particles,
                threads: args.threads,
                seed: args.seed,
                cohesion: args.cohesion.into(),
            },
            steps: args.steps,
            pair_path: args.pair_path.into(),
            show_progress: !args.quiet,
            pair_phase_reps: args.pair_phase_reps,
        })?,
    };
    out.write_all(text.as_bytes())?;
    Ok(())
}
