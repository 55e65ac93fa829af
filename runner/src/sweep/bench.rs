//! Speed benchmarks: `tilth bench settling-bed` (tools/bench/settling-bed/README.md), the
//! kernel against LIGGGHTS and LAMMPS on the scene of `lab::settling_bed`.

use crate::lab::settling_bed::{self, SettlingBed, TimedRun};
use crate::text::summary;
use anyhow::Result;
use std::io::Write;
use tilth_kernel::sim::PairPath;

/// One settling-bed benchmark.
pub struct SettlingBedRun {
    /// The scene: particles, threads, seed, cohesion law.
    pub bed: SettlingBed,
    /// Time steps to run.
    pub steps: u64,
    /// How the pair phase evaluates touching contacts (the same bits on every path).
    pub pair_path: PairPath,
    pub show_progress: bool,
    /// After the run, time the pair phase alone this many times on the final state.
    pub pair_phase_reps: usize,
}

/// Runs the settling bed and reports its speed, the time per phase, the final state's hash
/// and the memory per particle, as text.
pub fn settling_bed(req: &SettlingBedRun) -> Result<String> {
    let run = settling_bed::run_timed(&req.bed, req.steps, req.pair_path, req.show_progress)?;
    summary(|out| write_settling_bed(req, run, out))
}

fn write_settling_bed(req: &SettlingBedRun, run: TimedRun, out: &mut dyn Write) -> Result<()> {
    let (mut sim, setup, secs) = (run.sim, run.setup_seconds, run.stepping_seconds);
    let n = sim.particles.len();
    let n_div = n.max(1) as f64;
    writeln!(out, "particles: {n}")?;
    writeln!(out, "steps: {}", sim.step)?;
    writeln!(out, "threads: {}", req.bed.threads)?;
    writeln!(out, "setup seconds: {setup:.3}")?;
    writeln!(out, "wall seconds: {secs:.3}")?;
    // As LIGGGHTS's "Pair / Neigh / Other time (%)" after its loop.
    writeln!(out, "time per part of the stepping loop:")?;
    let parts = super::report::time_breakdown(&run.times, secs);
    super::report::write_time_breakdown(out, &parts, "  ")?;
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
    if req.pair_phase_reps > 0 {
        let t = sim.time_pair_phase(req.pair_phase_reps) / req.pair_phase_reps as f64;
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
