//! `tilth bench settling-bed`: the kernel's speed benchmark
//! (tools/bench/settling-bed/README.md); the scene is `lab::settling_bed`, the run and its
//! report `sweep::bench`. `tilth bench lab`: the instruments' runs timed (`sweep::bench_lab`).

use crate::lab::settling_bed::{self, SettlingBed};
use crate::sweep::bench;
use crate::sweep::bench_lab::{self, LabBench, Scale};
use anyhow::Result;
use clap::{Args, Subcommand, ValueEnum};
use std::io::Write;
use std::path::PathBuf;
use tilth_kernel::sim::PairPath;

#[derive(Debug, Subcommand)]
pub enum Bench {
    /// Spheres falling into a box and settling into a bed (compare with LIGGGHTS and LAMMPS).
    SettlingBed(SettlingBedArgs),
    /// Each instrument's run (funnel, direct shear, UCS) at the coarse preset and at the
    /// study's scale, on 1 and 2 threads: wall time per run and runs per hour.
    Lab(LabArgs),
}

#[derive(Debug, Args)]
pub struct LabArgs {
    /// Experiment files to time (default: the study's three instruments).
    #[arg(default_values_t = [
        "sweeps/experiments/repose.toml".to_string(),
        "sweeps/experiments/direct_shear.toml".to_string(),
        "sweeps/experiments/ucs.toml".to_string(),
    ])]
    pub files: Vec<String>,
    /// Sizes to run: the coarse preset, the file as written (the study's scale), or both.
    #[arg(long, value_enum, default_value_t = ScaleArg::Coarse)]
    pub scale: ScaleArg,
    /// Worker threads per run, each measured in turn.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2],
          value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: Vec<u64>,
    /// Runs of each; the table shows the median.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub rounds: u64,
    /// Cores a sweep fills with such runs (the runs-per-hour column).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(1..))]
    pub cores: u64,
    /// Scratch directory for the runs' files (each removed after its run).
    #[arg(long, default_value = "runs/bench-lab")]
    pub scratch: PathBuf,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// `--scale`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScaleArg {
    /// The coarse preset (minutes in all).
    Coarse,
    /// The files as written: the study's scale (the funnel alone takes minutes a run).
    Study,
    /// Both.
    Both,
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
        Bench::Lab(args) => bench_lab::lab(&LabBench {
            files: args.files.iter().map(PathBuf::from).collect(),
            scales: match args.scale {
                ScaleArg::Coarse => vec![Scale::Coarse],
                ScaleArg::Study => vec![Scale::Study],
                ScaleArg::Both => vec![Scale::Coarse, Scale::Study],
            },
            threads: args.threads.clone(),
            rounds: args.rounds as usize,
            cores: args.cores,
            scratch: args.scratch.clone(),
            show_progress: !args.quiet,
        })?,
    };
    out.write_all(text.as_bytes())?;
    Ok(())
}
