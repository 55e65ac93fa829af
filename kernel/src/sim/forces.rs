//! One evaluation of every force and torque: the pair phase, then the particle phase, in
//! which each chunk of particles adds its wall contacts to the pair phase's sums and, in a
//! step, takes its second half kick and the failure checks as soon as its forces are known
//! (and, within a run, the next step's first half kick and drift); then the walls' totals.

#[cfg(doc)]
use super::checks::plausible_position;
use super::checks::{Failure, check};
use super::drift::{ChunkMotion, ChunkResult, Drift, kick_and_drift};
use super::pair_forces::{PairPath, add_pair_forces};
use super::sum_and_kick::{ChunkSums, ChunkWalls, start_sums, sum_and_kick};
use super::team::{Team, map_items};
use super::wall_forces::{ChunkBodies, WallCtx, WallList, WallOut, WallRows, chunk_wall_forces};
use super::{Aabb, Simulation};
use crate::neighbor::CHUNK;
use crate::timing::Laps;
use crate::wall::Hit;
use glam::DVec3;

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

/// What every particle-phase chunk reads besides its own rows: the wall contacts' context,
/// the particles' constant properties, and the step's settings.
struct ParticlePhase<'a> {
    wall_ctx: WallCtx<'a>,
    radius: &'a [f64],
    mass: &'a [f64],
    inertia: &'a [f64],
    material: &'a [u16],
    /// m/s^2.
    gravity: DVec3,
    /// Whether the step kicks (not in the evaluation before the first step).
    kick: bool,
    /// Each particle's (dt/2 / m, dt/2 / I).
    kick_factor: &'a [(f64, f64)],
    /// The positions at the last list build, m.
    ref_position: &'a [DVec3],
    /// The squared speed limit, m^2/s^2.
    limit2: f64,
    dom: Aabb,
    /// s.
    dt: f64,
    /// Whether every position passed [`plausible_position`] since it last changed.
    positions_ok: bool,
    /// Whether a chunk that passes its checks applies the next step's drift.
    drift_next: bool,
}

impl Simulation {
    /// Computes every force and torque. With `kick`, also applies the step's second half kick
    /// to each particle as soon as its force is known (one pass over memory instead of two)
    /// and returns the first particle in a failed state. `positions_ok`: whether every
    /// position passed [`plausible_position`] since it last changed; when not, every
    /// particle gets the exact test. With `drift_next` (and `kick`), a particle phase that
    /// finds no failure also applies the next step's first half kick and drift, and
    /// returns its results (see [`Simulation::run`]).
    pub(super) fn compute_forces(
        &mut self,
        kick: bool,
        positions_ok: bool,
        drift_next: bool,
        team: Option<&Team>,
    ) -> (Option<(usize, Failure)>, Option<Drift>) {
        let mut laps = Laps::start();
        let pool = self.pool.clone();
        self.ready_next_sums();
        self.pairs_carrying = pool.install(|| self.pair_phase(team));
        // This step's sums are complete; the old rows become the next step's.
        std::mem::swap(&mut self.particles.force, &mut self.next_force);
        std::mem::swap(&mut self.particles.torque, &mut self.next_torque);
        self.next_ready = None;
        self.times.pair += laps.lap();

        let drift_next = drift_next && kick;
        let results = self.particle_phase(kick, positions_ok, drift_next, team);
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
        self.add_wall_totals(kick);
        self.times.particle += laps.lap();
        (failure, next)
    }

    /// Particle phase: each particle's sum (gravity and its pairs', then its walls), the
    /// second half kick and the checks; and the next step's sums readied. Returns each
    /// chunk's result, in chunk order; leaves each chunk's share of every wall's force and
    /// torque in `wall_shares`. `drift_next` only with `kick`.
    fn particle_phase(
        &mut self,
        kick: bool,
        positions_ok: bool,
        drift_next: bool,
        team: Option<&Team>,
    ) -> Vec<ChunkResult> {
        let dt = self.dt;
        let gravity = self.gravity;
        let stride = self.pairs.stride;
        let wc = &mut self.walls_near;
        let p = &mut self.particles;
        let n = p.len();
        let nwalls = self.walls.len();
        self.wall_shares
            .resize(n.div_ceil(CHUNK) * nwalls, (DVec3::ZERO, DVec3::ZERO));
        let all_rows = WallRows {
            base: 0,
            history: &mut wc.history[..],
            force: &mut wc.force[..],
            point: &mut wc.point[..],
            shares: &mut self.wall_shares[..],
        };
        let wall_chunks = chunk_wall_rows(all_rows, &wc.start, n, nwalls, stride);
        // `advance` refreshed them for this step's particles.
        debug_assert!(!kick || self.kick_factor.len() == n);
        let phase = ParticlePhase {
            wall_ctx: WallCtx {
                list: WallList {
                    wall: &wc.wall,
                    feature: &wc.feature,
                },
                start: &wc.start,
                walls: &self.walls,
                model: &self.model,
                stride,
                dt,
                // Walls bond to nothing: every model runs them on the pair phase's path.
                path: self.pair_path,
            },
            radius: &p.radius,
            mass: &p.mass,
            inertia: &p.inertia,
            material: &p.material,
            gravity,
            kick,
            kick_factor: &self.kick_factor,
            ref_position: &self.ref_position,
            limit2: self.speed_limit * self.speed_limit,
            dom: self.domain,
            dt,
            positions_ok,
            drift_next,
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
        let results: Vec<ChunkResult> = self
            .pool
            .install(|| map_items(team, items, |c, rows| phase.chunk(c, rows)));
        self.next_ready = Some(gravity);
        results
    }

    /// Each wall's force and torque: the chunks' shares, in chunk order; and, in a step
    /// (`kick`), the impulse of this step's force over the step, N s.
    fn add_wall_totals(&mut self, kick: bool) {
        // Summing every contact here, one thread did what the chunks now do on all.
        let nwalls = self.walls.len();
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
}

impl ParticlePhase<'_> {
    /// One chunk of particles: rows c * CHUNK.. of each array, and their wall rows.
    #[inline]
    fn chunk(
        &self,
        c: usize,
        ((((((fs, ts), vs), ws), xs), mut mine), (next_f, next_t)): ChunkRows,
    ) -> ChunkResult {
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
                radius: self.radius,
                mass: self.mass,
                inertia: self.inertia,
                material: self.material,
            };
            chunk_wall_forces(&self.wall_ctx, &bodies, &mut mine, &mut outs, &mut hits);
        }
        let rows = c * CHUNK..c * CHUNK + fs.len();
        // Whether every kicked particle of the chunk passed the cheap test.
        let plausible_all = sum_and_kick(
            ChunkSums {
                f: fs,
                t: ts,
                v: vs,
                w: ws,
                mass: &self.mass[rows.clone()],
                kick: self.kick.then(|| &self.kick_factor[rows.clone()]),
                next_f,
                next_t,
            },
            self.gravity,
            ChunkWalls {
                outs: &outs,
                start: &self.wall_ctx.start[rows.start..rows.end + 1],
                base: mine.base,
            },
            self.limit2,
        );
        WALL_OUTS.set(outs);
        mine.add_wall_shares(&self.wall_ctx.list, self.wall_ctx.walls);
        // The exact test only for a chunk the cheap one flagged: the first
        // failing particle in index order, as a test of each would find it.
        // A chunk it passes is where a failure cannot be (the cheap test is
        // exact for what it passes), so only it may go on to the next drift.
        if plausible_all && self.positions_ok {
            let next = self.drift_next.then(|| {
                kick_and_drift(
                    ChunkMotion {
                        x: xs,
                        v: vs,
                        w: ws,
                        f: fs,
                        t: ts,
                        kf: &self.kick_factor[rows.clone()],
                        x0: &self.ref_position[rows],
                    },
                    self.dt,
                    self.dom,
                )
            });
            return ChunkResult::Passed(next);
        }
        let failed = (0..fs.len()).find_map(|k| {
            let i = c * CHUNK + k;
            check(xs[k], vs[k], ws[k], self.limit2, self.dom).map(|f| (i, f))
        });
        ChunkResult::Checked(failed)
    }
}

/// Splits the wall-contact rows `all` (of every particle, with every chunk's `nwalls`
/// shares) at the boundaries of the chunks of [`CHUNK`] particles, so that each task owns
/// its rows: particle p's rows start at `start[p]`, of `stride` history values each.
fn chunk_wall_rows<'a>(
    all: WallRows<'a>,
    start: &[u32],
    n: usize,
    nwalls: usize,
    stride: usize,
) -> Vec<WallRows<'a>> {
    let WallRows {
        base: mut at,
        history: mut hist,
        mut force,
        mut point,
        mut shares,
    } = all;
    let mut wall_chunks = vec![];
    for c in 0..n.div_ceil(CHUNK) {
        let end = start[((c + 1) * CHUNK).min(n)] as usize;
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
    wall_chunks
}
