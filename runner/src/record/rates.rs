//! `[record]`: how often each channel is written, in frames per simulated second.

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

/// Frame rates per channel (Hz of simulated time); 0 switches a channel off.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RecordSection {
    /// Particle point clouds (`/particles`), frames per simulated second.
    #[serde(default = "default_particles_hz")]
    pub particles_hz: f64,
    /// Wall poses (`/walls`) and forces and torques (`/walls/<name>/force|torque`).
    #[serde(default = "default_walls_hz")]
    pub walls_hz: f64,
    /// Scalar time series (`/scalars/<name>`): kinetic energy, contacts, the observable.
    #[serde(default = "default_scalars_hz")]
    pub scalars_hz: f64,
    /// Bonds (`/bonds`: every bond's state; `/bonds/lines`: intact bonds coloured by force),
    /// when the run has any.
    #[serde(default = "default_bonds_hz")]
    pub bonds_hz: f64,
    /// Also write every particle as a sphere in a `foxglove.SceneUpdate` (`/spheres`),
    /// which Foxglove draws at true size; off by default because it is ten times larger.
    #[serde(default)]
    pub spheres: bool,
    /// Close the current MCAP chunk after this many particle frames, so that a killed run
    /// loses at most that many frames.
    #[serde(default = "default_flush_frames")]
    pub flush_frames: u32,
}

fn default_particles_hz() -> f64 {
    50.0
}
fn default_walls_hz() -> f64 {
    50.0
}
fn default_scalars_hz() -> f64 {
    500.0
}
fn default_bonds_hz() -> f64 {
    10.0
}
fn default_flush_frames() -> u32 {
    5
}

impl Default for RecordSection {
    fn default() -> Self {
        RecordSection {
            particles_hz: default_particles_hz(),
            walls_hz: default_walls_hz(),
            scalars_hz: default_scalars_hz(),
            bonds_hz: default_bonds_hz(),
            spheres: false,
            flush_frames: default_flush_frames(),
        }
    }
}

/// Frame intervals in steps (0 = off).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRates {
    pub particles: u64,
    pub walls: u64,
    pub scalars: u64,
    pub bonds: u64,
}

impl RecordSection {
    /// Checks the rates (0 or within [0.1 Hz, 1/dt]) and turns them into step intervals.
    pub fn resolve(&self, dt: f64) -> Result<FrameRates> {
        let max = 1.0 / dt;
        let interval = |key: &str, hz: f64| -> Result<u64> {
            if hz == 0.0 {
                return Ok(0);
            }
            if !(hz.is_finite() && (0.1..=max).contains(&hz)) {
                bail!(
                    "record.{key} = {hz} is out of range: allowed 0 (off) or [0.1, {max:.0}] \
                     frames per simulated second (1/dt)"
                );
            }
            Ok(((1.0 / (hz * dt)).round() as u64).max(1))
        };
        if self.flush_frames == 0 {
            bail!("record.flush_frames = 0 is out of range: allowed [1, 4294967295]");
        }
        Ok(FrameRates {
            particles: interval("particles_hz", self.particles_hz)?,
            walls: interval("walls_hz", self.walls_hz)?,
            scalars: interval("scalars_hz", self.scalars_hz)?,
            bonds: interval("bonds_hz", self.bonds_hz)?,
        })
    }
}

impl FrameRates {
    /// Steps from `step` to the next step at which some channel is due (at most `max`).
    pub fn steps_to_next(&self, step: u64, max: u64) -> u64 {
        [self.particles, self.walls, self.scalars, self.bonds]
            .iter()
            .filter(|&&k| k > 0)
            .map(|&k| k - step % k)
            .fold(max, u64::min)
    }

    /// Whether a channel with interval `k` is due at `step`.
    pub fn due(k: u64, step: u64) -> bool {
        k > 0 && step % k == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_follow_the_rates() {
        let r = RecordSection::default().resolve(5e-6).unwrap();
        // 50 Hz at dt = 5e-6 s: one frame per 0.02 s = 4000 steps.
        assert_eq!(r.particles, 4000);
        assert_eq!(r.scalars, 400);
        assert_eq!(r.steps_to_next(0, 10_000), 400);
        assert_eq!(r.steps_to_next(399, 10_000), 1);
        assert_eq!(r.steps_to_next(0, 7), 7);
    }

    #[test]
    fn rates_beyond_the_step_are_refused() {
        let s = RecordSection {
            particles_hz: 1e6,
            ..Default::default()
        };
        let e = s.resolve(5e-6).unwrap_err().to_string();
        assert!(e.contains("record.particles_hz"), "{e}");
        assert!(e.contains("200000"), "{e}");
    }
}
