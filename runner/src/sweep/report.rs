//! The summary of a run: one struct, printed as plain text or as JSON.

use crate::config::SceneInfo;
use serde::Serialize;
use std::io::{self, Write};
use tilth_kernel::sim::Simulation;
use tilth_kernel::timing::PhaseTimes;

#[derive(Debug, Serialize)]
pub struct RunReport {
    /// The scene file.
    pub scene: String,
    pub materials: Vec<String>,
    /// Contact laws in slot order.
    pub laws: Vec<String>,
    pub threads: usize,
    /// Time step, s.
    pub dt: f64,
    /// The longest step the touching contacts stood at the last reorder (kernel
    /// `step_check`), s; `null` when nothing touched.
    pub contact_step_limit: Option<f64>,
    pub steps: u64,
    /// s.
    pub simulated_time: f64,
    /// Loading, checking and creating the initial particles, s.
    pub setup_seconds: f64,
    /// The stepping loop, s.
    pub wall_seconds: f64,
    /// Sum over steps of the particle count, divided by `wall_seconds`.
    pub particle_steps_per_second: f64,
    /// Where `wall_seconds` went, part by part of the step, then `other` (recording,
    /// progress, whatever the loop did besides stepping).
    pub time_breakdown: Vec<TimePart>,
    pub particles: usize,
    /// Translational plus rotational, J.
    pub kinetic_energy: f64,
    /// The rotational part, J.
    pub rotational_kinetic_energy: f64,
    /// The fastest particle's speed, m/s.
    pub max_speed: f64,
    /// Sum of m |g| over the particles, N.
    pub total_weight: f64,
    /// Contacts carrying force at the end.
    pub contacts: Contacts,
    pub neighbour_rebuilds: u64,
    pub walls: Vec<WallReport>,
    pub factories: Vec<FactoryReport>,
    pub warnings: Vec<String>,
    /// Samples every `output.every` (empty without it).
    pub samples: Vec<Sample>,
}

/// One part of the stepping loop's time.
#[derive(Debug, Clone, Serialize)]
pub struct TimePart {
    pub part: &'static str,
    /// s.
    pub seconds: f64,
    /// Share of the loop's wall time, %.
    pub percent: f64,
}

/// The kernel's time per part of the step over a loop of `wall_seconds`, then `other`: the
/// rest of the loop (never negative).
pub fn time_breakdown(times: &PhaseTimes, wall_seconds: f64) -> Vec<TimePart> {
    let share = |s: f64| {
        if wall_seconds > 0.0 {
            100.0 * s / wall_seconds
        } else {
            0.0
        }
    };
    let mut parts: Vec<TimePart> = times
        .parts()
        .iter()
        .map(|&(part, d)| TimePart {
            part,
            seconds: d.as_secs_f64(),
            percent: share(d.as_secs_f64()),
        })
        .collect();
    let other = (wall_seconds - times.total().as_secs_f64()).max(0.0);
    parts.push(TimePart {
        part: "other",
        seconds: other,
        percent: share(other),
    });
    parts
}

/// The breakdown as an aligned table, one part a line, each line starting with `indent`.
pub fn write_time_breakdown(
    out: &mut dyn Write,
    parts: &[TimePart],
    indent: &str,
) -> io::Result<()> {
    for p in parts {
        writeln!(
            out,
            "{indent}{:<10} {:>9.3} s {:>5.1} %",
            p.part, p.seconds, p.percent
        )?;
    }
    Ok(())
}

#[derive(Debug, Serialize)]
pub struct Contacts {
    pub particle_particle: usize,
    pub particle_wall: usize,
}

#[derive(Debug, Serialize)]
pub struct WallReport {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    /// Force the particles exert on the wall in the last step, N.
    pub force: [f64; 3],
    /// That force along gravity over the particles' total weight: 1 for a floor carrying a
    /// settled bed alone. `null` without gravity or particles.
    pub weight_fraction: Option<f64>,
}

#[derive(Debug, Serialize)]
pub struct FactoryReport {
    pub created: usize,
    pub count: usize,
    /// Placement attempts rejected for overlap.
    pub rejections: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Sample {
    /// s.
    pub time: f64,
    pub particles: usize,
    pub contacts: usize,
    /// J.
    pub kinetic_energy: f64,
}

impl Sample {
    pub fn of(sim: &Simulation) -> Sample {
        let (pairs, walls) = sim.contact_counts();
        Sample {
            time: sim.time,
            particles: sim.particles.len(),
            contacts: pairs + walls,
            kinetic_energy: sim.particles.kinetic_energy(),
        }
    }
}

/// What a run cost: the threads it ran on, its set-up and wall seconds, the time in each
/// phase and the particle-steps it made.
#[derive(Debug, Clone, Copy)]
pub struct RunCost<'a> {
    pub threads: usize,
    pub setup_seconds: f64,
    pub wall_seconds: f64,
    pub times: &'a PhaseTimes,
    pub particle_steps: u64,
}

impl RunReport {
    pub fn new(
        sim: &Simulation,
        info: &SceneInfo,
        cost: RunCost<'_>,
        samples: Vec<Sample>,
    ) -> RunReport {
        let RunCost {
            threads,
            setup_seconds,
            wall_seconds,
            times,
            particle_steps,
        } = cost;
        let g = sim.gravity.length();
        let total_weight: f64 = sim.particles.mass.iter().sum::<f64>() * g;
        let down = sim.gravity.normalize_or_zero();
        let walls = sim
            .walls
            .iter()
            .zip(&info.walls)
            .map(|(w, (name, kind))| WallReport {
                name: name.clone(),
                kind: kind.to_string(),
                force: w.force.to_array(),
                weight_fraction: (total_weight > 0.0).then(|| w.force.dot(down) / total_weight),
            })
            .collect();
        let factories: Vec<FactoryReport> = sim
            .factories
            .iter()
            .map(|f| FactoryReport {
                created: f.inserted,
                count: f.spec.count,
                rejections: f.rejections,
            })
            .collect();
        let mut warnings = sim.warnings.clone();
        for (k, f) in factories.iter().enumerate() {
            if f.created < f.count {
                warnings.push(format!(
                    "factories[{k}] created {} of {} particles ({} placements rejected): its region is too crowded or the run too short",
                    f.created, f.count, f.rejections
                ));
            }
        }
        let (pp, pw) = sim.contact_counts();
        let p = &sim.particles;
        RunReport {
            scene: info.origin.clone(),
            materials: info.materials.clone(),
            laws: info.laws.clone(),
            threads,
            dt: sim.dt,
            contact_step_limit: sim.packing_frequency.map(|f| f.stable_step()),
            steps: sim.step,
            simulated_time: sim.time,
            setup_seconds,
            wall_seconds,
            particle_steps_per_second: particle_steps as f64 / wall_seconds.max(1e-12),
            time_breakdown: time_breakdown(times, wall_seconds),
            particles: sim.particles.len(),
            kinetic_energy: sim.particles.kinetic_energy(),
            rotational_kinetic_energy: p
                .inertia
                .iter()
                .zip(&p.angular_velocity)
                .map(|(i, w)| 0.5 * i * w.length_squared())
                .sum(),
            max_speed: p.velocity.iter().map(|v| v.length()).fold(0.0, f64::max),
            total_weight,
            contacts: Contacts {
                particle_particle: pp,
                particle_wall: pw,
            },
            neighbour_rebuilds: sim.rebuilds,
            walls,
            factories,
            warnings,
            samples,
        }
    }

    /// The plain-text summary.
    pub fn write_text(&self, out: &mut dyn Write) -> io::Result<()> {
        let walls: Vec<String> = self
            .walls
            .iter()
            .map(|w| format!("{} ({})", w.name, w.kind))
            .collect();
        writeln!(out, "scene               {}", self.scene)?;
        writeln!(
            out,
            "simulated           {} particles; materials {}; laws {}; walls {}",
            self.particles,
            self.materials.join(", "),
            self.laws.join(" + "),
            if walls.is_empty() {
                "none".into()
            } else {
                walls.join(", ")
            }
        )?;
        writeln!(
            out,
            "steps               {} x {:.3e} s = {:.6} s simulated",
            self.steps, self.dt, self.simulated_time
        )?;
        if let Some(limit) = self.contact_step_limit {
            writeln!(
                out,
                "contact step limit  {limit:.3e} s (the touching contacts under their last load; the step is {:.0} % of it)",
                100.0 * self.dt / limit
            )?;
        }
        writeln!(
            out,
            "wall time           {:.3} s stepping ({} thread{}), {:.3} s setup",
            self.wall_seconds,
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            self.setup_seconds
        )?;
        writeln!(
            out,
            "speed               {:.3e} particle-steps/s",
            self.particle_steps_per_second
        )?;
        writeln!(out, "time per part       of the stepping loop:")?;
        write_time_breakdown(out, &self.time_breakdown, "                    ")?;
        writeln!(
            out,
            "kinetic energy      {:.4e} J ({:.4e} J rotational), fastest particle {:.3e} m/s",
            self.kinetic_energy, self.rotational_kinetic_energy, self.max_speed
        )?;
        writeln!(out, "total weight        {:.4e} N", self.total_weight)?;
        writeln!(
            out,
            "contacts            {} particle-particle, {} particle-wall",
            self.contacts.particle_particle, self.contacts.particle_wall
        )?;
        writeln!(out, "neighbour rebuilds  {}", self.neighbour_rebuilds)?;
        for w in &self.walls {
            let [x, y, z] = w.force;
            write!(
                out,
                "wall {:<14} force ({x:.4e}, {y:.4e}, {z:.4e}) N",
                w.name
            )?;
            match w.weight_fraction {
                Some(r) => writeln!(out, "; along gravity {r:.4} x total weight")?,
                None => writeln!(out)?,
            }
        }
        for (k, f) in self.factories.iter().enumerate() {
            writeln!(out, "factory {k:<11} created {} of {}", f.created, f.count)?;
        }
        if !self.samples.is_empty() {
            writeln!(
                out,
                "samples             time/s  particles  contacts  kinetic energy/J"
            )?;
            for s in &self.samples {
                writeln!(
                    out,
                    "                    {:<7} {:>9} {:>9}  {:.4e}",
                    short(s.time),
                    s.particles,
                    s.contacts,
                    s.kinetic_energy
                )?;
            }
        }
        for w in &self.warnings {
            writeln!(out, "warning             {w}")?;
        }
        Ok(())
    }
}

/// `t` to 6 significant digits, without trailing zeros (0.15, 2e-5).
fn short(t: f64) -> String {
    let rounded: f64 = format!("{t:.5e}").parse().unwrap_or(t);
    format!("{rounded}")
}
