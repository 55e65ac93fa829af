//! `ucs`: the unconfined compression test (docs/experiments.md).
//!
//! A steel mould (61.8 mm inner diameter) on a steel base is filled loosely; the particles
//! settle, a platen compacts them with `compaction_force`, bonds form, the mould is removed
//! and the platen compresses the free specimen (initial height h0, 40 mm at the default
//! packing) at constant speed until the axial force has clearly passed its peak or the axial
//! strain reaches `max_strain` (15 %). Speed: at most half of `max_inertial_number`, with the
//! inertial number I = (v / h0) d sqrt(rho / sigma) computed at `reference_stress` (the
//! stress scale of the test; the actual I along the test is reported).

use super::experiment::{Built, Common, soil_density};
use super::protocol::{Control, Protocol};
use super::scene::{self, WallId};
use super::specimen::{self, Prep, Preparation};
use crate::config::WallSection;
use anyhow::{Result, bail};
use serde::Deserialize;
use std::collections::BTreeMap;
use tilth_kernel::DVec3;
use tilth_kernel::sim::Simulation;
use tilth_kernel::wall::Motion;

/// `[ucs]`: the test's parameters (SI units).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UcsParams {
    /// Mould inner diameter, m (61.8 mm).
    #[serde(default = "default_diameter")]
    pub mould_diameter: f64,
    /// Specimen height the particle count is sized for, m (40 mm).
    #[serde(default = "default_height")]
    pub height: f64,
    /// Particle diameter, m (2 mm; coarse preset 4 mm).
    pub diameter: Option<f64>,
    #[serde(default = "default_packing")]
    pub packing: f64,
    /// Compaction force before bonding, N (as the shear test: 12 N).
    #[serde(default = "default_compaction")]
    pub compaction_force: f64,
    /// Stop at this axial strain (the study: 15 %).
    #[serde(default = "default_max_strain")]
    pub max_strain: f64,
    /// The test ends once the force has fallen below this fraction of its peak.
    #[serde(default = "default_drop")]
    pub peak_drop: f64,
    /// Platen speed, m/s, constant. Default: adaptive, the speed that keeps the inertial
    /// number at half of `max_inertial_number` at the current stress (at least 1 kPa), at
    /// most the speed that does so at `reference_stress`.
    pub speed: Option<f64>,
    #[serde(default = "default_inertial")]
    pub max_inertial_number: f64,
    /// Stress scale for the speed and the loaded time step (`specimen::loaded_steps`), Pa
    /// (the study's strengths: 11-320 kPa).
    #[serde(default = "default_reference")]
    pub reference_stress: f64,
    #[serde(default = "default_phase_time")]
    pub max_phase_time: f64,
}

fn default_diameter() -> f64 {
    0.0618
}
fn default_height() -> f64 {
    0.040
}
fn default_packing() -> f64 {
    0.55
}
fn default_compaction() -> f64 {
    12.0
}
fn default_max_strain() -> f64 {
    0.15
}
fn default_drop() -> f64 {
    0.8
}
fn default_inertial() -> f64 {
    1.0e-3
}
fn default_reference() -> f64 {
    5.0e4
}
fn default_phase_time() -> f64 {
    2.0
}

impl Default for UcsParams {
    fn default() -> Self {
        toml::from_str("").expect("defaults")
    }
}

/// The fragment catcher's radius beyond the specimen's, m (inside the domain's r + 0.05).
const CATCHER_GAP: f64 = 0.04;

/// The scene and protocol of an unconfined compression test.
pub fn build(c: &Common, p: &UcsParams) -> Result<Built> {
    let d = super::experiment::particle_diameter(c, p.diameter);
    let mix = super::sizes::SizeMix::of(c.model, c.at(), d)?;
    check_params(p, d)?;
    let rho = soil_density(c.model)?;
    let speed = platen_speed(p, d, rho)?;
    let r = 0.5 * p.mould_diameter;
    let area = std::f64::consts::PI * r * r;
    let loads = specimen::Loads {
        compaction: p.compaction_force / area,
        test: p.reference_stress,
    };
    let (steps, count) = specimen::particles_for(c, &mix, area * p.height, p.packing, loads, true)?;
    let parts = c.model.scene_parts(c.at(), true)?;
    let (z_fill, z_top) = specimen::mould_heights(p.height, p.packing, d);
    let duration = 4.0 * p.max_phase_time + p.max_strain * p.height / speed + 0.5;
    let simulation = specimen::simulation(
        c,
        steps.prepare,
        duration,
        r + 0.05,
        z_top + 0.02,
        mix.min_diameter(),
    );
    let walls = mould_walls(r, z_top);
    let (mould, platen) = (
        WallId::find(&walls, "mould")?,
        WallId::find(&walls, "platen")?,
    );
    let fill = specimen::fill(count, &mix, r - 0.6 * d, 0.6 * d, z_fill);
    let scene = scene::scene(parts, simulation, walls, vec![fill]);
    let prep = Preparation::new(
        platen,
        p.compaction_force,
        p.max_phase_time,
        z_top,
        d,
        steps.bonded,
    );
    Ok(Built {
        scene: scene::to_value(&scene)?,
        bonded_dt: Some(steps.bonded),
        protocol: Box::new(UcsProtocol {
            mould,
            platen,
            prep,
            phase: Phase::Prepare,
            p: p.clone(),
            area,
            speed,
            d,
            rho,
            bonds: 0,
            started: 0.0,
            z0: 0.0,
            h0: 0.0,
            peak: Peak::default(),
            max_i: 0.0,
            stop_reason: String::new(),
            platen_z: z_top,
            adaptive: p.speed.is_none(),
            platen_force: specimen::MeanForce::new(&[platen]),
        }),
    })
}

/// Refuses a specimen the particles of diameter `d` (m) do not fit and values out of range.
fn check_params(p: &UcsParams, d: f64) -> Result<()> {
    specimen::check_fit("ucs", p.mould_diameter, p.height, d)?;
    specimen::check_positive(
        "ucs",
        &[
            ("compaction_force", p.compaction_force),
            ("max_inertial_number", p.max_inertial_number),
            ("reference_stress", p.reference_stress),
            ("max_phase_time", p.max_phase_time),
        ],
    )?;
    if !(p.max_strain > 0.0 && p.max_strain < 0.5) {
        bail!(
            "ucs.max_strain = {} is out of range: allowed (0, 0.5)",
            p.max_strain
        );
    }
    if !(p.peak_drop > 0.0 && p.peak_drop < 1.0) {
        bail!(
            "ucs.peak_drop = {} is out of range: allowed (0, 1)",
            p.peak_drop
        );
    }
    specimen::check_packing("ucs", p.packing)
}

/// The platen's speed, m/s, for particles of diameter `d` (m) and density `rho` (kg/m^3): the
/// one given, or the speed at half of `max_inertial_number` at `reference_stress` (the
/// adaptive speed's ceiling); refused when it passes that limit.
fn platen_speed(p: &UcsParams, d: f64, rho: f64) -> Result<f64> {
    let i_at = |v: f64, h: f64| specimen::inertial_number(v / h, d, rho, p.reference_stress);
    let speed = match p.speed {
        Some(v) if v > 0.0 && v.is_finite() => v,
        Some(v) => bail!("ucs.speed = {v} is out of range: allowed (0, inf) m/s"),
        None => 0.5 * p.max_inertial_number / i_at(1.0, p.height),
    };
    if i_at(speed, p.height) > p.max_inertial_number {
        bail!(
            "ucs.speed = {speed} m/s gives an inertial number of {:.2e} at {} Pa, above max_inertial_number = {:.1e}",
            i_at(speed, p.height),
            p.reference_stress,
            p.max_inertial_number
        );
    }
    Ok(speed)
}

/// The rig for a specimen of radius `r` (m) with the platen at `z_top` (m): the base, the
/// mould (removed once the bonds form), the platen and the fragment catcher.
fn mould_walls(r: f64, z_top: f64) -> Vec<WallSection> {
    vec![
        scene::floor("base"),
        scene::ring("mould", 0.0, z_top, r),
        scene::disc("platen", z_top, r + 0.02),
        // A brittle specimen throws fragments at up to about 1 m/s when it fails; without a
        // wall around it they leave the domain and end the run as an error. The catcher
        // holds them on the base, well clear of the specimen.
        scene::ring("catcher", 0.0, z_top + 0.02, r + CATCHER_GAP),
    ]
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Prepare,
    Release,
    Compress,
    Done,
}

/// The failure point so far, by corrected-area stress.
#[derive(Debug, Clone, Copy, Default)]
struct Peak {
    strain: f64,
    force: f64,
    stress: f64,
}

struct UcsProtocol {
    /// Removed once the bonds form.
    mould: WallId,
    /// Compacts, then compresses the free specimen.
    platen: WallId,
    prep: Preparation,
    phase: Phase,
    p: UcsParams,
    area: f64,
    speed: f64,
    d: f64,
    rho: f64,
    bonds: usize,
    started: f64,
    /// Platen offset and specimen height when compression starts, m.
    z0: f64,
    h0: f64,
    peak: Peak,
    max_i: f64,
    stop_reason: String,
    /// The platen's initial height, m.
    platen_z: f64,
    /// Speed follows the stress (see [`UcsParams::speed`]).
    adaptive: bool,
    /// Mean force on the platen since the last control call (the block just run).
    platen_force: specimen::MeanForce,
}

impl UcsProtocol {
    fn strain(&self, sim: &Simulation) -> f64 {
        if self.h0 > 0.0 {
            (self.z0 - self.platen.of(sim).offset.z) / self.h0
        } else {
            0.0
        }
    }

    /// Axial force over the last block, positive in compression, N.
    fn force(&self, sim: &Simulation) -> f64 {
        self.platen_force.mean(sim).z
    }
}

impl Protocol for UcsProtocol {
    fn control(&mut self, sim: &mut Simulation) -> Result<Control> {
        let block = ((0.002 / sim.dt).ceil() as u64).max(1);
        // Decisions use the force averaged over the block just run; then a new block starts.
        let f_mean = self.force(sim);
        self.platen_force.mark(sim);
        match self.phase {
            Phase::Prepare => {
                if self.prep.advance(sim, "ucs")? {
                    self.bonds = self.prep.bond(sim)?;
                    if self.bonds == 0 {
                        bail!(
                            "ucs: no bonds formed after compaction (step {}): the particles do not touch",
                            sim.step
                        );
                    }
                    sim.set_wall_active(self.mould.index(), false);
                    self.platen.of_mut(sim).motion = Motion::Fixed;
                    self.phase = Phase::Release;
                    self.started = sim.time;
                }
            }
            Phase::Release => {
                if specimen::mean_speed(sim) < 0.005 || sim.time - self.started > 0.1 {
                    // The specimen's height is the distance from the base to the platen.
                    self.z0 = self.platen.of(sim).offset.z;
                    self.h0 = self.platen_z + self.z0;
                    if self.h0 < 4.0 * self.d || specimen::top(sim) < 0.5 * self.h0 {
                        bail!(
                            "ucs: the specimen collapsed when the mould was removed (height {:.1} mm, step {}): bonds too weak to stand",
                            specimen::top(sim) * 1e3,
                            sim.step
                        );
                    }
                    let v = if self.adaptive {
                        let unit =
                            specimen::inertial_number(1.0 / self.h0, self.d, self.rho, 1.0e3);
                        (0.5 * self.p.max_inertial_number / unit).min(self.speed)
                    } else {
                        self.speed
                    };
                    self.platen.of_mut(sim).motion = Motion::Velocity(DVec3::new(0.0, 0.0, -v));
                    self.phase = Phase::Compress;
                }
            }
            Phase::Compress => {
                let eps = self.strain(sim);
                let f = f_mean;
                let ac = self.area / (1.0 - eps).max(1e-6);
                let sigma = f / ac;
                if sigma > self.peak.stress {
                    self.peak = Peak {
                        strain: eps,
                        force: f,
                        stress: sigma,
                    };
                }
                let v_now = -self.platen.of(sim).velocity.z;
                let i = specimen::inertial_number(
                    v_now / self.h0.max(1e-9),
                    self.d,
                    self.rho,
                    sigma.max(1.0),
                );
                if sigma > 0.1 * self.peak.stress && self.peak.stress > 0.0 {
                    self.max_i = self.max_i.max(i);
                }
                if self.adaptive {
                    // I is linear in the speed: aim at half the limit at today's stress.
                    let unit = specimen::inertial_number(
                        1.0 / self.h0,
                        self.d,
                        self.rho,
                        sigma.max(1.0e3),
                    );
                    let v = (0.5 * self.p.max_inertial_number / unit).min(self.speed);
                    self.platen.of_mut(sim).motion = Motion::Velocity(DVec3::new(0.0, 0.0, -v));
                }
                let past_peak = self.peak.stress > 0.0
                    && sigma < self.p.peak_drop * self.peak.stress
                    && eps > self.peak.strain + 0.01;
                if past_peak || eps >= self.p.max_strain {
                    self.stop_reason = if past_peak {
                        format!("the stress fell below {} of its peak", self.p.peak_drop)
                    } else {
                        format!("axial strain reached {}", self.p.max_strain)
                    };
                    self.platen.of_mut(sim).motion = Motion::Fixed;
                    self.phase = Phase::Done;
                    return Ok(Control::Done);
                }
            }
            Phase::Done => return Ok(Control::Done),
        }
        Ok(Control::Step(block))
    }

    fn scalars(&self, sim: &Simulation) -> Vec<(String, f64)> {
        let (intact, broken) = sim.bond_counts();
        let mut out = vec![
            ("platen_force".to_string(), self.force(sim)),
            ("bonds_intact".to_string(), intact as f64),
            ("bonds_broken".to_string(), broken as f64),
        ];
        // The test's curve: written only while compressing (see the shear test).
        if matches!(self.phase, Phase::Compress | Phase::Done) {
            let eps = self.strain(sim);
            let f = self.force(sim);
            let sigma = f / (self.area / (1.0 - eps).max(1e-6));
            let v = -self.platen.of(sim).velocity.z;
            out.push(("axial_strain".into(), eps));
            out.push(("axial_force".into(), f));
            out.push((
                "inertial_number".into(),
                specimen::inertial_number(v / self.h0.max(1e-9), self.d, self.rho, sigma.max(1.0)),
            ));
        }
        out
    }

    fn units(&self) -> Vec<(String, String)> {
        specimen::units(&[
            ("platen_force", "N"),
            ("axial_strain", "-"),
            ("axial_force", "N"),
            ("inertial_number", "-"),
            ("bonds_intact", "count"),
            ("bonds_broken", "count"),
        ])
    }

    fn metadata(&self) -> BTreeMap<String, String> {
        specimen::record(vec![
            ("type", "ucs".to_string()),
            ("diameter_m", self.p.mould_diameter.to_string()),
            ("height_m", self.p.height.to_string()),
            ("speed_m_per_s", self.speed.to_string()),
            ("particle_diameter_m", self.d.to_string()),
        ])
    }

    fn phase(&self) -> String {
        match (self.phase, self.prep.phase) {
            (Phase::Prepare, Prep::Fill) => "filling".into(),
            (Phase::Prepare, Prep::Settle) => "settling".into(),
            (Phase::Prepare, _) => "compacting".into(),
            (Phase::Release, _) => "mould removed".into(),
            (Phase::Compress, _) => "compressing".into(),
            (Phase::Done, _) => "done".into(),
        }
    }

    fn progress(&self, sim: &Simulation) -> f64 {
        match self.phase {
            Phase::Prepare | Phase::Release => 0.0,
            Phase::Compress => 0.3 + 0.7 * self.strain(sim) / self.p.max_strain,
            Phase::Done => 1.0,
        }
    }

    fn summary(&self, sim: &Simulation) -> serde_json::Value {
        let (intact, broken) = sim.bond_counts();
        serde_json::json!({
            "ucs_kpa": self.peak.stress / 1e3,
            "strain_at_failure": self.peak.strain,
            "peak_force_n": self.peak.force,
            "initial_height_m": self.h0,
            "speed_m_per_s": self.speed,
            "max_inertial_number": self.max_i,
            "stopped_because": self.stop_reason,
            "particles": sim.particles.len(),
            "bonds_formed": self.bonds,
            "time_step_bonded_s": self.prep.bonded_dt,
            "bonds_intact": intact,
            "bonds_broken": broken,
            "completed": self.phase == Phase::Done,
        })
    }
}
