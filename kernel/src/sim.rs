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

use crate::contact::ContactModel;
use crate::factory::Factory;
#[cfg(doc)]
use crate::neighbor::CHUNK;
use crate::neighbor::{PairList, PairSchedule, WallContacts};
use crate::particles::Particles;
use crate::step_check::PackingFrequency;
use crate::timing::PhaseTimes;
use crate::wall::Wall;
use glam::DVec3;
pub use pair_forces::PairPath;
use std::collections::BTreeMap;

mod accessors;
mod bonds;
mod checks;
mod drift;
mod flat;
mod forces;
mod neighbors;
mod pair_forces;
mod setup;
mod stepping;
mod sum_and_kick;
mod team;
mod time_step;
mod wall_forces;

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
