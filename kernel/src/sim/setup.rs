//! Building a simulation: the set-up's checks (time step, skin, threads, particles, material
//! pairs, overlaps), what is derived from it once (the Rayleigh time, the list's reach, the
//! speed no physical motion reaches), the thread pool, and the first force evaluation.

use super::time_step::{check_dt, rayleigh_step_warning};
use super::{Aabb, PairPath, Setup, Simulation, ThreadStart};
use crate::contact::ContactModel;
use crate::error::{KernelError, Result};
use crate::factory::Factory;
use crate::neighbor::{PairList, PairSchedule, WallContacts};
use crate::particles::Particles;
use crate::timestep::rayleigh_time;
use crate::timing::PhaseTimes;
use crate::wall::Wall;
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;

impl Simulation {
    /// Checks the set-up (time step, material pairs, overlaps) and prepares the first step.
    pub fn new(setup: Setup) -> Result<Simulation> {
        Self::with_thread_start(setup, None)
    }

    /// Like [`Simulation::new`]; `on_thread_start(k)` runs first on each worker thread
    /// `k = 0..threads`. A front end uses it to pin workers to cores; the physics never
    /// depends on it.
    pub fn with_thread_start(
        setup: Setup,
        on_thread_start: Option<ThreadStart>,
    ) -> Result<Simulation> {
        let Setup {
            model,
            particles,
            walls,
            factories,
            dt,
            gravity,
            skin,
            threads,
            domain,
        } = setup;
        check_dt(dt)?;
        check_settings(skin, threads, gravity, domain)?;
        check_particles(&particles, model.materials().len())?;
        let mats = materials_in_use(&particles, &factories);
        require_material_pairs(&model, &mats, &walls)?;
        let r_max = largest_radius(&particles, &factories);
        let t_r = shortest_rayleigh_time(&model, &particles, &factories, &mats);
        let warnings: Vec<String> = rayleigh_step_warning(dt, t_r).into_iter().collect();
        let reach = if r_max > 0.0 {
            model.max_reach(r_max)
        } else {
            0.0
        };
        let extra = skin + reach;
        let speed_limit = speed_limit(&particles, &factories, &walls, gravity, domain);
        let pool = thread_pool(threads, on_thread_start)?;
        let stride = model.history_stride();
        let nwalls = walls.len();
        let mut sim = Simulation {
            particles,
            model,
            walls,
            factories,
            step: 0,
            time: 0.0,
            dt,
            gravity,
            domain,
            warnings,
            rebuilds: 0,
            times: PhaseTimes::default(),
            rayleigh_time: t_r,
            packing_frequency: None,
            loaded_step_warned: false,
            time_origin: 0.0,
            step_origin: 0,
            skin,
            extra,
            pairs: PairList::empty(stride),
            schedule: PairSchedule::default(),
            next_force: vec![],
            next_torque: vec![],
            next_ready: None,
            pairs_carrying: 0,
            pair_path: PairPath::default(),
            walls_near: WallContacts::empty(),
            wall_shares: vec![],
            ref_position: vec![],
            kick_factor: vec![],
            wall_ref_offset: vec![DVec3::ZERO; nwalls],
            speed_limit,
            pending_order: None,
            retired_bonds: BTreeMap::new(),
            bonded: false,
            pool,
        };
        sim.check_overlaps()?;
        sim.insert_particles();
        sim.rebuild();
        sim.compute_forces(false, true, false, None);
        Ok(sim)
    }

    /// Refuses particles that overlap at the start by more than a millionth of the smaller
    /// radius (more is a placement error, not a contact).
    fn check_overlaps(&mut self) -> Result<()> {
        let p = &self.particles;
        let mut list = PairList::empty(1);
        self.pool
            .install(|| list.rebuild(&p.position, &p.radius, &p.id, 0.0, None));
        for k in 0..list.len() {
            let (i, j) = (list.i[k] as usize, list.j[k] as usize);
            let overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).length();
            if overlap > 1e-6 * p.radius[i].min(p.radius[j]) {
                return Err(KernelError::InitialOverlap {
                    i,
                    j,
                    overlap,
                    pi: p.position[i].to_array(),
                    pj: p.position[j].to_array(),
                });
            }
        }
        Ok(())
    }
}

/// Refuses a skin that is negative or not finite (m), no threads, a gravity that is not
/// finite, or a domain empty along some axis.
fn check_settings(skin: f64, threads: usize, gravity: DVec3, domain: Aabb) -> Result<()> {
    if !(skin >= 0.0 && skin.is_finite()) {
        return Err(KernelError::OutOfRange {
            key: "skin".into(),
            value: skin,
            range: "[0, inf)".into(),
            unit: "m".into(),
        });
    }
    if threads == 0 {
        return Err(KernelError::OutOfRange {
            key: "threads".into(),
            value: 0.0,
            range: "[1, cores]".into(),
            unit: "".into(),
        });
    }
    if !gravity.is_finite() {
        return Err(KernelError::Invalid("gravity must be finite".into()));
    }
    if !(domain.min.cmplt(domain.max).all()) {
        return Err(KernelError::Invalid(format!(
            "domain min {:?} must lie below max {:?} on every axis",
            domain.min, domain.max
        )));
    }
    Ok(())
}

/// Refuses the first particle whose radius is not a positive number, whose material index
/// is not below `nmat` (the model's count of materials), or whose position or velocity is
/// not finite.
fn check_particles(particles: &Particles, nmat: usize) -> Result<()> {
    for i in 0..particles.len() {
        let r = particles.radius[i];
        if !(r > 0.0 && r.is_finite()) {
            return Err(KernelError::OutOfRange {
                key: format!("particles[{i}].radius"),
                value: r,
                range: "(0, inf)".into(),
                unit: "m".into(),
            });
        }
        if particles.material[i] as usize >= nmat {
            return Err(KernelError::Invalid(format!(
                "particles[{i}] has material index {} but only {nmat} materials exist",
                particles.material[i]
            )));
        }
        if !particles.position[i].is_finite() || !particles.velocity[i].is_finite() {
            return Err(KernelError::Invalid(format!(
                "particles[{i}] has a non-finite position or velocity"
            )));
        }
    }
    Ok(())
}

/// The materials of the particles and of what the factories make, ascending, each once.
fn materials_in_use(particles: &Particles, factories: &[Factory]) -> Vec<usize> {
    let mut mats: Vec<usize> = particles.material.iter().map(|&m| m as usize).collect();
    mats.extend(factories.iter().map(|f| f.spec.material as usize));
    mats.sort_unstable();
    mats.dedup();
    mats
}

/// Refuses a model without coefficients for a material pair that can meet: any two of the
/// materials in use `mats` (a material with itself included), and each with every wall's.
fn require_material_pairs(model: &ContactModel, mats: &[usize], walls: &[Wall]) -> Result<()> {
    let mut needed = vec![];
    for (k, &a) in mats.iter().enumerate() {
        for &b in &mats[k..] {
            needed.push((a, b));
        }
        for w in walls {
            needed.push((a, w.material as usize));
        }
    }
    model.require_pairs(&needed)
}

/// The largest radius among the particles and what the factories make, m (0 with none):
/// what the list's reach beyond touching is bounded with.
fn largest_radius(particles: &Particles, factories: &[Factory]) -> f64 {
    let mut r_max = particles.radius.iter().copied().fold(0.0, f64::max);
    for f in factories {
        r_max = r_max.max(f.max_radius());
    }
    r_max
}

/// The shortest Rayleigh time (s) over the materials in use `mats`, each at its smallest
/// particle, present or to be made by a factory: the bound the time step is checked against.
fn shortest_rayleigh_time(
    model: &ContactModel,
    particles: &Particles,
    factories: &[Factory],
    mats: &[usize],
) -> f64 {
    let mut t_r = f64::INFINITY;
    for &m in mats {
        let mat = &model.materials()[m];
        let r = particles
            .radius
            .iter()
            .zip(&particles.material)
            .filter(|(_, pm)| **pm as usize == m)
            .map(|(r, _)| *r)
            .chain(
                factories
                    .iter()
                    .filter(|f| f.spec.material as usize == m)
                    .map(|f| f.min_radius()),
            )
            .fold(f64::INFINITY, f64::min);
        t_r = t_r.min(rayleigh_time(
            r,
            mat.density,
            mat.shear_modulus(),
            mat.poisson_ratio,
        ));
    }
    t_r
}

/// A speed (m/s) no physical run reaches, beyond which a particle is a runaway: free fall
/// across the domain's diagonal plus every imposed speed (particles', factories', walls'),
/// ten times over, plus 1 m/s: 10 (sqrt(2 |g| h) + v_imposed) + 1.
fn speed_limit(
    particles: &Particles,
    factories: &[Factory],
    walls: &[Wall],
    gravity: DVec3,
    domain: Aabb,
) -> f64 {
    let height = (domain.max - domain.min).length();
    let imposed = particles
        .velocity
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max)
        + factories
            .iter()
            .map(|f| f.spec.velocity.length())
            .fold(0.0, f64::max)
        + walls.iter().map(|w| w.max_speed()).fold(0.0, f64::max);
    10.0 * ((2.0 * gravity.length() * height).sqrt() + imposed) + 1.0
}

/// The simulation's worker pool of `threads` threads, each running `on_thread_start` first.
fn thread_pool(
    threads: usize,
    on_thread_start: Option<ThreadStart>,
) -> Result<Arc<rayon::ThreadPool>> {
    let builder = rayon::ThreadPoolBuilder::new().num_threads(threads);
    let builder = match on_thread_start {
        Some(hook) => builder.start_handler(move |k| hook(k)),
        None => builder,
    };
    let pool = builder
        .build()
        .map_err(|e| KernelError::Invalid(format!("cannot start {threads} threads: {e}")))?;
    Ok(Arc::new(pool))
}
