//! `tilt`: the tilting-plate test of soil on steel (the inclinometer of the study's table 1,
//! which measured the soil-steel static friction coefficient; docs/experiments.md).
//!
//! A soil sample is made in a ring knife on a steel plate as the UCS specimen is (filled
//! loosely, settled, compacted with `compaction_force`, bonded), the ring and the platen are
//! taken away, and once the sample rests the plate is tilted: gravity turns about the
//! horizontal y axis, quickly to `start_angle` and then at `tilt_rate`, until the sample (the
//! median of its grains' velocities) moves down the slope faster than `slide_speed`. The
//! reading is the plate's angle then, theta, and tan(theta), the static friction coefficient
//! an inclinometer reports. A speed, not a distance: the sample creeps before it slides (its
//! contacts' springs and bonds give, a few tenths of a millimetre), a slide runs away. A
//! rigid block with Coulomb friction mu slides at tan(theta) = mu; adhesion between soil
//! and steel adds to the load the friction carries (F_t <= mu (N + F_adh)), so theta rises
//! with it, the more the lighter the sample is per contact.

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

/// `[tilt]`: the test's parameters (SI units; angles in degrees).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TiltParams {
    /// Ring knife inner diameter, m (the study's 61.8 mm).
    #[serde(default = "default_diameter")]
    pub sample_diameter: f64,
    /// Sample height the particle count is sized for, m (the ring knife's 20 mm). A lower
    /// sample presses each contact with the plate less, so adhesion to the plate shows more.
    #[serde(default = "default_height")]
    pub sample_height: f64,
    /// Particle diameter, m (2 mm; coarse preset 4 mm).
    pub diameter: Option<f64>,
    #[serde(default = "default_packing")]
    pub packing: f64,
    /// Compaction force before bonding, N (as the shear and UCS tests: 12 N).
    #[serde(default = "default_compaction")]
    pub compaction_force: f64,
    /// The plate is turned to this angle at four times `tilt_rate` first, degrees.
    #[serde(default = "default_start")]
    pub start_angle: f64,
    /// Tilting speed from `start_angle` on, degrees/s. The reading lags the angle at which
    /// the sample starts to slide by the time it takes to reach `slide_speed`: for a rigid
    /// block under Coulomb friction mu, accelerating from rest at theta_c at g omega (cos
    /// theta_c + mu sin theta_c) t, omega t = sqrt(2 v omega / (g (cos theta_c + mu sin
    /// theta_c))), 0.7 degrees at 10 degrees/s and 5 mm/s.
    #[serde(default = "default_rate")]
    pub tilt_rate: f64,
    /// The sample slides when it (the median of its grains' velocities) moves down the
    /// slope faster than this, m/s.
    #[serde(default = "default_slide")]
    pub slide_speed: f64,
    /// Stop with a warning at this angle if the sample has not slid, degrees.
    #[serde(default = "default_max_angle")]
    pub max_angle: f64,
    #[serde(default = "default_phase_time")]
    pub max_phase_time: f64,
}

fn default_diameter() -> f64 {
    0.0618
}
fn default_height() -> f64 {
    0.020
}
fn default_packing() -> f64 {
    0.55
}
fn default_compaction() -> f64 {
    12.0
}
fn default_start() -> f64 {
    20.0
}
fn default_rate() -> f64 {
    10.0
}
fn default_slide() -> f64 {
    0.005
}
fn default_max_angle() -> f64 {
    75.0
}
fn default_phase_time() -> f64 {
    2.0
}

impl Default for TiltParams {
    fn default() -> Self {
        toml::from_str("").expect("defaults")
    }
}

/// The fence's radius beyond the sample's, m (inside the domain's r + 0.05).
const FENCE_GAP: f64 = 0.04;

/// The freed sample rests when its grains' mean speed is below this, m/s ...
const REST_SPEED: f64 = 0.002;
/// ... after at least this long, s (the platen's spring-back has to show first).
const REST_AFTER: f64 = 0.02;

/// The scene and protocol of a tilting-plate test.
pub fn build(c: &Common, p: &TiltParams) -> Result<Built> {
    let d = super::experiment::particle_diameter(c, p.diameter);
    let mix = super::sizes::SizeMix::of(c.model, c.at(), d)?;
    check_params(p, d)?;
    soil_density(c.model)?;
    let r = 0.5 * p.sample_diameter;
    let area = std::f64::consts::PI * r * r;
    let loads = specimen::Loads {
        compaction: p.compaction_force / area,
        test: p.compaction_force / area,
    };
    let volume = area * p.sample_height;
    let (steps, count) = specimen::particles_for(c, &mix, volume, p.packing, loads, true)?;
    let parts = c.model.scene_parts(c.at(), true)?;
    let (z_fill, z_top) = specimen::mould_heights(p.sample_height, p.packing, d);
    let tilt_time =
        (p.max_angle - p.start_angle) / p.tilt_rate + p.start_angle / (4.0 * p.tilt_rate);
    let duration = 5.0 * p.max_phase_time + tilt_time + 0.5;
    // The sample slides at most a few diameters before the test stops: a domain r + 5 cm
    // wide holds it.
    let simulation = specimen::simulation(
        c,
        steps.prepare,
        duration,
        r + 0.05,
        z_top + 0.02,
        mix.min_diameter(),
    );
    let walls = rig_walls(r, z_top);
    let (ring, platen) = (
        WallId::find(&walls, "ring")?,
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
        protocol: Box::new(TiltProtocol {
            ring,
            platen,
            prep,
            phase: Phase::Prepare,
            p: p.clone(),
            d,
            bonds: 0,
            started: 0.0,
            angle: 0.0,
            g: 0.0,
            x0: 0.0,
            slide_angle: None,
            early: false,
        }),
    })
}

/// Refuses a sample the particles of diameter `d` (m) do not fit and values out of range.
fn check_params(p: &TiltParams, d: f64) -> Result<()> {
    specimen::check_fit("tilt", p.sample_diameter, p.sample_height, d)?;
    specimen::check_positive(
        "tilt",
        &[
            ("compaction_force", p.compaction_force),
            ("tilt_rate", p.tilt_rate),
            ("slide_speed", p.slide_speed),
            ("max_phase_time", p.max_phase_time),
        ],
    )?;
    if !(p.max_angle > 0.0 && p.max_angle < 90.0) {
        bail!(
            "tilt.max_angle = {} is out of range: allowed (0, 90) degrees",
            p.max_angle
        );
    }
    if !(p.start_angle >= 0.0 && p.start_angle < p.max_angle) {
        bail!(
            "tilt.start_angle = {} is out of range: allowed [0, max_angle = {}) degrees",
            p.start_angle,
            p.max_angle
        );
    }
    specimen::check_packing("tilt", p.packing)
}

/// The rig for a sample of radius `r` (m) with the platen at `z_top` (m): the plate (the
/// floor), the ring knife and the platen, both taken away once the bonds form, and a fence.
fn rig_walls(r: f64, z_top: f64) -> Vec<WallSection> {
    vec![
        scene::floor("plate"),
        scene::ring("ring", 0.0, z_top, r),
        scene::disc("platen", z_top, r + 0.02),
        // The grains no bond holds roll off down the plate as it tilts; the fence keeps them
        // in the domain, well clear of the sample.
        scene::ring("fence", 0.0, z_top + 0.02, r + FENCE_GAP),
    ]
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Prepare,
    Release,
    Tilt,
    Done,
}

struct TiltProtocol {
    /// The ring knife, removed once the bonds form.
    ring: WallId,
    /// Compacts the sample, then is removed with the ring.
    platen: WallId,
    prep: Preparation,
    phase: Phase,
    p: TiltParams,
    /// Particle diameter, m.
    d: f64,
    bonds: usize,
    /// When the current phase began, s.
    started: f64,
    /// The plate's angle now, degrees.
    angle: f64,
    /// |g|, m/s^2.
    g: f64,
    /// Where the sample was along the slope when the tilt began ([`median_x`]), m.
    x0: f64,
    /// The angle at which the protocol saw the sample slide, degrees.
    slide_angle: Option<f64>,
    /// It slid while the plate turned fast, before `start_angle`.
    early: bool,
}

/// The median of `x`; 0 when empty. A mean would move with the few unbonded grains that
/// roll away down the plate.
fn median(mut x: Vec<f64>) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let mid = x.len() / 2;
    *x.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Where the sample is along x (down the slope), m.
fn median_x(sim: &Simulation) -> f64 {
    median(sim.particles.position.iter().map(|p| p.x).collect())
}

/// How fast the sample moves down the slope, m/s.
fn median_vx(sim: &Simulation) -> f64 {
    median(sim.particles.velocity.iter().map(|v| v.x).collect())
}

impl TiltProtocol {
    /// The plate's angle at `t` s after the tilt began, degrees: `start_angle` at four times
    /// the rate, then `tilt_rate`.
    fn angle_at(&self, t: f64) -> f64 {
        let fast = 4.0 * self.p.tilt_rate;
        let t_start = self.p.start_angle / fast;
        if t <= t_start {
            fast * t
        } else {
            self.p.start_angle + self.p.tilt_rate * (t - t_start)
        }
    }

    /// The sample's travel down the slope since the tilt began, m.
    fn travel(&self, sim: &Simulation) -> f64 {
        median_x(sim) - self.x0
    }
}

impl Protocol for TiltProtocol {
    fn control(&mut self, sim: &mut Simulation) -> Result<Control> {
        // Gravity turns by 0.01 degrees a block at the speed of the moment: a smooth turn
        // to the sample, and blocks long enough that the protocol's own work stays small.
        let rate = if self.angle < self.p.start_angle {
            4.0 * self.p.tilt_rate
        } else {
            self.p.tilt_rate
        };
        let block = ((0.01 / rate / sim.dt).floor() as u64).max(1);
        match self.phase {
            Phase::Prepare => {
                if self.prep.advance(sim, "tilt")? {
                    self.bonds = self.prep.bond(sim)?;
                    if self.bonds == 0 {
                        bail!(
                            "tilt: no bonds formed after compaction (step {}): the particles do not touch",
                            sim.step
                        );
                    }
                    sim.set_wall_active(self.ring.index(), false);
                    sim.set_wall_active(self.platen.index(), false);
                    self.phase = Phase::Release;
                    self.started = sim.time;
                }
            }
            Phase::Release => {
                let since = sim.time - self.started;
                if since > REST_AFTER && specimen::mean_speed(sim) < REST_SPEED {
                    if specimen::top(sim) < 0.5 * self.p.sample_height {
                        bail!(
                            "tilt: the sample collapsed when the ring was lifted (height {:.1} mm, step {}): bonds too weak to stand",
                            specimen::top(sim) * 1e3,
                            sim.step
                        );
                    }
                    self.g = sim.gravity.length();
                    self.x0 = median_x(sim);
                    self.started = sim.time;
                    self.phase = Phase::Tilt;
                } else if since > self.p.max_phase_time {
                    bail!(
                        "tilt: the sample did not come to rest within max_phase_time = {} s after the ring was lifted (mean speed {:.4} m/s, step {})",
                        self.p.max_phase_time,
                        specimen::mean_speed(sim),
                        sim.step
                    );
                }
            }
            Phase::Tilt => {
                let speed = median_vx(sim);
                if speed >= self.p.slide_speed && self.slide_angle.is_none() {
                    self.slide_angle = Some(self.angle);
                    self.early = self.angle < self.p.start_angle;
                }
                // On to twice the threshold, so that the record (a sample every few
                // milliseconds) holds the crossing the reducer reads.
                if speed >= 2.0 * self.p.slide_speed {
                    self.phase = Phase::Done;
                    return Ok(Control::Done);
                }
                if self.angle >= self.p.max_angle {
                    self.phase = Phase::Done;
                    return Ok(Control::Done);
                }
                self.angle = self.angle_at(sim.time - self.started).min(self.p.max_angle);
                let theta = self.angle.to_radians();
                sim.gravity = DVec3::new(theta.sin(), 0.0, -theta.cos()) * self.g;
            }
            Phase::Done => return Ok(Control::Done),
        }
        Ok(Control::Step(block))
    }

    fn scalars(&self, sim: &Simulation) -> Vec<(String, f64)> {
        let (intact, broken) = sim.bond_counts();
        let mut out = vec![
            ("bonds_intact".to_string(), intact as f64),
            ("bonds_broken".to_string(), broken as f64),
        ];
        if matches!(self.phase, Phase::Tilt | Phase::Done) {
            out.push(("plate_angle".into(), self.angle));
            out.push(("slide".into(), self.travel(sim)));
            out.push(("slide_speed".into(), median_vx(sim)));
        }
        out
    }

    fn units(&self) -> Vec<(String, String)> {
        specimen::units(&[
            ("plate_angle", "degree"),
            ("slide", "m"),
            ("slide_speed", "m/s"),
            ("bonds_intact", "count"),
            ("bonds_broken", "count"),
        ])
    }

    fn metadata(&self) -> BTreeMap<String, String> {
        specimen::record(vec![
            ("type", "tilt".to_string()),
            ("diameter_m", self.p.sample_diameter.to_string()),
            ("height_m", self.p.sample_height.to_string()),
            ("tilt_rate_deg_per_s", self.p.tilt_rate.to_string()),
            ("slide_speed_m_per_s", self.p.slide_speed.to_string()),
            ("particle_diameter_m", self.d.to_string()),
        ])
    }

    fn phase(&self) -> String {
        match (self.phase, self.prep.phase) {
            (Phase::Prepare, Prep::Fill) => "filling".into(),
            (Phase::Prepare, Prep::Settle) => "settling".into(),
            (Phase::Prepare, _) => "compacting".into(),
            (Phase::Release, _) => "ring removed".into(),
            (Phase::Tilt, _) => format!("tilting, {:.1} deg", self.angle),
            (Phase::Done, _) => "done".into(),
        }
    }

    fn progress(&self, _sim: &Simulation) -> f64 {
        match self.phase {
            Phase::Prepare | Phase::Release => 0.0,
            Phase::Tilt => 0.3 + 0.7 * self.angle / self.p.max_angle,
            Phase::Done => 1.0,
        }
    }

    fn summary(&self, sim: &Simulation) -> serde_json::Value {
        let (intact, broken) = sim.bond_counts();
        let warning = match (self.phase, self.slide_angle) {
            (Phase::Done, None) => Some(format!(
                "the sample did not slide up to max_angle = {} degrees",
                self.p.max_angle
            )),
            (_, Some(a)) if self.early => Some(format!(
                "the sample slid at {a:.1} degrees, before start_angle = {}, while the plate turned at four times tilt_rate: lower start_angle",
                self.p.start_angle
            )),
            _ => None,
        };
        // The readings (`slide_angle_deg`, `static_friction`) are the reducer's, from the
        // recorded curve (tools/src/reduce/tilt.rs); this is where the protocol saw the slide.
        serde_json::json!({
            "seen_sliding_at_deg": self.slide_angle,
            "particles": sim.particles.len(),
            "bonds_formed": self.bonds,
            "bonds_intact": intact,
            "bonds_broken": broken,
            "warning": warning,
            "completed": self.phase == Phase::Done,
        })
    }
}
