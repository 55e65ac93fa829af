//! `[simulation]`: time stepping, gravity, neighbour skin, threads, seed and domain.

use super::FactorySection;
use super::check;
use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};
use tilth_kernel::DVec3;
use tilth_kernel::particles::Particles;
use tilth_kernel::sim::Aabb;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSection {
    /// Time step, s.
    pub dt: f64,
    /// Simulated time, s. Give exactly one of `duration` and `steps`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// Number of steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Gravitational acceleration, m/s^2 (default [0, 0, -9.81]).
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Verlet skin, m (default 0.2 x the smallest particle diameter). The neighbour list is
    /// rebuilt when something has moved more than half of it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skin: Option<f64>,
    /// Worker threads (default 1); results do not depend on it. `--threads` overrides it.
    #[serde(default = "default_threads")]
    pub threads: usize,
    /// Seeds every factory (default 1); factory k gets its own seed derived from it.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Particles leaving this box stop the run.
    pub domain: DomainSection,
}

/// Axis-aligned box, m.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSection {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

/// Standard gravity pointing down the z axis, m/s^2: the default `gravity`.
pub const STANDARD_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

fn default_gravity() -> [f64; 3] {
    STANDARD_GRAVITY
}
fn default_threads() -> usize {
    1
}
fn default_seed() -> u64 {
    1
}

/// Default skin as a fraction of the smallest particle diameter.
pub const SKIN_PER_DIAMETER: f64 = 0.2;

/// Checked values of the section.
pub struct Resolved {
    pub dt: f64,
    pub steps: u64,
    pub gravity: DVec3,
    pub skin: f64,
    pub threads: usize,
    pub domain: Aabb,
}

impl SimulationSection {
    pub fn resolve(&self, particles: &Particles, factories: &[FactorySection]) -> Result<Resolved> {
        let dt = check::positive("simulation.dt", self.dt, "s")?;
        let steps = match (self.duration, self.steps) {
            (Some(t), None) => {
                check::positive("simulation.duration", t, "s")?;
                ((t / dt).round() as u64).max(1)
            }
            (None, Some(n)) if n > 0 => n,
            (None, Some(_)) => bail!("simulation.steps = 0; give at least 1"),
            (Some(_), Some(_)) => bail!(
                "simulation: both duration and steps are given; give exactly one of duration (s) and steps"
            ),
            (None, None) => bail!(
                "simulation: neither duration nor steps is given; give exactly one of duration (s) and steps"
            ),
        };
        if self.threads == 0 {
            bail!("simulation.threads = 0 is out of range: allowed [1, cores]");
        }
        let d_min = particles
            .radius
            .iter()
            .map(|r| 2.0 * r)
            .chain(
                factories
                    .iter()
                    .flat_map(|f| f.sizes.iter().map(|s| s.diameter)),
            )
            .fold(f64::INFINITY, f64::min);
        let skin = match self.skin {
            Some(s) => check::non_negative("simulation.skin", s, "m")?,
            None if d_min.is_finite() && d_min > 0.0 => SKIN_PER_DIAMETER * d_min,
            None => 0.0,
        };
        let min = check::vec3("simulation.domain.min", self.domain.min)?;
        let max = check::vec3("simulation.domain.max", self.domain.max)?;
        if !min.cmplt(max).all() {
            bail!(
                "simulation.domain: min {:?} must lie below max {:?} on every axis",
                self.domain.min,
                self.domain.max
            );
        }
        Ok(Resolved {
            dt,
            steps,
            gravity: check::vec3("simulation.gravity", self.gravity)?,
            skin,
            threads: self.threads,
            domain: Aabb { min, max },
        })
    }
}
