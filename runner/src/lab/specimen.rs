//! What the direct shear and UCS tests share: filling a cylindrical mould, settling,
//! compacting with a servo platen, forming bonds, and the inertial number.

use super::experiment::{Common, rayleigh_time, soil_density, soil_modulus, soil_poisson_ratio};
use super::scene::{self, WallId};
use super::sizes::SizeMix;
use crate::config::{FactorySection, SimulationSection};
use anyhow::{Result, bail};
use tilth_kernel::DVec3;
use tilth_kernel::sim::Simulation;
use tilth_kernel::timestep::{LOADED_COORDINATION, LoadedPacking, loaded_packing_step};
use tilth_kernel::wall::Motion;

/// Mean particle speed, m/s.
pub fn mean_speed(sim: &Simulation) -> f64 {
    let p = &sim.particles;
    if p.is_empty() {
        return 0.0;
    }
    p.velocity.iter().map(|v| v.length()).sum::<f64>() / p.len() as f64
}

/// The highest particle top, m (0 without particles).
pub fn top(sim: &Simulation) -> f64 {
    let p = &sim.particles;
    (0..p.len())
        .map(|k| p.position[k].z + p.radius[k])
        .fold(0.0, f64::max)
}

/// The mean force on a set of walls since a mark, from their impulses (N): the force on a
/// wall swings from step to step as contacts open and close, and a sample taken every few
/// thousand steps can land anywhere in that swing.
#[derive(Debug, Clone)]
pub struct MeanForce {
    walls: Vec<WallId>,
    impulse: DVec3,
    time: f64,
}

impl MeanForce {
    /// Averages the total force on `walls` from the start of the run (zero impulse at t = 0).
    pub fn new(walls: &[WallId]) -> MeanForce {
        MeanForce {
            walls: walls.to_vec(),
            impulse: DVec3::ZERO,
            time: 0.0,
        }
    }

    /// Starts a new interval now.
    pub fn mark(&mut self, sim: &Simulation) {
        self.impulse = self.walls.iter().map(|w| w.of(sim).impulse).sum();
        self.time = sim.time;
    }

    /// The mean total force since the mark; the current force if no time has passed.
    pub fn mean(&self, sim: &Simulation) -> DVec3 {
        let span = sim.time - self.time;
        if span <= 0.0 {
            return self.walls.iter().map(|w| w.of(sim).force).sum();
        }
        let now: DVec3 = self.walls.iter().map(|w| w.of(sim).impulse).sum();
        (now - self.impulse) / span
    }
}

/// The inertial number I = gamma_dot d sqrt(rho / p) (GDR MiDi 2004; docs/physics.md):
/// below about 1e-3 the loading is quasi-static.
pub fn inertial_number(strain_rate: f64, d: f64, rho: f64, pressure: f64) -> f64 {
    if pressure <= 0.0 {
        return f64::INFINITY;
    }
    strain_rate * d * (rho / pressure).sqrt()
}

/// A servo that drives a platen down (-z) to `force` N, at most `max_speed` m/s, full speed
/// when the force is missing entirely.
pub fn press(force: f64, max_speed: f64) -> Motion {
    Motion::Servo {
        axis: DVec3::new(0.0, 0.0, -1.0),
        target_force: force,
        // Full speed until within 2/3 of the target; higher gains set the platen oscillating.
        gain: 1.5 * max_speed / force,
        max_speed,
    }
}

/// Fraction of a bond's oscillation time scale sqrt(m / (S_n A)) the time step may be. The
/// Rayleigh step does not see bonds; each particle carries several in parallel, with their
/// bending and twisting springs, and at 0.2 of that scale the coarse UCS test gained energy
/// until it blew up while at 0.07 it ran clean.
pub const BOND_DT_FRACTION: f64 = 0.08;

/// The time steps of a bonded specimen, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Steps {
    /// Filling, settling and compacting, before any bond: `dt_fraction` of the Rayleigh
    /// time, at most the step a packing stands under the compaction pressure
    /// ([`loaded_steps`]).
    pub prepare: f64,
    /// From the moment bonds form (or, in a test without bonds, from the end of the
    /// compaction): the smaller of that, the step a packing stands under the test's
    /// pressure, and, if bonds form, [`BOND_DT_FRACTION`] of the stiffest bond's time scale.
    /// Stiff bonds need a step ten or more times shorter than the contacts; preparing at
    /// the bonds' step spent most of a run on unbonded grains.
    pub bonded: f64,
}

/// Pressures a specimen is stepped for, Pa.
#[derive(Debug, Clone, Copy)]
pub struct Loads {
    /// The compaction platen's force over the specimen's area.
    pub compaction: f64,
    /// The test's stress scale (the shear box's normal pressure, the UCS reference stress).
    pub test: f64,
}

/// The time steps and particle count for a specimen of `volume` (m^3) at `packing`. A
/// `[simulation] dt` given in the file is used throughout.
///
/// A step chosen from the Rayleigh time alone lost the grains' friction under load: the
/// 2 mm shear specimen at 20 % of it (bond-limited at 14 % for 4 mm grains, fine there) read
/// 49 N at a solid fraction of 0.735 with bonds that broke at once, frictionless grains 43 N,
/// and the same specimen at 10 % 111 N at 0.57 (docs/li2022-statistics.md, "The shear box
/// checked"); the kernel's test tests/tests/loaded_packing.rs shows it on 600 grains.
/// `bonds`: whether bonds will form (their stiffness then limits the step).
pub fn particles_for(
    c: &Common,
    mix: &SizeMix,
    volume: f64,
    packing: f64,
    loads: Loads,
    bonds: bool,
) -> Result<(Steps, usize)> {
    let d = mix.min_diameter();
    let steps = match c.sim.dt {
        Some(dt) => Steps {
            prepare: dt,
            bonded: dt,
        },
        None => {
            let (compaction, test) = loaded_steps(c, d, packing, loads)?;
            let prepare = (c.sim.dt_fraction * rayleigh_time(c.model, d)?).min(compaction);
            let loaded = prepare.min(test);
            Steps {
                prepare,
                bonded: if bonds {
                    loaded.min(bond_time_scale(c, d)? * BOND_DT_FRACTION)
                } else {
                    loaded
                },
            }
        }
    };
    Ok((steps, mix.count(packing * volume)))
}

/// The smallest restitution coefficient of the model's material pairs at these conditions
/// (1 where a pair has none: undamped), for [`loaded_steps`].
fn soil_restitution(c: &Common) -> Result<f64> {
    let parts = c.model.scene_parts(c.at(), true)?;
    Ok(parts
        .pairs
        .iter()
        .filter_map(|pair| pair.params.get("restitution").copied())
        .fold(1.0, f64::min))
}

/// The longest steps a packing of the model's soil (grains of diameter `d`, solid fraction
/// `packing`) stands under the compaction and the test pressure of `loads`:
/// [`loaded_packing_step`] with [`LOADED_COORDINATION`] contacts a grain and the model's
/// lowest restitution.
pub fn loaded_steps(c: &Common, d: f64, packing: f64, loads: Loads) -> Result<(f64, f64)> {
    let (rho, e) = (soil_density(c.model)?, soil_modulus(c.model)?);
    let (nu, restitution) = (soil_poisson_ratio(c.model), soil_restitution(c)?);
    let step = |pressure| {
        loaded_packing_step(&LoadedPacking {
            radius: 0.5 * d,
            density: rho,
            youngs_modulus: e,
            poisson_ratio: nu,
            restitution,
            pressure,
            coordination: LOADED_COORDINATION,
            solid_fraction: packing,
        })
    };
    Ok((step(loads.compaction), step(loads.test)))
}

/// Refuses any of `values` that is not a finite number above 0 (`section.key` in messages).
pub fn check_positive(section: &str, values: &[(&str, f64)]) -> Result<()> {
    for (k, v) in values {
        if !(*v > 0.0 && v.is_finite()) {
            bail!("{section}.{k} = {v} is out of range: allowed (0, inf)");
        }
    }
    Ok(())
}

/// Refuses a solid fraction no sphere packing has.
pub fn check_packing(section: &str, packing: f64) -> Result<()> {
    if !(packing > 0.1 && packing < 0.74) {
        bail!("{section}.packing = {packing} is out of range: allowed (0.1, 0.74)");
    }
    Ok(())
}

/// (name, unit) pairs as the protocol reports them.
pub fn units(list: &[(&str, &str)]) -> Vec<(String, String)> {
    list.iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect()
}

/// A metadata record from (key, value) pairs.
pub fn record(list: Vec<(&str, String)>) -> std::collections::BTreeMap<String, String> {
    list.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

/// Checks shared by both tests (`section` names the TOML table in messages).
pub fn check_fit(section: &str, box_diameter: f64, height: f64, d: f64) -> Result<()> {
    if !(d > 0.0 && box_diameter > 0.0 && height > 0.0) {
        bail!("{section}: diameters and heights must be > 0 m");
    }
    if box_diameter < 8.0 * d || height < 4.0 * d {
        bail!(
            "{section}: the specimen ({:.1} x {:.1} mm) does not fit particles of {:.1} mm: it needs \
             at least 8 particle diameters across and 4 in height",
            box_diameter * 1e3,
            height * 1e3,
            d * 1e3
        );
    }
    Ok(())
}

/// The top of a mould's loose fill and the compaction platen's starting height, m, for a
/// specimen `height` m high at solid fraction `packing` of grains `d` m across: loose
/// particles need about twice the specimen's height (2.4 times at packing 0.55, more in
/// proportion at a denser one); the platen starts two diameters above that.
pub fn mould_heights(height: f64, packing: f64, d: f64) -> (f64, f64) {
    let z_fill = 2.4 * height / (packing / 0.55);
    (z_fill, z_fill + 2.0 * d)
}

/// A factory filling a cylinder of `radius` between `z0` and `z1` with `count` particles of
/// the size mix `mix`, all within a few milliseconds.
pub fn fill(count: usize, mix: &SizeMix, radius: f64, z0: f64, z1: f64) -> FactorySection {
    let region = scene::cylinder_region(radius, z0, z1);
    scene::soil_factory(region, count, 2.0e5, [0.0; 3], mix)
}

/// The `[simulation]` of a specimen test: a domain `half` wide each way of the axis and up to
/// `top`, the skin `skin_fraction` (default 0.2) of the smallest diameter `d`.
pub fn simulation(
    c: &Common,
    dt: f64,
    duration: f64,
    half: f64,
    top: f64,
    d: f64,
) -> SimulationSection {
    let skin = c.sim.skin_fraction.unwrap_or(0.2) * d;
    scene::simulation(c, dt, duration, skin, scene::domain(half, -0.01, top))
}

/// Phases of preparing a specimen, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prep {
    Fill,
    Settle,
    Compact,
    Done,
}

/// Fill -> settle -> compact to `force` with platen `k`. Returns true when the specimen is
/// compacted (force within 5 % for `hold` s and particles nearly at rest).
pub struct Preparation {
    pub phase: Prep,
    pub platen: WallId,
    pub force: f64,
    pub started: f64,
    pub in_band_since: Option<f64>,
    pub max_phase_time: f64,
    /// The platen's initial height (its shape's z), m.
    pub platen_z: f64,
    /// Particle diameter, m.
    pub diameter: f64,
    /// The time step from the moment bonds form, s.
    pub bonded_dt: f64,
}

impl Preparation {
    /// Preparation with platen wall `platen` (its shape at height `platen_z`, m) compacting
    /// particles of diameter `diameter` (m) to `force` (N), each phase within `max_phase_time` s.
    pub fn new(
        platen: WallId,
        force: f64,
        max_phase_time: f64,
        platen_z: f64,
        diameter: f64,
        bonded_dt: f64,
    ) -> Self {
        Preparation {
            bonded_dt,
            phase: Prep::Fill,
            platen,
            force,
            started: 0.0,
            in_band_since: None,
            max_phase_time,
            platen_z,
            diameter,
        }
    }

    /// Bonds the prepared specimen: switches to the bonded time step first (so that the
    /// kernel's bond step check sees the step the bonds will run at), then forms the bonds.
    /// Returns how many formed.
    pub fn bond(&self, sim: &mut Simulation) -> Result<usize> {
        sim.set_dt(self.bonded_dt)?;
        Ok(sim.form_bonds())
    }

    /// Ends the preparation of a specimen without bonds: switches to the step of the loaded
    /// specimen. Returns 0, the bonds formed.
    pub fn unbonded(&self, sim: &mut Simulation) -> Result<usize> {
        sim.set_dt(self.bonded_dt)?;
        Ok(0)
    }

    /// Advances the preparation; errors when a phase cannot finish.
    pub fn advance(&mut self, sim: &mut Simulation, section: &str) -> Result<bool> {
        match self.phase {
            Prep::Fill => {
                let made: usize = sim.factories.iter().map(|f| f.inserted).sum();
                let wanted: usize = sim.factories.iter().map(|f| f.spec.count).sum();
                if made >= wanted {
                    self.phase = Prep::Settle;
                    self.started = sim.time;
                } else if sim.time - self.started > self.max_phase_time {
                    if made == 0 {
                        bail!(
                            "{section}: no particles were generated in {:.2} s: the fill region is too small for the particles",
                            self.max_phase_time
                        );
                    }
                    bail!(
                        "{section}: only {made} of {wanted} particles fit in the mould after {:.2} s; lower packing or enlarge the mould",
                        self.max_phase_time
                    );
                }
            }
            Prep::Settle => {
                if (mean_speed(sim) < 0.02 && sim.time - self.started > 0.05)
                    || sim.time - self.started > self.max_phase_time
                {
                    self.phase = Prep::Compact;
                    self.started = sim.time;
                    // Nothing lies between the platen and the loose fill: bring it down to
                    // half a diameter above the highest particle at once instead of driving it.
                    let offset = top(sim) + 0.5 * self.diameter - self.platen_z;
                    let platen = self.platen.of_mut(sim);
                    if offset < platen.offset.z {
                        platen.offset.z = offset;
                    }
                    platen.motion = press(self.force, 0.05);
                }
            }
            Prep::Compact => {
                let f = self.platen.of(sim).force.z;
                let in_band = (f - self.force).abs() < 0.05 * self.force;
                match (in_band, self.in_band_since) {
                    (true, None) => self.in_band_since = Some(sim.time),
                    (false, _) => self.in_band_since = None,
                    _ => {}
                }
                if self.in_band_since.is_some_and(|t0| sim.time - t0 > 0.02) {
                    self.phase = Prep::Done;
                    return Ok(true);
                }
                if sim.time - self.started > self.max_phase_time {
                    bail!(
                        "{section}: the platen reached {:.2} N of the {:.2} N compaction force after {:.2} s (step {}): the servo cannot reach it",
                        f,
                        self.force,
                        self.max_phase_time,
                        sim.step
                    );
                }
            }
            Prep::Done => return Ok(true),
        }
        Ok(false)
    }
}

/// sqrt(m / (S A)) of a bond between two particles of diameter `d` with the model's stiffest
/// bond spring (s): S the larger of the normal and shear stiffness per area, since either
/// spring oscillates on that time scale.
pub fn bond_time_scale(c: &Common, d: f64) -> Result<f64> {
    let parts = c.model.scene_parts(c.at(), true)?;
    let mut k_max: f64 = 0.0;
    for pair in &parts.pairs {
        let num = |k: &str| pair.params.get(k).copied();
        let stiffest = ["normal_stiffness_per_area", "shear_stiffness_per_area"]
            .into_iter()
            .filter_map(num)
            .fold(None, |a: Option<f64>, s| Some(a.map_or(s, |a| a.max(s))));
        if let Some(s) = stiffest {
            let rb = 0.5 * d * num("bond_radius_ratio").unwrap_or(1.0);
            k_max = k_max.max(s * std::f64::consts::PI * rb * rb);
        }
    }
    let rho = super::experiment::soil_density(c.model)?;
    let m = rho * std::f64::consts::PI * d.powi(3) / 6.0;
    Ok(if k_max > 0.0 {
        (m / k_max).sqrt()
    } else {
        f64::INFINITY
    })
}
