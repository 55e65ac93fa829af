//! The step loop: [`Simulation::run`] and [`Simulation::advance`], the team of threads a run
//! keeps awake, and one velocity-Verlet step: first half kick and drift, walls, factories,
//! reorder and list rebuild when due, then the force evaluation with the second half kick.

use super::checks::plausible_position;
use super::drift::{ChunkMotion, Drift, kick_and_drift};
use super::team::Team;
use super::{INSERT_EVERY, SORT_EVERY, Simulation};
use crate::error::Result;
use crate::neighbor::{CHUNK, chunks_per_task};
use crate::timing::Laps;
use glam::DVec3;
use rayon::prelude::*;

impl Simulation {
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
    pub(super) fn on_team<R: Send>(
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

    /// Lets the factories create the particles due by now; returns how many were created.
    pub(super) fn insert_particles(&mut self) -> usize {
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
}
