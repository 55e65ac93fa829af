//! The repose test's run: checks the heap at intervals until it is at rest ([`super::rest`])
//! and reports the heap, the funnel's flow and what stayed in the funnel.

use super::ReposeParams;
use super::funnel::Rig;
use crate::lab::discharge::Discharge;
use crate::lab::observe::{self, Tray};
use crate::lab::protocol::{Control, Protocol};
use anyhow::Result;
use std::collections::BTreeMap;
use tilth_kernel::sim::Simulation;

/// Runs a repose test to rest.
pub struct ReposeProtocol {
    pub(super) p: ReposeParams,
    pub(super) tray: Tray,
    pub(super) count: usize,
    pub(super) fill_time: f64,
    pub(super) z_out: f64,
    /// Outlet diameter, m.
    pub(super) outlet: f64,
    /// (time, cone angle) at each check.
    pub(super) angles: Vec<(f64, f64)>,
    /// (time, mean speed of the grains below the outlet, m/s) at each check.
    pub(super) mean_speeds: Vec<(f64, f64)>,
    pub(super) settled_at: Option<f64>,
    pub(super) check_every: f64,
    pub(super) next_check: f64,
    pub(super) diameter: f64,
    pub(super) mass_g: f64,
    /// The funnel's flow, sampled every [`DISCHARGE_SAMPLE`] s until 80 % has left it.
    pub(super) discharge: Discharge,
}

/// Sampling interval of the discharge, s: a coarse run empties the funnel's middle 60 % in
/// about 0.1 s, so 1 ms puts the rate's timing error well under 1 %.
const DISCHARGE_SAMPLE: f64 = 1e-3;

impl ReposeProtocol {
    /// A test of `p` on `rig`, pouring `count` particles of diameter `diameter` m (`mass_g`
    /// g in all) through an outlet `outlet` m wide.
    pub(super) fn new(
        p: &ReposeParams,
        rig: &Rig,
        count: usize,
        outlet: f64,
        diameter: f64,
        mass_g: f64,
    ) -> ReposeProtocol {
        ReposeProtocol {
            p: p.clone(),
            tray: rig.tray(),
            count,
            fill_time: count as f64 / p.rate,
            z_out: rig.z_out,
            outlet,
            angles: vec![],
            mean_speeds: vec![],
            settled_at: None,
            check_every: 0.02,
            next_check: 0.0,
            diameter,
            mass_g,
            discharge: Discharge::default(),
        }
    }

    /// The fraction of the poured mass below the outlet (by mass: with a fine fraction a
    /// count would weigh a fine grain as much as a coarse one).
    fn passed(&self, sim: &Simulation) -> f64 {
        let p = &sim.particles;
        let below: f64 = (0..p.len())
            .filter(|&k| p.position[k].z < self.z_out)
            .map(|k| p.mass[k])
            .sum();
        below * 1e3 / self.mass_g
    }

    /// The soil left in the funnel (above its outlet), g: what sticks to the funnel's wall
    /// or arches over its outlet, as a lab weighs the funnel after the test.
    fn residue_g(&self, sim: &Simulation) -> f64 {
        let p = &sim.particles;
        (0..p.len())
            .filter(|&k| p.position[k].z > self.z_out)
            .map(|k| p.mass[k])
            // A fold from +0: f64's `sum` of nothing is -0, which an empty funnel printed.
            .fold(0.0, |total, m| total + m)
            * 1e3
    }
}

impl Protocol for ReposeProtocol {
    fn control(&mut self, sim: &mut Simulation) -> Result<Control> {
        if sim.time + 1e-12 >= self.next_check {
            let h = observe::heap(sim, self.tray);
            self.angles.push((sim.time, h.cone_angle_deg));
            if let Some(v) = self.mean_speed_below_outlet(sim) {
                self.mean_speeds.push((sim.time, v));
            }
            self.next_check = sim.time + self.check_every;
            if self.at_rest(sim) {
                // At rest with most of the soil still in the funnel is a jam, not a heap.
                self.check_jam(sim, true)?;
                self.settled_at = Some(sim.time);
                return Ok(Control::Done);
            }
            self.check_jam(sim, false)?;
        }
        if sim.time >= self.p.max_time - 0.5 * sim.dt {
            return Ok(Control::Done);
        }
        let mut until = self.next_check;
        if !self.discharge.done() {
            self.discharge.sample(sim.time, self.passed(sim));
            until = until.min(sim.time + DISCHARGE_SAMPLE);
        }
        let steps = ((until - sim.time) / sim.dt).ceil().max(1.0) as u64;
        Ok(Control::Step(steps))
    }

    fn scalars(&self, sim: &Simulation) -> Vec<(String, f64)> {
        let h = observe::heap(sim, self.tray);
        vec![
            ("heap_cone_angle_deg".into(), h.cone_angle_deg),
            ("heap_height".into(), h.height_m),
            ("particles_on_tray".into(), h.particles_on_tray as f64),
        ]
    }

    fn units(&self) -> Vec<(String, String)> {
        vec![
            ("heap_cone_angle_deg".into(), "degree".into()),
            ("heap_height".into(), "m".into()),
            ("particles_on_tray".into(), "count".into()),
        ]
    }

    fn metadata(&self) -> BTreeMap<String, String> {
        [
            ("type", "repose".to_string()),
            ("tray_radius_m", self.tray.radius.to_string()),
            ("tray_top_z_m", self.tray.centre[2].to_string()),
            ("tray_centre_x_m", "0".into()),
            ("tray_centre_y_m", "0".into()),
            ("drop_height_m", self.p.drop_height.to_string()),
            ("particle_diameter_m", self.diameter.to_string()),
            ("mass_g", self.mass_g.to_string()),
            ("photographs", self.p.photographs.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }

    fn phase(&self) -> String {
        "pouring and settling".into()
    }

    fn progress(&self, sim: &Simulation) -> f64 {
        (sim.time / self.p.max_time).min(1.0)
    }

    fn summary(&self, sim: &Simulation) -> serde_json::Value {
        let h = observe::heap(sim, self.tray);
        serde_json::json!({
            "settled": self.settled_at.is_some(),
            "settled_at_s": self.settled_at,
            "heap_cone_angle_deg": h.cone_angle_deg,
            "heap_height_m": h.height_m,
            "particles_on_tray": h.particles_on_tray,
            "tray_mass_g": h.mass_on_tray_kg * 1e3,
            "funnel_flow_rate_g_s": self.discharge.rate_g_per_s(self.mass_g),
            "particles": sim.particles.len(),
            "particles_left_in_funnel": sim.particles.position.iter().filter(|x| x.z > self.z_out).count(),
            "funnel_residue_g": self.residue_g(sim),
            "heap_reached_outlet": self.reached_outlet(sim),
            "warning": if self.settled_at.is_none() {
                Some(self.not_at_rest(sim))
            } else if self.reached_outlet(sim) {
                Some(format!("the heap grew up to the funnel outlet ({} m above the tray): its angle is cut there and is a lower bound; raise repose.drop_height", self.p.drop_height))
            } else { None },
        })
    }
}
