//! `direct_shear`: the strain-controlled direct shear test (docs/experiments.md).
//!
//! A steel split box: a lower ring (fixed, with a bottom) and an upper ring of the specimen's
//! diameter (61.8 mm; area 3000 mm^2), each with a flange at the shear plane. Particles fill it loosely and settle; a platen
//! compacts them with the study's 12 N, bonds form, the platen servo then holds the normal
//! pressure, and the upper ring (with the platen riding on it) moves horizontally at
//! `shear_speed` until `shear_displacement` (5 mm). The shear force is the force of the
//! particles on the lower box (ring, bottom and flange) along the shear direction, averaged
//! over each 2 ms block; the channel `shear_force_drive` reads the same force where the
//! moving half (upper ring, flange, platen) pushes the soil, as a check. Loading is sped up
//! only while the inertial number I = (v / h) d sqrt(rho / sigma_n) stays below
//! `max_inertial_number`.

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

/// `[direct_shear]`: the test's parameters (SI units).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShearParams {
    /// Inner diameter of the box, m (61.8 mm: 3000 mm^2).
    #[serde(default = "default_box")]
    pub box_diameter: f64,
    /// Specimen height, m (20 mm); the particle count fills it at `packing`.
    #[serde(default = "default_height")]
    pub height: f64,
    /// Particle diameter, m (2 mm; coarse preset 4 mm).
    pub diameter: Option<f64>,
    /// Solid fraction of the compacted specimen (sets the particle count).
    #[serde(default = "default_packing")]
    pub packing: f64,
    /// Normal pressure during shear, Pa (table 12: 0.1 MPa); it also sets the loaded time
    /// step (`specimen::loaded_steps`).
    #[serde(default = "default_pressure")]
    pub normal_pressure: f64,
    /// Compaction force before bonding, N (the study: 12 N).
    #[serde(default = "default_compaction")]
    pub compaction_force: f64,
    /// Shear displacement, m (5 mm).
    #[serde(default = "default_displacement")]
    pub shear_displacement: f64,
    /// Shear speed, m/s; default: the speed at half of `max_inertial_number`.
    pub shear_speed: Option<f64>,
    #[serde(default = "default_inertial")]
    pub max_inertial_number: f64,
    /// Longest any preparation phase may take, s.
    #[serde(default = "default_phase_time")]
    pub max_phase_time: f64,
    /// Whether bonds form after compaction (the study's firm soil, its bonds from the
    /// model's `[bond]`). `false` shears the compacted specimen without bonds, as a
    /// remoulded soil is sheared (ASTM D3080): its strength is then the contacts' own
    /// friction, rolling resistance and adhesion, which the bonds otherwise hide.
    #[serde(default = "default_bonded")]
    pub bonded: bool,
}

fn default_box() -> f64 {
    0.0618
}

/// The shear plane of the box at its default diameter, m^2 (the study's 3000 mm^2).
pub fn default_shear_area() -> f64 {
    std::f64::consts::PI * default_box().powi(2) / 4.0
}
fn default_height() -> f64 {
    0.020
}
fn default_packing() -> f64 {
    0.55
}
fn default_pressure() -> f64 {
    1.0e5
}
fn default_compaction() -> f64 {
    12.0
}
fn default_displacement() -> f64 {
    0.005
}
fn default_inertial() -> f64 {
    1.0e-3
}
fn default_phase_time() -> f64 {
    2.0
}
fn default_bonded() -> bool {
    true
}

impl Default for ShearParams {
    fn default() -> Self {
        toml::from_str("").expect("defaults")
    }
}

/// The scene and protocol of a direct shear test.
pub fn build(c: &Common, p: &ShearParams) -> Result<Built> {
    let d = super::experiment::particle_diameter(c, p.diameter);
    let mix = super::sizes::SizeMix::of(c.model, c.at(), d)?;
    check_params(p, d)?;
    let rho = soil_density(c.model)?;
    check_pressure(c, p)?;
    let area = std::f64::consts::PI * p.box_diameter.powi(2) / 4.0;
    let speed = shear_speed(p, d, rho)?;
    let loads = specimen::Loads {
        compaction: p.compaction_force / area,
        test: p.normal_pressure,
    };
    let (steps, count) =
        specimen::particles_for(c, &mix, area * p.height, p.packing, loads, p.bonded)?;
    let parts = c.model.scene_parts(c.at(), true)?;
    let r = 0.5 * p.box_diameter;
    let (z_fill, z_top) = specimen::mould_heights(p.height, p.packing, d);
    let duration = 4.0 * p.max_phase_time + p.shear_displacement / speed + 0.5;
    let simulation = specimen::simulation(
        c,
        steps.prepare,
        duration,
        flange_radius(p, d) + 0.02,
        z_top + 0.02,
        mix.min_diameter(),
    );
    let walls = box_walls(p, d, z_top);
    let box_walls = BoxWalls::find(&walls)?;
    let fill = specimen::fill(count, &mix, r - 0.6 * d, 0.6 * d, z_fill);
    let scene = scene::scene(parts, simulation, walls, vec![fill]);
    let prep = Preparation::new(
        box_walls.platen,
        p.compaction_force,
        p.max_phase_time,
        z_top,
        d,
        steps.bonded,
    );
    Ok(Built {
        scene: scene::to_value(&scene)?,
        bonded_dt: p.bonded.then_some(steps.bonded),
        protocol: Box::new(ShearProtocol::new(p, box_walls, prep, area, speed, d, rho)),
    })
}

/// Refuses a specimen the particles of diameter `d` (m) do not fit and values out of range.
fn check_params(p: &ShearParams, d: f64) -> Result<()> {
    specimen::check_fit("direct_shear", p.box_diameter, p.height, d)?;
    specimen::check_positive(
        "direct_shear",
        &[
            ("normal_pressure", p.normal_pressure),
            ("compaction_force", p.compaction_force),
            ("shear_displacement", p.shear_displacement),
            ("max_inertial_number", p.max_inertial_number),
            ("max_phase_time", p.max_phase_time),
        ],
    )?;
    specimen::check_packing("direct_shear", p.packing)
}

/// Refuses a normal pressure the model's soil cannot carry.
fn check_pressure(c: &Common, p: &ShearParams) -> Result<()> {
    let e = super::experiment::soil_modulus(c.model)?;
    // Hertz overlaps grow as (p/E)^(2/3): at p = 2 % of E they pass 7 % of the radius, where
    // the contact law stops being valid and the servo would chase a specimen it crushes.
    if p.normal_pressure > 0.02 * e {
        bail!(
            "direct_shear.normal_pressure = {} Pa is beyond what the particles can carry: the servo cannot reach it with soil of E = {e:.3e} Pa (allowed up to 2 % of E, {:.3e} Pa)",
            p.normal_pressure,
            0.02 * e
        );
    }
    Ok(())
}

/// The shear speed, m/s, for particles of diameter `d` (m) and density `rho` (kg/m^3): the
/// one given, or the speed at half of `max_inertial_number`; refused when the test would
/// not be quasi-static.
fn shear_speed(p: &ShearParams, d: f64, rho: f64) -> Result<f64> {
    let i_auto = |v: f64| specimen::inertial_number(v / p.height, d, rho, p.normal_pressure);
    let speed = match p.shear_speed {
        Some(v) if v > 0.0 && v.is_finite() => v,
        Some(v) => bail!("direct_shear.shear_speed = {v} is out of range: allowed (0, inf) m/s"),
        // I is linear in v: the speed at half the limit.
        None => 0.5 * p.max_inertial_number / i_auto(1.0),
    };
    if i_auto(speed) > p.max_inertial_number {
        bail!(
            "direct_shear.shear_speed = {speed} m/s gives an inertial number of {:.2e}, above max_inertial_number = {:.1e}: the test would not be quasi-static",
            i_auto(speed),
            p.max_inertial_number
        );
    }
    Ok(speed)
}

/// The split box for particles of diameter `d` (m), its platen at `z_top` (m): the lower
/// ring (fixed) on its bottom, the upper ring from the shear plane (half the specimen's
/// height) up to the platen, and a flange on each ring at the shear plane.
///
/// The flanges are the lower ring's top face and the upper ring's bottom face, as wide as
/// the shear displacement plus two grains: once the rings are offset, soil in the upper ring
/// that overhangs the lower one rests on the lower flange, and soil in the lower ring that
/// the upper ring has uncovered is held down by the upper flange, as in a real box. They
/// start half a grain outside the rings: a grain cannot pass that gap, and grains in the box
/// do not touch four walls at once where the rings meet (four wall springs on one grain at
/// the time step of one made the 0.34 MPa specimen blow up under load).
fn box_walls(p: &ShearParams, d: f64, z_top: f64) -> Vec<WallSection> {
    let r = 0.5 * p.box_diameter;
    let z_mid = 0.5 * p.height;
    let flange_outer = flange_radius(p, d);
    vec![
        scene::ring("lower_box", 0.0, z_mid, r),
        scene::disc("bottom", 0.0, r),
        scene::ring("upper_box", z_mid, z_top, r),
        scene::disc("platen", z_top, r - 0.1 * d),
        scene::flange("lower_flange", z_mid, r + 0.5 * d, flange_outer),
        scene::flange("upper_flange", z_mid, r + 0.5 * d, flange_outer),
    ]
}

/// The flanges' outer radius for particles of diameter `d`, m: the box's radius plus the
/// shear displacement and two grains.
fn flange_radius(p: &ShearParams, d: f64) -> f64 {
    0.5 * p.box_diameter + p.shear_displacement + 2.0 * d
}

/// The walls of the split box the protocol moves and weighs.
#[derive(Debug, Clone, Copy)]
struct BoxWalls {
    lower: WallId,
    bottom: WallId,
    upper: WallId,
    platen: WallId,
    lower_flange: WallId,
    upper_flange: WallId,
}

impl BoxWalls {
    /// Finds them by name among the walls of [`box_walls`].
    fn find(walls: &[WallSection]) -> Result<BoxWalls> {
        let find = |name| WallId::find(walls, name);
        Ok(BoxWalls {
            lower: find("lower_box")?,
            bottom: find("bottom")?,
            upper: find("upper_box")?,
            platen: find("platen")?,
            lower_flange: find("lower_flange")?,
            upper_flange: find("upper_flange")?,
        })
    }

    /// The half that moves: the upper ring, its flange and the platen riding on it.
    fn moving(&self) -> [WallId; 3] {
        [self.upper, self.upper_flange, self.platen]
    }
}

/// Proportional gain of the platen servo while shearing, (m/s) per unit relative force
/// error: v = SERVO_GAIN (F_target - F) / F_target, at most 0.02 m/s. A proportional servo
/// trails a specimen that contracts at v_z by a relative force error of v_z / SERVO_GAIN:
/// the study's 2 mm specimen contracts at 7-10 % of the shear speed (0.043 m/s), and at a
/// gain of 0.02 it carried 85-90 % of its normal load while shearing (4 mm: 95 %). At 0.3
/// it carries 98.6 % (4 mm: 99.6 %) with no oscillation of the block means.
const SERVO_GAIN: f64 = 0.3;

/// Fraction of the last block's mean force error added to the servo's target each block
/// (2 ms; an integral time of 20 ms). It removes the lag [`SERVO_GAIN`] leaves: the 2 mm
/// specimen then carries 100.1 % of its load on average while shearing, every block mean
/// within 2.5 %. Behind the slow 0.02 gain an integral of 0.3 rang with a period of about
/// 0.15 s (block means 290-310 N); behind 0.3 it does not.
const SERVO_INTEGRAL: f64 = 0.1;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Prepare,
    Load,
    Shear,
    Done,
}

struct ShearProtocol {
    walls: BoxWalls,
    prep: Preparation,
    phase: Phase,
    p: ShearParams,
    area: f64,
    speed: f64,
    d: f64,
    rho: f64,
    bonds: usize,
    started: f64,
    in_band_since: Option<f64>,
    /// Integral correction added to the platen servo's target force while shearing, N.
    normal_bias: f64,
    /// The largest |normal - target| / target block mean past the first 10 % of the
    /// displacement.
    max_normal_deviation: f64,
    /// Upper box offset at the start of shearing, m.
    x0: f64,
    /// (displacement, force) at the peak so far.
    peak: (f64, f64),
    max_i: f64,
    /// The largest |box - drive| block mean past the first 10 % of the displacement, N.
    max_gap: f64,
    /// Mean forces on the lower box and on the platen since the last control call: the
    /// block just run (see [`specimen::MeanForce`]).
    box_force: specimen::MeanForce,
    /// The same for the moving half (upper ring, its flange and the platen riding on it).
    drive_force: specimen::MeanForce,
    platen_force: specimen::MeanForce,
}

impl ShearProtocol {
    /// A test of `p` in the box `walls`, prepared by `prep`, on the shear plane's `area`
    /// (m^2) at `speed` (m/s), with particles of diameter `d` (m) and density `rho` (kg/m^3).
    fn new(
        p: &ShearParams,
        walls: BoxWalls,
        prep: Preparation,
        area: f64,
        speed: f64,
        d: f64,
        rho: f64,
    ) -> ShearProtocol {
        ShearProtocol {
            walls,
            prep,
            phase: Phase::Prepare,
            p: p.clone(),
            area,
            speed,
            d,
            rho,
            bonds: 0,
            started: 0.0,
            in_band_since: None,
            normal_bias: 0.0,
            max_normal_deviation: 0.0,
            x0: 0.0,
            peak: (0.0, 0.0),
            max_i: 0.0,
            max_gap: 0.0,
            box_force: specimen::MeanForce::new(&[walls.lower, walls.bottom, walls.lower_flange]),
            drive_force: specimen::MeanForce::new(&walls.moving()),
            platen_force: specimen::MeanForce::new(&[walls.platen]),
        }
    }

    fn displacement(&self, sim: &Simulation) -> f64 {
        self.walls.upper.of(sim).offset.x - self.x0
    }

    /// Shear force on the lower box over the last block, N.
    fn shear_force(&self, sim: &Simulation) -> f64 {
        self.box_force.mean(sim).x
    }

    /// The force the moving half (upper ring, flange, platen) exerts on the soil along the
    /// shear direction over the last block, N: the same force as [`Self::shear_force`] read at
    /// the other end of the specimen. The two differ by the rate of change of the soil's
    /// momentum, so a gap between them means the test is not quasi-static.
    fn drive_force(&self, sim: &Simulation) -> f64 {
        -self.drive_force.mean(sim).x
    }

    /// Normal force on the platen over the last block, N.
    fn normal_force(&self, sim: &Simulation) -> f64 {
        self.platen_force.mean(sim).z
    }
}

impl Protocol for ShearProtocol {
    fn control(&mut self, sim: &mut Simulation) -> Result<Control> {
        let block = ((0.002 / sim.dt).ceil() as u64).max(1);
        // Decisions use the forces averaged over the block just run; then a new block starts.
        let (fx, fz) = (self.shear_force(sim), self.normal_force(sim));
        let drive = self.drive_force(sim);
        self.box_force.mark(sim);
        self.drive_force.mark(sim);
        self.platen_force.mark(sim);
        match self.phase {
            Phase::Prepare => {
                if self.prep.advance(sim, "direct_shear")? {
                    self.bonds = if self.p.bonded {
                        self.prep.bond(sim)?
                    } else {
                        self.prep.unbonded(sim)?
                    };
                    if self.bonds == 0 && self.p.bonded {
                        bail!(
                            "direct_shear: no bonds formed after compaction (step {}): the particles do not touch",
                            sim.step
                        );
                    }
                    let target = self.p.normal_pressure * self.area;
                    self.walls.platen.of_mut(sim).motion = specimen::press(target, 0.05);
                    self.phase = Phase::Load;
                    self.started = sim.time;
                }
            }
            Phase::Load => {
                let target = self.p.normal_pressure * self.area;
                let f = fz;
                // 3 %: under a constant platen speed the specimen creeps (grains rearrange),
                // so the servo approaches its target slowly; the reducer reports the normal
                // stress actually carried during shearing.
                let in_band = (f - target).abs() < 0.03 * target;
                match (in_band, self.in_band_since) {
                    (true, None) => self.in_band_since = Some(sim.time),
                    (false, _) => self.in_band_since = None,
                    _ => {}
                }
                if self.in_band_since.is_some_and(|t0| sim.time - t0 > 0.01) {
                    self.phase = Phase::Shear;
                    self.x0 = self.walls.upper.of(sim).offset.x;
                    let v = DVec3::new(self.speed, 0.0, 0.0);
                    self.walls.upper.of_mut(sim).motion = Motion::Velocity(v);
                    self.walls.upper_flange.of_mut(sim).motion = Motion::Velocity(v);
                    self.walls.platen.of_mut(sim).motion = Motion::ServoCarried {
                        axis: DVec3::new(0.0, 0.0, -1.0),
                        target_force: target,
                        gain: SERVO_GAIN / target,
                        max_speed: 0.02,
                        velocity: v,
                    };
                } else if sim.time - self.started > self.p.max_phase_time {
                    bail!(
                        "direct_shear: the normal pressure {} Pa ({:.1} N) was not reached: the platen carries {:.1} N after {:.2} s (step {}); the servo cannot reach it with this specimen",
                        self.p.normal_pressure,
                        target,
                        f,
                        self.p.max_phase_time,
                        sim.step
                    );
                }
            }
            Phase::Shear => {
                let x = self.displacement(sim);
                let target = self.p.normal_pressure * self.area;
                // The integral part of the servo, on block means: the per-step force swings
                // as contacts come and go, its block mean does not.
                self.normal_bias = (self.normal_bias + SERVO_INTEGRAL * (target - fz))
                    .clamp(-0.5 * target, 0.5 * target);
                if let Motion::ServoCarried { target_force, .. } =
                    &mut self.walls.platen.of_mut(sim).motion
                {
                    *target_force = target + self.normal_bias;
                }
                if fx > self.peak.1 {
                    self.peak = (x, fx);
                }
                let sigma = fz.max(0.0) / self.area;
                let i =
                    specimen::inertial_number(self.speed / self.p.height, self.d, self.rho, sigma);
                if x > 0.1 * self.p.shear_displacement {
                    self.max_i = self.max_i.max(i);
                    self.max_normal_deviation =
                        self.max_normal_deviation.max((fz - target).abs() / target);
                    self.max_gap = self.max_gap.max((fx - drive).abs());
                }
                if x >= self.p.shear_displacement {
                    for wall in self.walls.moving() {
                        wall.of_mut(sim).motion = Motion::Fixed;
                    }
                    self.phase = Phase::Done;
                    return Ok(Control::Done);
                }
                let left = ((self.p.shear_displacement - x) / (self.speed * sim.dt)).ceil() as u64;
                return Ok(Control::Step(block.min(left.max(1))));
            }
            Phase::Done => return Ok(Control::Done),
        }
        Ok(Control::Step(block))
    }

    fn scalars(&self, sim: &Simulation) -> Vec<(String, f64)> {
        let (intact, broken) = sim.bond_counts();
        let mut out = vec![
            ("normal_force".to_string(), self.normal_force(sim)),
            ("bonds_intact".to_string(), intact as f64),
            ("bonds_broken".to_string(), broken as f64),
        ];
        // The test's curve: written only while shearing, so that a reducer reads the test,
        // not the preparation.
        if matches!(self.phase, Phase::Shear | Phase::Done) {
            let sigma = self.normal_force(sim).max(0.0) / self.area;
            out.push(("shear_displacement".into(), self.displacement(sim)));
            out.push(("shear_force".into(), self.shear_force(sim)));
            out.push(("shear_force_drive".into(), self.drive_force(sim)));
            out.push((
                "inertial_number".into(),
                specimen::inertial_number(self.speed / self.p.height, self.d, self.rho, sigma),
            ));
        }
        out
    }

    fn units(&self) -> Vec<(String, String)> {
        specimen::units(&[
            ("shear_displacement", "m"),
            ("shear_force", "N"),
            ("shear_force_drive", "N"),
            ("normal_force", "N"),
            ("inertial_number", "-"),
            ("bonds_intact", "count"),
            ("bonds_broken", "count"),
        ])
    }

    fn metadata(&self) -> BTreeMap<String, String> {
        specimen::record(vec![
            ("type", "direct_shear".to_string()),
            ("diameter_m", self.p.box_diameter.to_string()),
            ("area_m2", self.area.to_string()),
            ("height_m", self.p.height.to_string()),
            ("normal_pressure_pa", self.p.normal_pressure.to_string()),
            ("shear_speed_m_per_s", self.speed.to_string()),
            ("particle_diameter_m", self.d.to_string()),
        ])
    }

    fn phase(&self) -> String {
        match (self.phase, self.prep.phase) {
            (Phase::Prepare, Prep::Fill) => "filling".into(),
            (Phase::Prepare, Prep::Settle) => "settling".into(),
            (Phase::Prepare, _) => "compacting".into(),
            (Phase::Load, _) => "normal load".into(),
            (Phase::Shear, _) => "shearing".into(),
            (Phase::Done, _) => "done".into(),
        }
    }

    fn progress(&self, sim: &Simulation) -> f64 {
        match self.phase {
            Phase::Prepare => 0.0,
            Phase::Load => 0.3,
            Phase::Shear => 0.3 + 0.7 * self.displacement(sim) / self.p.shear_displacement,
            Phase::Done => 1.0,
        }
    }

    fn summary(&self, sim: &Simulation) -> serde_json::Value {
        let (intact, broken) = sim.bond_counts();
        serde_json::json!({
            "peak_shear_force_n": self.peak.1,
            "peak_at_displacement_m": self.peak.0,
            "normal_pressure_pa": self.p.normal_pressure,
            "shear_speed_m_per_s": self.speed,
            "max_inertial_number": self.max_i,
            "max_force_gap_n": self.max_gap,
            "max_normal_deviation": self.max_normal_deviation,
            "particles": sim.particles.len(),
            "bonds_formed": self.bonds,
            "time_step_bonded_s": self.prep.bonded_dt,
            "bonds_intact": intact,
            "bonds_broken": broken,
            "completed": self.phase == Phase::Done,
        })
    }
}
