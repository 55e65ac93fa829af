//! The simulation: velocity-Verlet stepping with deterministic parallel force evaluation.
//!
//! One step:
//! 1. half kick and drift (v += F/m dt/2, omega += T/I dt/2, x += v dt), tracking the largest
//!    displacement since the last neighbour-list build and testing the new positions (finite,
//!    inside the domain);
//! 2. walls move; factories create particles;
//! 3. rebuild the pair list and wall contact list when something moved more than skin/2
//!    (history is carried over);
//! 4. pair phase: every listed pair's force and torques (contact laws, then the bond if
//!    intact), added to both particles' force sums, which start from gravity's, block by
//!    block of the pair list and phase by phase ([`PairSchedule`]);
//! 5. particle phase: each particle adds its wall contacts;
//! 6. second half kick, applied in the particle phase as each force is known, with the
//!    failure checks (non-finite state, runaway speed, escape); within [`Simulation::run`],
//!    also the next step's step 1 for each chunk that passed them, while its particles are
//!    in cache (the same operations, so the same bits).
//!
//! The wall-clock time of each part is summed in [`Simulation::times`].
//!
//! Every sum runs in an order that does not depend on the thread count, so 1 and 2 threads
//! give the same bits (work is split in fixed chunks of [`CHUNK`] rows, and the pair phase
//! in blocks set by the pair list and its contacts). Within [`Simulation::run`] on several
//! threads, the pair and particle phases run on a team whose threads stay awake between
//! phases (`team.rs`); elsewhere every parallel loop is rayon's.

use crate::contact::{BondState, BondStatus, ContactModel};
use crate::error::{KernelError, Result};
use crate::factory::Factory;
use crate::neighbor::{
    CHUNK, PairList, PairSchedule, WallContacts, build_wall_contacts, chunks_per_task,
};
use crate::particles::Particles;
use crate::step_check::{PackingFrequency, loaded_step_warning, packing_frequency};
use crate::timestep::{BOND_WARN_FRACTION, WARN_FRACTION, rayleigh_time};
use crate::timing::{Laps, PhaseTimes};
use crate::wall::{Hit, Wall};
use drift::{ChunkMotion, ChunkResult, Drift, kick_and_drift};
use glam::DVec3;
pub use pair_forces::PairPath;
use pair_forces::add_pair_forces;
use rayon::prelude::*;
use std::collections::BTreeMap;
use sum_and_kick::{ChunkSums, ChunkWalls, start_sums, sum_and_kick};
use team::{Team, map_items};
use wall_forces::{ChunkBodies, WallCtx, WallList, WallOut, WallRows, chunk_wall_forces};

mod drift;
mod flat;
mod pair_forces;
mod sum_and_kick;
mod team;
mod wall_forces;

thread_local! {
    /// Each thread's wall-contact outputs of one particle-phase chunk ([`WallOut`]), kept
    /// from chunk to chunk rather than allocated for each.
    static WALL_OUTS: std::cell::Cell<Vec<WallOut>> = const { std::cell::Cell::new(Vec::new()) };
}

/// One particle-phase task's rows: force, torque, velocity, spin, position, wall contacts,
/// and the next pair phase's force and torque sums.
type ChunkRows<'a> = (
    (
        (
            (
                ((&'a mut [DVec3], &'a mut [DVec3]), &'a mut [DVec3]),
                &'a mut [DVec3],
            ),
            &'a mut [DVec3],
        ),
        WallRows<'a>,
    ),
    (&'a mut [DVec3], &'a mut [DVec3]),
);

/// Steps between spatial reorderings of the particles (cell order, for cache locality; as
/// LAMMPS's `atom_modify sort`). A fixed step schedule, not a rebuild count, so that runs
/// with different skins reorder at the same moments.
pub const SORT_EVERY: u64 = 1000;

/// Steps between factory insertions (particles due meanwhile appear together).
pub const INSERT_EVERY: u64 = 50;

/// Axis-aligned box, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

/// A hook run first on each worker thread, given the worker's index.
pub type ThreadStart = std::sync::Arc<dyn Fn(usize) + Send + Sync>;

/// Everything a simulation is built from.
pub struct Setup {
    pub model: ContactModel,
    pub particles: Particles,
    pub walls: Vec<Wall>,
    pub factories: Vec<Factory>,
    /// Time step, s.
    pub dt: f64,
    /// m/s^2.
    pub gravity: DVec3,
    /// Verlet skin, m.
    pub skin: f64,
    pub threads: usize,
    /// Particles leaving this box stop the run.
    pub domain: Aabb,
}

pub struct Simulation {
    /// The particles. Between steps their positions and velocities may be edited; their
    /// masses, inertias and order change only through the simulation, which caches what
    /// it derives from them.
    pub particles: Particles,
    pub model: ContactModel,
    pub walls: Vec<Wall>,
    pub factories: Vec<Factory>,
    pub step: u64,
    pub time: f64,
    pub dt: f64,
    pub gravity: DVec3,
    pub domain: Aabb,
    /// Messages worth showing the user (time step, crowded factories).
    pub warnings: Vec<String>,
    /// Neighbour list rebuilds so far.
    pub rebuilds: u64,
    /// Wall-clock time per part of the step, summed over every step so far.
    pub times: PhaseTimes,
    /// Rayleigh time of the smallest particle, s.
    pub rayleigh_time: f64,
    /// The packing's stiffest contact mode at the last reorder (every [`SORT_EVERY`]
    /// steps; see [`crate::step_check`]), `None` before the first or while nothing touches.
    pub packing_frequency: Option<PackingFrequency>,
    /// Whether the step has been warned about as too long for the loaded contacts (once per
    /// step size: [`Simulation::set_dt`] clears it).
    loaded_step_warned: bool,
    skin: f64,
    /// skin + the laws' reach: the list distance beyond touching.
    extra: f64,
    pairs: PairList,
    /// How the pair phase splits its sums, made from `pairs` at each rebuild.
    schedule: PairSchedule,
    /// The force and torque sums the next pair phase adds to, one row per particle, and
    /// the gravity they start from (`m g` and zero; see [`sum_and_kick::start_sums`]), or
    /// `None` when they are not ready (new particles, a new order). The pair phase adds to
    /// these, then they change places with `particles.force` and `torque`: the particle
    /// phase reads the complete sums there and readies the old rows here for the next step,
    /// in the same pass (it once summed each block's partial sums, twice the rows).
    next_force: Vec<DVec3>,
    next_torque: Vec<DVec3>,
    next_ready: Option<DVec3>,
    /// Listed pairs that carried force in the last evaluation.
    pairs_carrying: usize,
    /// How the pair phase evaluates touching contacts.
    pair_path: PairPath,
    walls_near: WallContacts,
    /// Each particle-phase chunk's share of every wall's force and torque (chunk-major),
    /// summed over the chunks in order after the phase.
    wall_shares: Vec<(DVec3, DVec3)>,
    ref_position: Vec<DVec3>,
    /// Each particle's half-step kick factors (dt/2 / m, dt/2 / I), computed by the same
    /// expressions the kicks would evaluate, so the bits are the same as dividing at each
    /// kick, without two divisions per particle per half kick. Refreshed when particles are
    /// inserted or reordered and when the step changes (a particle's mass and inertia never
    /// change once it exists); `advance` fills them on its first call.
    kick_factor: Vec<(f64, f64)>,
    wall_ref_offset: Vec<DVec3>,
    speed_limit: f64,
    /// Set by a reorder, consumed by the rebuild that follows it.
    pending_order: Option<Vec<u32>>,
    /// Bonds whose pair left the neighbour list (broken ones that drifted apart), by
    /// (smaller id, larger id), with the time they broke: still reported, never re-formed.
    retired_bonds: BTreeMap<(u32, u32), f64>,
    /// Whether bonds were ever formed; rebuilds then retire the bonded pairs they drop.
    bonded: bool,
    /// The time and step of the last change of the time step (0 and 0 without one):
    /// `time = time_origin + (step - step_origin) dt`, a product rather than a running sum.
    time_origin: f64,
    step_origin: u64,
    /// Shared so `run` can enter it once; nested `install` calls from inside are direct calls.
    pool: std::sync::Arc<rayon::ThreadPool>,
}

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
        let nmat = model.materials().len();
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
        // Which material pairs can meet.
        let mut mats: Vec<usize> = particles.material.iter().map(|&m| m as usize).collect();
        mats.extend(factories.iter().map(|f| f.spec.material as usize));
        mats.sort_unstable();
        mats.dedup();
        let mut needed = vec![];
        for (k, &a) in mats.iter().enumerate() {
            for &b in &mats[k..] {
                needed.push((a, b));
            }
            for w in &walls {
                needed.push((a, w.material as usize));
            }
        }
        model.require_pairs(&needed)?;

        let mut r_min = particles
            .radius
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let mut r_max = particles.radius.iter().copied().fold(0.0, f64::max);
        for f in &factories {
            r_min = r_min.min(f.min_radius());
            r_max = r_max.max(f.max_radius());
        }
        let mut t_r = f64::INFINITY;
        for &m in &mats {
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
        let warnings: Vec<String> = rayleigh_step_warning(dt, t_r).into_iter().collect();
        let reach = if r_max > 0.0 {
            model.max_reach(r_max)
        } else {
            0.0
        };
        let extra = skin + reach;
        // A bound no physical run reaches: free fall across the domain plus every imposed
        // speed, ten times over.
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
        let speed_limit = 10.0 * ((2.0 * gravity.length() * height).sqrt() + imposed) + 1.0;
        let pool = std::sync::Arc::new(
            {
                let builder = rayon::ThreadPoolBuilder::new().num_threads(threads);
                match on_thread_start {
                    Some(hook) => builder.start_handler(move |k| hook(k)),
                    None => builder,
                }
            }
            .build()
            .map_err(|e| KernelError::Invalid(format!("cannot start {threads} threads: {e}")))?,
        );
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

    /// Advances `n` steps, stopping at the first failure. Within the run each step's
    /// particle phase also applies the next step's first half kick and drift to each
    /// particle as soon as its second half kick is done (one pass over memory instead of
    /// two, with the same operations in the same order, so the same bits as `n` calls of
    /// [`Simulation::advance`]); the last step does not, so the state between runs is the
    /// ordinary end-of-step state.
    pub fn run(&mut self, n: u64) -> Result<()> {
        self.on_team(|sim, team| sim.steps(n, team))
    }

    /// Runs `f` inside the pool, entered once, so that every parallel phase in it runs
    /// without a hand-off: on one thread as it is; on more, on the pool's first thread,
    /// the others staying awake as its team (given to `f`).
    fn on_team<R: Send>(
        &mut self,
        f: impl FnOnce(&mut Simulation, Option<&Team>) -> R + Send,
    ) -> R {
        let pool = std::sync::Arc::clone(&self.pool);
        let helpers = pool.current_num_threads() - 1;
        if helpers == 0 {
            return pool.install(|| f(self, None));
        }
        let team = Team::new(helpers);
        let leader = std::sync::Mutex::new(Some((self, f)));
        let mut out = pool.broadcast(|ctx| {
            if ctx.index() != 0 {
                team.help(ctx.index());
                return None;
            }
            let (sim, f) = leader.lock().ok()?.take()?;
            let out =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(sim, Some(&team))));
            team.release();
            Some(out.unwrap_or_else(|p| std::panic::resume_unwind(p)))
        });
        out.swap_remove(0).expect("the leader's result")
    }

    /// `n` steps, each drifting the next, the parallel phases on `team` when given.
    fn steps(&mut self, n: u64, team: Option<&Team>) -> Result<()> {
        let mut drifted = None;
        for s in 0..n {
            drifted = self.step(drifted, s + 1 < n, team)?;
        }
        Ok(())
    }

    /// Number of worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// One velocity-Verlet step.
    pub fn advance(&mut self) -> Result<()> {
        self.step(None, false, None).map(|_| ())
    }

    /// One velocity-Verlet step. `drifted`: the first half kick and drift were already
    /// applied by the previous step's particle phase, which found these displacement and
    /// position results. With `drift_next`, this step's particle phase applies the next
    /// step's, and returns its results.
    fn step(
        &mut self,
        drifted: Option<Drift>,
        drift_next: bool,
        team: Option<&Team>,
    ) -> Result<Option<Drift>> {
        let mut laps = Laps::start();
        let dt = self.dt;
        if self.kick_factor.len() != self.particles.len() {
            self.refresh_kick_factor();
        }
        let kick_factor = &self.kick_factor;
        let dom = self.domain;
        // The positions change here only, so they are checked here, while in registers (the
        // particle phase then tests only what its kick changes).
        let Drift {
            max_disp2,
            mut positions_ok,
        } = match drifted {
            Some(d) => d,
            None => self.pool.install(|| {
                let p = &mut self.particles;
                p.position
                    .par_chunks_mut(CHUNK)
                    .zip(p.velocity.par_chunks_mut(CHUNK))
                    .zip(p.angular_velocity.par_chunks_mut(CHUNK))
                    .zip(p.force.par_chunks(CHUNK))
                    .zip(p.torque.par_chunks(CHUNK))
                    .zip(kick_factor.par_chunks(CHUNK))
                    .zip(self.ref_position.par_chunks(CHUNK))
                    .with_max_len(chunks_per_task())
                    .map(|((((((x, v), w), f), t), kf), x0)| {
                        kick_and_drift(
                            ChunkMotion {
                                x,
                                v,
                                w,
                                f,
                                t,
                                kf,
                                x0,
                            },
                            dt,
                            dom,
                        )
                    })
                    .reduce(Drift::none, Drift::join)
            }),
        };
        let mut wall_disp: f64 = 0.0;
        for (w, r0) in self.walls.iter_mut().zip(&self.wall_ref_offset) {
            w.update_velocity();
            w.offset += w.velocity * dt;
            wall_disp = wall_disp.max((w.offset - *r0).length());
        }
        self.step += 1;
        self.time = self.time_origin + (self.step - self.step_origin) as f64 * dt;
        self.times.integrate += laps.lap();
        // Factories fill in batches: a new particle forces a list rebuild, so inserting a
        // few every step would rebuild every step.
        let created = if self.step % INSERT_EVERY == 0 {
            let made = self.insert_particles();
            let new = &self.particles.position[self.particles.len() - made..];
            positions_ok &= new.iter().all(|&x| plausible_position(x, dom));
            self.times.insert += laps.lap();
            made
        } else {
            0
        };
        let sort = self.step % SORT_EVERY == 0;
        if sort {
            self.sort_particles();
        }
        if sort || created > 0 || max_disp2.sqrt() + wall_disp > 0.5 * self.skin {
            self.rebuild();
        }
        if sort {
            self.check_loaded_step();
        }
        self.times.neighbor += laps.lap();
        match self.compute_forces(true, positions_ok, drift_next, team) {
            (None, next) => Ok(next),
            (Some((i, kind)), _) => Err(self.failure(i, kind)),
        }
    }

    /// Bounds the packing's stiffest contact mode from the pair list and warns, once per
    /// step size, when the step is beyond its stable limit. Reads state only: a run with
    /// and without the check gives the same bits.
    fn check_loaded_step(&mut self) {
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

    /// Lets the factories create the particles due by now; returns how many were created.
    fn insert_particles(&mut self) -> usize {
        let mut made = 0;
        for f in &mut self.factories {
            if !f.done() {
                made += f.insert(self.time, &mut self.particles);
            }
        }
        if made > 0 {
            self.ref_position.resize(self.particles.len(), DVec3::ZERO);
            self.refresh_kick_factor();
        }
        made
    }

    /// Puts the particles in cell order; the next rebuild carries history through the
    /// permutation.
    fn sort_particles(&mut self) {
        let p = &self.particles;
        let r_max = p.radius.iter().copied().fold(0.0, f64::max);
        // Cells from the particle size alone, so the order does not depend on the skin (nor
        // the bits: a test runs two skins). A quarter over the diameter, so that the cut of
        // the usual skins (up to half a radius) spans one layer of cells, not two: in cells
        // of one diameter a partner could lie two layers away in index, and each block of
        // the pair schedule reached twice as far beyond its rows (settled bed: 2.1 partial
        // sums a particle in cells of 2 r, 1.8 in cells of 2.5 r).
        let grid = crate::neighbor::CellGrid::build(&p.position, 2.5 * r_max);
        let order = grid.cell_order().to_vec();
        self.particles.permute(&order);
        self.refresh_kick_factor();
        self.pending_order = Some(order);
    }

    fn rebuild(&mut self) {
        self.rebuilds += 1;
        let bonded_before = self
            .bonded
            .then(|| self.bonded_pairs(self.pending_order.as_deref()));
        let p = &self.particles;
        let extra = self.extra;
        let pairs = &mut self.pairs;
        let walls = &self.walls;
        let old = &self.walls_near;
        let stride = self.model.history_stride();
        let order = self.pending_order.take();
        let model = &self.model;
        let bonded = self.bonded;
        let keep = |h: &[f64]| model.bond_intact(h);
        let (new_walls, schedule) = self.pool.install(|| {
            // Intact bonds keep their pairs in the list, however far they stretch.
            let keep: Option<crate::neighbor::pairs::PairFilter<'_>> = bonded.then_some(&keep);
            pairs.rebuild_keeping(&p.position, &p.radius, &p.id, extra, order.as_deref(), keep);
            let walls = build_wall_contacts(p, walls, old, extra, stride, order.as_deref());
            let schedule =
                PairSchedule::build(&pairs.row_start, &pairs.j, &pairs.history, pairs.stride);
            (walls, schedule)
        });
        self.walls_near = new_walls;
        self.schedule = schedule;
        self.ref_position.clone_from(&self.particles.position);
        for (r, w) in self.wall_ref_offset.iter_mut().zip(&self.walls) {
            *r = w.offset;
        }
        if let Some(before) = bonded_before {
            self.retire_dropped_bonds(before);
        }
    }

    /// The bonded pairs of the current list by (smaller id, larger id), with their status.
    /// `old_of_new`: a reorder applied to the particles since the list was built.
    fn bonded_pairs(&self, old_of_new: Option<&[u32]>) -> Vec<((u32, u32), BondStatus)> {
        let p = &self.particles;
        let ids: std::borrow::Cow<[u32]> = match old_of_new {
            None => (&p.id[..]).into(),
            Some(order) => {
                let mut ids = vec![0; order.len()];
                for (new, &old) in order.iter().enumerate() {
                    ids[old as usize] = p.id[new];
                }
                ids.into()
            }
        };
        let list = &self.pairs;
        let stride = list.stride;
        (0..list.len())
            .filter_map(|k| {
                let status = self
                    .model
                    .bond_status(&list.history[k * stride..(k + 1) * stride]);
                let (a, b) = (ids[list.i[k] as usize], ids[list.j[k] as usize]);
                (status != BondStatus::None).then_some(((a.min(b), a.max(b)), status))
            })
            .collect()
    }

    /// Keeps the bonds a rebuild dropped from the list. A broken one keeps its time; an
    /// intact one can only have been dropped stretched beyond the bond law's reach, where its
    /// tensile stress exceeds the strength, so it breaks now, as it would have in this step.
    fn retire_dropped_bonds(&mut self, before: Vec<((u32, u32), BondStatus)>) {
        let mut after: Vec<(u32, u32)> = self
            .bonded_pairs(None)
            .into_iter()
            .map(|(k, _)| k)
            .collect();
        after.sort_unstable();
        for (key, status) in before {
            if after.binary_search(&key).is_err() {
                let time = match status {
                    BondStatus::Broken(t) => t,
                    _ => self.time,
                };
                self.retired_bonds.insert(key, time);
            }
        }
    }

    /// Computes every force and torque. With `kick`, also applies the step's second half kick
    /// to each particle as soon as its force is known (one pass over memory instead of two)
    /// and returns the first particle in a failed state. `positions_ok`: whether every
    /// position passed [`plausible_position`] since it last changed; when not, every
    /// particle gets the exact test. With `drift_next` (and `kick`), a particle phase that
    /// finds no failure also applies the next step's first half kick and drift, and
    /// returns its results (see [`Simulation::run`]).
    fn compute_forces(
        &mut self,
        kick: bool,
        positions_ok: bool,
        drift_next: bool,
        team: Option<&Team>,
    ) -> (Option<(usize, Failure)>, Option<Drift>) {
        let mut laps = Laps::start();
        let dt = self.dt;
        let pool = self.pool.clone();
        self.ready_next_sums();
        self.pairs_carrying = pool.install(|| self.pair_phase(team));
        // This step's sums are complete; the old rows become the next step's.
        std::mem::swap(&mut self.particles.force, &mut self.next_force);
        std::mem::swap(&mut self.particles.torque, &mut self.next_torque);
        self.next_ready = None;
        self.times.pair += laps.lap();

        // Particle phase: each particle's sum (gravity and its pairs', then its walls), the
        // second half kick and the checks; and the next step's sums readied.
        let gravity = self.gravity;
        let model = &self.model;
        let stride = self.pairs.stride;
        let walls = &self.walls;
        let wc = &mut self.walls_near;
        let p = &mut self.particles;
        let n = p.len();
        let nwalls = walls.len();
        self.wall_shares
            .resize(n.div_ceil(CHUNK) * nwalls, (DVec3::ZERO, DVec3::ZERO));
        // Split the wall-contact arrays at the chunk boundaries so each task owns its rows.
        let mut wall_chunks = vec![];
        {
            let (mut hist, mut force, mut point) =
                (&mut wc.history[..], &mut wc.force[..], &mut wc.point[..]);
            let mut shares = &mut self.wall_shares[..];
            let mut at = 0usize;
            for c in 0..n.div_ceil(CHUNK) {
                let end = wc.start[((c + 1) * CHUNK).min(n)] as usize;
                let len = end - at;
                let (h1, h2) = hist.split_at_mut(len * stride);
                let (f1, f2) = force.split_at_mut(len);
                let (p1, p2) = point.split_at_mut(len);
                let (s1, s2) = shares.split_at_mut(nwalls);
                wall_chunks.push(WallRows {
                    base: at,
                    history: h1,
                    force: f1,
                    point: p1,
                    shares: s1,
                });
                hist = h2;
                force = f2;
                point = p2;
                shares = s2;
                at = end;
            }
        }
        let wstart = &wc.start;
        let wall_ctx = WallCtx {
            list: WallList {
                wall: &wc.wall,
                feature: &wc.feature,
            },
            start: wstart,
            walls,
            model,
            stride,
            dt,
            // Walls bond to nothing: every model runs them on the pair phase's path.
            path: self.pair_path,
        };
        let (radius, mass, inertia, material) = (&p.radius, &p.mass, &p.inertia, &p.material);
        let limit2 = self.speed_limit * self.speed_limit;
        let dom = self.domain;
        // `advance` refreshed them for this step's particles.
        debug_assert!(!kick || self.kick_factor.len() == n);
        let kick_factor = &self.kick_factor;
        let drift_next = drift_next && kick;
        let ref_position = &self.ref_position;
        // One chunk of particles: rows c * CHUNK.. of each array, and their wall rows.
        let chunk = |c: usize,
                     ((((((fs, ts), vs), ws), xs), mut mine), (next_f, next_t)): ChunkRows|
         -> ChunkResult {
            // The chunk's wall contacts first, so that the touching ones with a wall of
            // one listed feature can be evaluated in lanes; each particle adds its own in
            // its loop below. Most chunks have none (and need no scratch space).
            let mut outs = WALL_OUTS.take();
            outs.clear();
            outs.resize(mine.force.len(), WallOut::NONE);
            if !outs.is_empty() {
                // Room for a particle's usual wall hits: growing it took glibc's arena lock
                // (`realloc` bypasses the per-thread cache) on both threads at once.
                let mut hits: Vec<(f64, usize, Hit)> = Vec::with_capacity(8);
                let bodies = ChunkBodies {
                    first: c * CHUNK,
                    x: xs,
                    v: vs,
                    w: ws,
                    radius,
                    mass,
                    inertia,
                    material,
                };
                chunk_wall_forces(&wall_ctx, &bodies, &mut mine, &mut outs, &mut hits);
            }
            let rows = c * CHUNK..c * CHUNK + fs.len();
            // Whether every kicked particle of the chunk passed the cheap test.
            let plausible_all = sum_and_kick(
                ChunkSums {
                    f: fs,
                    t: ts,
                    v: vs,
                    w: ws,
                    mass: &mass[rows.clone()],
                    kick: kick.then(|| &kick_factor[rows.clone()]),
                    next_f,
                    next_t,
                },
                gravity,
                ChunkWalls {
                    outs: &outs,
                    start: &wstart[rows.start..rows.end + 1],
                    base: mine.base,
                },
                limit2,
            );
            WALL_OUTS.set(outs);
            mine.add_wall_shares(&wall_ctx.list, walls);
            // The exact test only for a chunk the cheap one flagged: the first
            // failing particle in index order, as a test of each would find it.
            // A chunk it passes is where a failure cannot be (the cheap test is
            // exact for what it passes), so only it may go on to the next drift.
            if plausible_all && positions_ok {
                let next = drift_next.then(|| {
                    kick_and_drift(
                        ChunkMotion {
                            x: xs,
                            v: vs,
                            w: ws,
                            f: fs,
                            t: ts,
                            kf: &kick_factor[rows.clone()],
                            x0: &ref_position[rows],
                        },
                        dt,
                        dom,
                    )
                });
                return ChunkResult::Passed(next);
            }
            let failed = (0..fs.len()).find_map(|k| {
                let i = c * CHUNK + k;
                check(xs[k], vs[k], ws[k], limit2, dom).map(|f| (i, f))
            });
            ChunkResult::Checked(failed)
        };
        let next_rows = self
            .next_force
            .chunks_mut(CHUNK)
            .zip(self.next_torque.chunks_mut(CHUNK));
        let items: Vec<ChunkRows> = p
            .force
            .chunks_mut(CHUNK)
            .zip(p.torque.chunks_mut(CHUNK))
            .zip(p.velocity.chunks_mut(CHUNK))
            .zip(p.angular_velocity.chunks_mut(CHUNK))
            .zip(p.position.chunks_mut(CHUNK))
            .zip(wall_chunks)
            .zip(next_rows)
            .collect();
        let results: Vec<ChunkResult> = self.pool.install(|| map_items(team, items, chunk));
        self.next_ready = Some(gravity);
        let failure = results.iter().find_map(|r| match r {
            ChunkResult::Checked(f) => *f,
            ChunkResult::Passed(_) => None,
        });
        let next = match failure {
            Some(_) => {
                self.undo_drift(&results);
                None
            }
            None if drift_next => Some(self.finish_drift(&results)),
            None => None,
        };

        // Wall totals: the chunks' shares, in chunk order. Summing every contact here, one
        // thread did what the chunks now do on all.
        for w in &mut self.walls {
            w.force = DVec3::ZERO;
            w.torque = DVec3::ZERO;
        }
        if nwalls > 0 {
            for shares in self.wall_shares.chunks(nwalls) {
                for (w, &(f, t)) in self.walls.iter_mut().zip(shares) {
                    w.force += f;
                    w.torque += t;
                }
            }
        }
        // Each step's force acts for one step (the initial evaluation adds nothing).
        if kick {
            for w in &mut self.walls {
                w.impulse += w.force * self.dt;
            }
        }
        self.times.particle += laps.lap();
        (failure, next)
    }

    fn failure(&self, i: usize, kind: Failure) -> KernelError {
        let p = &self.particles;
        let (x, v) = (p.position[i], p.velocity[i]);
        let frac = self.dt / self.rayleigh_time;
        let dt_cause = (frac > WARN_FRACTION).then(|| {
            format!(
                "the time step {:.3e} s is {:.0} % of the Rayleigh time {:.3e} s; use at most 40 % (EDEM practice 20-40 %)",
                self.dt,
                100.0 * frac,
                self.rayleigh_time
            )
        });
        let (what, cause) = match kind {
            Failure::NonFinite => (
                format!("particle {i} has a non-finite position, velocity or spin (x = {:?})", x.to_array()),
                dt_cause.unwrap_or_else(|| "a contact produced a non-finite force: check for particles created on top of each other or walls, and for extreme law parameters".into()),
            ),
            Failure::Runaway => (
                format!("particle {i} moves at {:.3e} m/s, above the {:.3e} m/s any physical motion here can reach (runaway kinetic energy)", v.length(), self.speed_limit),
                dt_cause.unwrap_or_else(|| "energy is being injected: particles created overlapping, a wall moving or a servo pushing too fast, an unstable law parameter, or a step too long for strongly damped contacts (a low restitution coefficient, such as 0.15, lowers the explicit scheme's stability limit for the tangential spring: try 20 % of the Rayleigh time)".into()),
            ),
            Failure::Escaped => {
                // Faster than free fall plus every imposed speed: it was shot out, not spilled.
                let physical = (self.speed_limit - 1.0) / 10.0;
                let shot = v.length() > 2.0 * physical;
                (
                    format!(
                        "particle {i} left the domain [{:?}, {:?}] at x = {:?} m, v = {:?} m/s",
                        self.domain.min.to_array(),
                        self.domain.max.to_array(),
                        x.to_array(),
                        v.to_array()
                    ),
                    dt_cause.unwrap_or_else(|| {
                        if shot {
                            format!("it moves at {:.3} m/s, faster than anything in this set-up can make it ({physical:.3} m/s): energy was injected, most often by particles created overlapping a wall (check factory regions against the geometry) or by a wall moving too fast", v.length())
                        } else {
                            "the geometry is open (a missing wall) or particles tunnelled through a wall; enlarge the domain or close the geometry".into()
                        }
                    }),
                )
            }
        };
        KernelError::BlowUp {
            step: self.step,
            time: self.time,
            what,
            cause,
        }
    }

    /// The neighbour list (pairs and their contact history).
    pub fn pairs(&self) -> &PairList {
        &self.pairs
    }

    /// A diagnostic for measuring changes to the pair phase: runs it alone `reps` times on
    /// the current state and returns the seconds they took. The contact history is put back
    /// before each (untimed), so every repetition does the same work as this step's pair
    /// phase; nothing else changes. Full runs vary by 5-10 % on a shared VM, these by about
    /// 2 %. On more than one thread the phase runs on
    /// the team a run keeps awake, as in [`Simulation::run`]; on rayon alone it scaled
    /// 1.32x from one thread to two where runs scale 1.65-1.85x.
    pub fn time_pair_phase(&mut self, reps: usize) -> f64 {
        let saved = self.pairs.history.clone();
        // One entry into the pool: entering it per repetition would time a thread handoff.
        let seconds = self.on_team(|sim, team| {
            let mut seconds = 0.0;
            for _ in 0..reps {
                sim.pairs.history.copy_from_slice(&saved);
                let t = std::time::Instant::now();
                std::hint::black_box(sim.pair_phase(team));
                seconds += t.elapsed().as_secs_f64();
                // As the particle phase leaves them (untimed: it readies them as it reads
                // this step's).
                sim.next_ready = None;
                sim.ready_next_sums();
            }
            seconds
        });
        self.pairs.history.copy_from_slice(&saved);
        seconds
    }

    /// Sets the sums the next pair phase adds to (`m g` and zero), unless the particle phase
    /// readied them for these particles and this gravity.
    fn ready_next_sums(&mut self) {
        let p = &self.particles;
        let ready = self.next_ready.map(|g| g.to_array().map(f64::to_bits))
            == Some(self.gravity.to_array().map(f64::to_bits));
        if ready && self.next_force.len() == p.len() {
            return;
        }
        self.next_force.resize(p.len(), DVec3::ZERO);
        self.next_torque.resize(p.len(), DVec3::ZERO);
        start_sums(
            &mut self.next_force,
            &mut self.next_torque,
            &p.mass,
            self.gravity,
        );
        self.next_ready = Some(self.gravity);
    }

    /// The pair phase on this step's state (inside the pool, or on `team`): every listed
    /// pair's forces added to the next sums (readied). Returns the pairs carrying force.
    fn pair_phase(&mut self, team: Option<&Team>) -> usize {
        let (p, model, pairs, schedule) = (
            &self.particles,
            &self.model,
            &mut self.pairs,
            &self.schedule,
        );
        let sums = (&mut self.next_force[..], &mut self.next_torque[..]);
        let times = (self.dt, self.time);
        // Bonds are evaluated one at a time: once bonds are formed, a model runs its whole
        // pair phase so. Before (a bonded sample's filling and compaction; a model whose bond
        // law never forms a bond, as in a repose test) no pair holds a bond, and the lanes
        // give the bits of the scalar pipeline. (A lane form of the bond law was
        // 11 % slower on the UCS test.)
        let path = if self.bonded {
            PairPath::OneByOne
        } else {
            self.pair_path
        };
        add_pair_forces(p, model, pairs, schedule, sums, times, path, team)
    }

    /// How the pair phase evaluates touching contacts: [`crate::contact::LANES`] at a time
    /// through the laws' lane forms (the default), or one at a time (see [`PairPath`]).
    pub fn set_pair_path(&mut self, path: PairPath) {
        self.pair_path = path;
    }

    /// Number of pairs in the neighbour list.
    pub fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// Switches wall `k` on or off (a mould removed, a box wall added): an inactive wall
    /// touches nothing. Its contacts end now; the neighbour lists are rebuilt at once.
    pub fn set_wall_active(&mut self, k: usize, active: bool) {
        if self.walls[k].active != active {
            self.walls[k].active = active;
            self.walls[k].force = DVec3::ZERO;
            self.walls[k].torque = DVec3::ZERO;
            self.rebuild();
        }
    }

    /// Bonds every listed pair closer than the bond law's contact radius sum that has never
    /// been bonded (a broken bond never re-forms). Returns how many bonds formed; none
    /// without a bond law. New bonds carry no load. Call it between steps; the result does
    /// not depend on the thread count.
    pub fn form_bonds(&mut self) -> usize {
        if !self.model.has_bond() {
            return 0;
        }
        let p = &self.particles;
        let list = &mut self.pairs;
        let stride = list.stride;
        let mut formed = 0;
        let mut shortest = f64::INFINITY;
        for k in 0..list.len() {
            let (i, j) = (list.i[k] as usize, list.j[k] as usize);
            let h = &mut list.history[k * stride..(k + 1) * stride];
            let key = (p.id[i].min(p.id[j]), p.id[i].max(p.id[j]));
            if self.retired_bonds.contains_key(&key) {
                continue;
            }
            let (a, b) = (p.material[i] as usize, p.material[j] as usize);
            let r = (p.radius[i], p.radius[j]);
            if self
                .model
                .form_bond(a, b, r, (p.position[j] - p.position[i]).length(), h)
            {
                formed += 1;
                let mass = p.mass[i].min(p.mass[j]);
                if let Some(t) = self.model.bond_time_scale(a, b, mass, r) {
                    shortest = shortest.min(t);
                }
            }
        }
        self.bonded |= formed > 0;
        if let Some(w) = bond_step_warning(self.dt, shortest) {
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
        }
        formed
    }

    /// Every bond ever formed, intact or broken, ordered by particle ids (`i < j`, stable
    /// ids, not indices), with the loads on particle i (zero once broken) and the time it
    /// broke.
    pub fn bonds(&self) -> Vec<BondState> {
        let p = &self.particles;
        let list = &self.pairs;
        let stride = list.stride;
        let mut out: Vec<BondState> = (0..list.len())
            .filter_map(|k| {
                let (i, j) = (list.i[k] as usize, list.j[k] as usize);
                let h = &list.history[k * stride..(k + 1) * stride];
                let (loads, broken_time) =
                    self.model
                        .bond_loads(p.material[i] as usize, p.material[j] as usize, h)?;
                // The list keeps each pair in the row of its smaller id.
                debug_assert!(p.id[i] < p.id[j]);
                Some(BondState {
                    i: p.id[i],
                    j: p.id[j],
                    loads,
                    broken_time,
                })
            })
            .collect();
        out.extend(self.retired_bonds.iter().map(|(&(i, j), &t)| BondState {
            i,
            j,
            loads: Default::default(),
            broken_time: Some(t),
        }));
        out.sort_unstable_by_key(|b| (b.i, b.j));
        out
    }

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
    fn refresh_kick_factor(&mut self) {
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

    /// Numbers of intact and of broken bonds.
    pub fn bond_counts(&self) -> (usize, usize) {
        if !self.bonded {
            return (0, 0);
        }
        let list = &self.pairs;
        let stride = list.stride;
        let (mut intact, mut broken) = (0, self.retired_bonds.len());
        for k in 0..list.len() {
            match self
                .model
                .bond_status(&list.history[k * stride..(k + 1) * stride])
            {
                BondStatus::Intact => intact += 1,
                BondStatus::Broken(_) => broken += 1,
                BondStatus::None => {}
            }
        }
        (intact, broken)
    }

    /// Contacts that currently carry force (pairs, then walls).
    pub fn contact_counts(&self) -> (usize, usize) {
        let pairs = self.pairs_carrying;
        let walls = self
            .walls_near
            .force
            .iter()
            .filter(|f| **f != DVec3::ZERO)
            .count();
        (pairs, walls)
    }

    /// Heap bytes held by particles, the pair list and the wall contacts.
    pub fn heap_bytes(&self) -> usize {
        self.particles.heap_bytes()
            + self.pairs.heap_bytes()
            + self.ref_position.capacity() * 24
            + self.kick_factor.capacity() * 16
            + (self.next_force.capacity() + self.next_torque.capacity()) * 24
            + self.walls_near.heap_bytes()
            + self.wall_shares.capacity() * 48
            // A B-tree entry (two ids and a time) with its share of the node, roughly.
            + self.retired_bonds.len() * 24
    }

    /// FNV-1a hash of the bits of every position, velocity and spin, in particle-id order:
    /// equal hashes mean bit-identical states.
    pub fn state_hash(&self) -> u64 {
        let mut h: u64 = 0xcbf29ce484222325;
        let p = &self.particles;
        // In id order, so the hash does not depend on how particles are currently sorted.
        let mut by_id: Vec<usize> = (0..p.len()).collect();
        by_id.sort_unstable_by_key(|&i| p.id[i]);
        for arr in [&p.position, &p.velocity, &p.angular_velocity] {
            for v in by_id.iter().map(|&i| &arr[i]) {
                for x in v.to_array() {
                    for b in x.to_bits().to_le_bytes() {
                        h ^= b as u64;
                        h = h.wrapping_mul(0x100000001b3);
                    }
                }
            }
        }
        h
    }
}

/// Refuses a time step that is not a positive number.
fn check_dt(dt: f64) -> Result<()> {
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
fn rayleigh_step_warning(dt: f64, t_r: f64) -> Option<String> {
    (dt > WARN_FRACTION * t_r).then(|| {
        format!(
            "time step {dt:.3e} s is {:.0} % of the Rayleigh time {t_r:.3e} s; EDEM practice is 20-40 %, above that contacts may be unstable",
            100.0 * dt / t_r
        )
    })
}

/// The warning for a step `dt` too long for the shortest bond time scale `t_b` (s) formed.
fn bond_step_warning(dt: f64, t_b: f64) -> Option<String> {
    (dt > BOND_WARN_FRACTION * t_b).then(|| {
        format!(
            "time step {dt:.3e} s is {:.0} % of the stiffest bond's time scale sqrt(m / (S A)) = {t_b:.3e} s; above {:.0} % bonded particles may gain energy until the run blows up: shorten the step to {:.3e} s or soften the bonds",
            100.0 * dt / t_b,
            100.0 * BOND_WARN_FRACTION,
            0.8 * BOND_WARN_FRACTION * t_b
        )
    })
}

/// The cheap test, as the two halves below make it: false for every state [`check`]
/// refuses (and for a few it accepts, such as a finite spin too large to square).
#[cfg(test)]
fn plausible(x: DVec3, v: DVec3, w: DVec3, limit2: f64, dom: Aabb) -> bool {
    plausible_position(x, dom) & plausible_motion(v, w, limit2)
}

// The cheap test in two halves, each made where what it tests changes: the position in the
// drift, while it is in registers; the velocities in the particle phase, after its kick.
// Written with `&`, not `&&`: no branch per particle. The exact test on each particle took
// about a fifth of the particle phase in a dilute flow; the cheap one about half as much,
// and loading each position again for it was most of what was left.

/// The velocity half of the cheap test.
#[inline(always)]
fn plausible_motion(v: DVec3, w: DVec3, limit2: f64) -> bool {
    let (v2, w2) = (v.length_squared(), w.length_squared());
    // A NaN fails every comparison; an infinity makes its square infinite.
    (v2 <= limit2) & (v2 < f64::INFINITY) & (w2 < f64::INFINITY)
}

/// The position half of the cheap test.
#[inline(always)]
fn plausible_position(x: DVec3, dom: Aabb) -> bool {
    (x.length_squared() < f64::INFINITY)
        & (x.x >= dom.min.x)
        & (x.y >= dom.min.y)
        & (x.z >= dom.min.z)
        & (x.x <= dom.max.x)
        & (x.y <= dom.max.y)
        & (x.z <= dom.max.z)
}

/// What is wrong with a particle after its kick, if anything.
#[inline]
fn check(x: DVec3, v: DVec3, w: DVec3, limit2: f64, dom: Aabb) -> Option<Failure> {
    if !(x.is_finite() && v.is_finite() && w.is_finite()) {
        Some(Failure::NonFinite)
    } else if v.length_squared() > limit2 {
        Some(Failure::Runaway)
    } else if x.cmplt(dom.min).any() || x.cmpgt(dom.max).any() {
        Some(Failure::Escaped)
    } else {
        None
    }
}

#[derive(Debug, Clone, Copy)]
enum Failure {
    NonFinite,
    Runaway,
    Escaped,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every state the exact test refuses, the cheap one flags: a failure is never missed.
    /// Components from finite, huge, infinite and NaN values, against finite and infinite
    /// domains and speed limits.
    #[test]
    fn the_cheap_test_flags_every_state_the_exact_one_refuses() {
        let values = [
            0.0,
            0.5,
            -0.5,
            2.0,
            -2.0,
            1e200,
            -1e200,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let domains = [
            Aabb {
                min: DVec3::splat(-1.0),
                max: DVec3::splat(1.0),
            },
            Aabb {
                min: DVec3::splat(f64::NEG_INFINITY),
                max: DVec3::splat(f64::INFINITY),
            },
        ];
        let mut refused = 0;
        for dom in domains {
            for limit2 in [1.0, f64::INFINITY] {
                for &a in &values {
                    for &b in &values {
                        // One odd component on each vector in turn, the rest ordinary.
                        let odd = [
                            (DVec3::new(a, 0.1, b), DVec3::splat(0.1), DVec3::splat(0.1)),
                            (DVec3::splat(0.1), DVec3::new(0.1, a, b), DVec3::splat(0.1)),
                            (DVec3::splat(0.1), DVec3::splat(0.1), DVec3::new(b, 0.1, a)),
                        ];
                        for (x, v, w) in odd {
                            let exact = check(x, v, w, limit2, dom);
                            let cheap = plausible(x, v, w, limit2, dom);
                            if exact.is_some() {
                                refused += 1;
                                assert!(!cheap, "missed {exact:?} at x {x} v {v} w {w}");
                            }
                        }
                    }
                }
            }
        }
        // The grid does reach the failures, and the cheap test passes ordinary states.
        assert!(refused > 500, "{refused}");
        assert!(plausible(
            DVec3::splat(0.1),
            DVec3::splat(0.1),
            DVec3::splat(0.1),
            1.0,
            domains[0]
        ));
    }
}
