//! The time step: its checks and warnings (against the Rayleigh time, the bonds' time
//! scale and the loaded packing's stiffest mode), a change of step between steps, and the
//! kick factors derived from it.

use super::Simulation;
use crate::error::{KernelError, Result};
use crate::step_check::{loaded_step_warning, packing_frequency};
use crate::timestep::{BOND_WARN_FRACTION, WARN_FRACTION};

impl Simulation {
    /// Changes the time step from the next step on, e.g. to the shorter step bonds need
    /// once they form (a specimen prepared at the contacts' step, then bonded). Velocity
    /// Verlet is self-starting, so a step of one length may follow one of another; contact
    /// histories integrate rates with each step's own `dt`. Refuses a step that is not a
    /// positive number; warns, as at start, above [`WARN_FRACTION`] of the Rayleigh time, and
    /// checks the new step against the loaded contacts anew.
    pub fn set_dt(&mut self, dt: f64) -> Result<()> {
        check_dt(dt)?;
        if dt == self.dt {
            return Ok(());
        }
        self.time_origin = self.time;
        self.step_origin = self.step;
        self.dt = dt;
        self.refresh_kick_factor();
        self.loaded_step_warned = false;
        if let Some(w) = rayleigh_step_warning(dt, self.rayleigh_time) {
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
        }
        Ok(())
    }

    /// Recomputes every particle's half-step kick factors (dt/2 / m, dt/2 / I) from the
    /// particles and the step: velocity-Verlet's half kick is v += F (dt/2 / m),
    /// omega += T (dt/2 / I). In place, so it allocates nothing once the count of particles
    /// stops growing.
    pub(super) fn refresh_kick_factor(&mut self) {
        // The masses may have a new order: the next sums start from them.
        self.next_ready = None;
        let (p, dt) = (&self.particles, self.dt);
        self.kick_factor.clear();
        self.kick_factor.extend(
            p.mass
                .iter()
                .zip(&p.inertia)
                .map(|(m, i)| (0.5 * dt / m, 0.5 * dt / i)),
        );
    }

    /// Bounds the packing's stiffest contact mode from the pair list and warns, once per
    /// step size, when the step is beyond its stable limit. Reads state only: a run with
    /// and without the check gives the same bits.
    pub(super) fn check_loaded_step(&mut self) {
        let f = packing_frequency(&self.particles, &self.model, &self.pairs, self.dt);
        self.packing_frequency = f;
        if self.loaded_step_warned {
            return;
        }
        if let Some(w) = f.and_then(|f| loaded_step_warning(self.dt, &f)) {
            self.warnings.push(w);
            self.loaded_step_warned = true;
        }
    }
}

/// Refuses a time step that is not a positive number.
pub(super) fn check_dt(dt: f64) -> Result<()> {
    if dt > 0.0 && dt.is_finite() {
        return Ok(());
    }
    Err(KernelError::OutOfRange {
        key: "dt".into(),
        value: dt,
        range: "(0, inf)".into(),
        unit: "s".into(),
    })
}

/// The warning for a step `dt` above [`WARN_FRACTION`] of the Rayleigh time `t_r` (s).
pub(super) fn rayleigh_step_warning(dt: f64, t_r: f64) -> Option<String> {
    (dt > WARN_FRACTION * t_r).then(|| {
        format!(
            "time step {dt:.3e} s is {:.0} % of the Rayleigh time {t_r:.3e} s; EDEM practice is 20-40 %, above that contacts may be unstable",
            100.0 * dt / t_r
        )
    })
}

/// The warning for a step `dt` too long for the shortest bond time scale `t_b` (s) formed.
pub(super) fn bond_step_warning(dt: f64, t_b: f64) -> Option<String> {
    (dt > BOND_WARN_FRACTION * t_b).then(|| {
        format!(
            "time step {dt:.3e} s is {:.0} % of the stiffest bond's time scale sqrt(m / (S A)) = {t_b:.3e} s; above {:.0} % bonded particles may gain energy until the run blows up: shorten the step to {:.3e} s or soften the bonds",
            100.0 * dt / t_b,
            100.0 * BOND_WARN_FRACTION,
            0.8 * BOND_WARN_FRACTION * t_b
        )
    })
}
