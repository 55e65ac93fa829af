//! When the heap is at rest, why it is not, and when the funnel jammed instead.

use super::run::ReposeProtocol;
use crate::lab::observe;
use anyhow::{Result, bail};
use tilth_kernel::sim::Simulation;

/// The "still" path to rest: the mean speed below the outlet under this fraction of
/// `rest_speed` for `rest_time` (see `ReposeProtocol::at_rest`).
const STILL_FRACTION: f64 = 0.2;

impl ReposeProtocol {
    /// The mean speed (m/s) of the grains below the outlet, `None` when there are none.
    pub(super) fn mean_speed_below_outlet(&self, sim: &Simulation) -> Option<f64> {
        let p = &sim.particles;
        let (sum, n) = (0..p.len())
            .filter(|&k| p.position[k].z < self.z_out)
            .fold((0.0, 0usize), |(s, n), k| {
                (s + p.velocity[k].length(), n + 1)
            });
        (n > 0).then(|| sum / n as f64)
    }

    pub(super) fn at_rest(&self, sim: &Simulation) -> bool {
        let p = &sim.particles;
        if p.len() < self.count || sim.time < self.fill_time {
            return false;
        }
        // Below the outlet: what is left in the funnel at rest is residue (or, when the heap
        // has grown up to the outlet, the soil the heap holds back).
        match self.mean_speed_below_outlet(sim) {
            Some(v) if v <= self.p.rest_speed => {}
            _ => return false,
        }
        // The heap is not done while the funnel still holds a fifth of the soil and it moves:
        // a choked outlet lets the heap below rest while the pour goes on (then either the
        // funnel empties, or it comes to rest and `check_jam` names the jam).
        let above: Vec<usize> = (0..p.len())
            .filter(|&k| p.position[k].z > self.z_out)
            .collect();
        if above.len() * 5 > self.count && !self.reached_outlet(sim) {
            let speed =
                above.iter().map(|&k| p.velocity[k].length()).sum::<f64>() / above.len() as f64;
            if speed > self.p.rest_speed {
                return false;
            }
        }
        // Still: the soil below the outlet moved slower than STILL_FRACTION x rest_speed on
        // average at every check for rest_time. Then the heap is at rest even if its angle
        // still flips: a grain hanging on one contact can spin about that contact's normal
        // for ever, since no law of a model without twisting resistance opposes that spin
        // (tests/tests/twisting.rs), and as it passes observe::HEAP_SPEED the angle flips
        // (docs/li2022-compare.md, "Grains that never stop"). A heap that is still flowing or
        // creeping moves faster than this on average.
        let since = sim.time - self.p.rest_time;
        let still = self.p.rest_speed * STILL_FRACTION;
        if self.mean_speeds.iter().any(|(t, _)| *t <= since)
            && self
                .mean_speeds
                .iter()
                .filter(|(t, _)| *t >= since)
                .all(|(_, v)| *v < still)
        {
            return true;
        }
        let window: Vec<f64> = self
            .angles
            .iter()
            .filter(|(t, _)| *t >= since)
            .map(|(_, a)| *a)
            .collect();
        let spans_window = self.angles.iter().any(|(t, _)| *t <= since);
        let lo = window.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = window.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        spans_window && hi - lo < self.p.rest_angle
    }

    /// Why a run that reached `max_time` was not at rest, in words. Either the soil below the
    /// outlet still moves on average (then more time may settle it), or it is at rest on
    /// average and a few grains keep moving: in a cohesive (JKR) model some grains rock or
    /// orbit for ever, and as one near the apex passes [`observe::HEAP_SPEED`] the cone angle
    /// flips between two values, so the angle never holds still and more time does not help
    /// (docs/li2022-compare.md, "Grains that never stop").
    pub(super) fn not_at_rest(&self, sim: &Simulation) -> String {
        let p = &sim.particles;
        let below: Vec<usize> = (0..p.len())
            .filter(|&k| p.position[k].z < self.z_out)
            .collect();
        let speeds: Vec<f64> = below.iter().map(|&k| p.velocity[k].length()).collect();
        let mean = speeds.iter().sum::<f64>() / speeds.len().max(1) as f64;
        let since = sim.time - self.p.rest_time;
        let (lo, hi) = self
            .angles
            .iter()
            .filter(|(t, _)| *t >= since)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, a)| {
                (lo.min(*a), hi.max(*a))
            });
        let movers = speeds.iter().filter(|&&v| v > observe::HEAP_SPEED).count();
        let fastest = speeds.iter().copied().fold(0.0, f64::max);
        if below.is_empty() || mean > self.p.rest_speed || !(hi >= lo) {
            return format!(
                "the heap was not at rest at max_time = {} s (mean speed below the outlet {mean:.2e} m/s, rest_speed {}); raise repose.max_time",
                self.p.max_time, self.p.rest_speed
            );
        }
        format!(
            "the heap was not at rest at max_time = {} s: the soil below the outlet is at rest on average \
             (mean speed {mean:.2e} m/s, rest_speed {}), but the cone angle moved between {lo:.2} and {hi:.2} deg over the last {} s \
             (rest_angle {}), with {movers} grain(s) faster than {} m/s (the fastest {fastest:.3} m/s). If those grains rock or orbit \
             for ever, more time will not settle the heap: the angle flips as they pass that speed and the reading is one of its values \
             (docs/li2022-compare.md, \"Grains that never stop\")",
            self.p.max_time,
            self.p.rest_speed,
            self.p.rest_time,
            self.p.rest_angle,
            observe::HEAP_SPEED,
        )
    }

    /// Whether the heap on the tray has grown up to the funnel outlet: its top is there, and
    /// there is enough soil below the outlet to build that tall a cone even at 80 degrees
    /// (V = pi/3 h^3 cot^2 80, at a solid fraction of 0.5). Without the second test, a few
    /// grains hanging from an arched outlet would pass for a heap that reached it.
    pub(super) fn reached_outlet(&self, sim: &Simulation) -> bool {
        let h = observe::heap(sim, self.tray);
        let top = self.p.drop_height - self.diameter;
        if h.height_m < top {
            return false;
        }
        let p = &sim.particles;
        let (mut solid, mut below) = (0.0, 0usize);
        for k in 0..p.len() {
            if p.position[k].z < self.z_out {
                solid += 4.0 / 3.0 * std::f64::consts::PI * p.radius[k].powi(3);
                below += 1;
            }
        }
        let cot = (80f64).to_radians().tan().recip();
        let cone = std::f64::consts::PI / 3.0 * top.powi(3) * cot * cot;
        below > 0 && solid >= 0.5 * cone
    }

    /// Fails when particles stay in the funnel, at rest, well after the pour (or once what
    /// has reached the tray is at rest, `settled`): the outlet arched over (cohesion, or
    /// particles too large for it). Not when the heap has grown up to the outlet: then the
    /// heap holds the soil back, and the result says so.
    pub(super) fn check_jam(&self, sim: &Simulation, settled: bool) -> Result<()> {
        if sim.particles.len() < self.count || (!settled && sim.time < self.fill_time + 0.5) {
            return Ok(());
        }
        if self.reached_outlet(sim) {
            return Ok(());
        }
        let p = &sim.particles;
        let stuck: Vec<usize> = (0..p.len())
            .filter(|&k| p.position[k].z > self.z_out)
            .collect();
        if stuck.is_empty() {
            return Ok(());
        }
        let speed = stuck.iter().map(|&k| p.velocity[k].length()).sum::<f64>() / stuck.len() as f64;
        // A few grains stuck to the funnel wall are residue; a fifth of the soil is a jam.
        if speed < self.p.rest_speed && stuck.len() * 5 > self.count {
            bail!(
                "the funnel jammed at t = {:.2} s (step {}): {} of {} particles are at rest above \
                 the outlet (mean speed {:.1e} m/s). The outlet ({} m) is {:.1} particle diameters \
                 wide; cohesion arches over narrow outlets: use smaller particles or a wider outlet",
                sim.time,
                sim.step,
                stuck.len(),
                p.len(),
                speed,
                self.outlet,
                self.outlet / self.diameter
            );
        }
        Ok(())
    }
}
