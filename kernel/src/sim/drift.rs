//! The first half kick and drift (v += F dt/2m, omega += T dt/2I, x += v dt) of a chunk of
//! particles, with what it finds for the neighbour list and the failure checks. A step
//! runs it in a pass of its own, or, within [`Simulation::run`], in the step before's
//! particle phase as soon as a chunk's second half kick is done.

use super::{Aabb, CHUNK, Failure, Simulation, plausible_position};
use glam::DVec3;

/// What the first half kick and drift found: the largest squared displacement since the
/// last list build (m^2), and whether every new position passed [`plausible_position`].
#[derive(Debug, Clone, Copy)]
pub(super) struct Drift {
    pub max_disp2: f64,
    pub positions_ok: bool,
}

impl Drift {
    pub fn none() -> Drift {
        Drift {
            max_disp2: 0.0,
            positions_ok: true,
        }
    }

    pub fn join(self, other: Drift) -> Drift {
        Drift {
            max_disp2: self.max_disp2.max(other.max_disp2),
            positions_ok: self.positions_ok & other.positions_ok,
        }
    }
}

/// A chunk of particles' motion: what the first half kick and drift change and read.
pub(super) struct ChunkMotion<'a> {
    pub x: &'a mut [DVec3],
    pub v: &'a mut [DVec3],
    pub w: &'a mut [DVec3],
    pub f: &'a [DVec3],
    pub t: &'a [DVec3],
    pub kf: &'a [(f64, f64)],
    pub x0: &'a [DVec3],
}

/// The first half kick and the drift of one chunk (v += F dt/2m, omega += T dt/2I,
/// x += v dt), with its largest displacement from `x0` and the cheap position test: the
/// chunk's bounding box, and a sum that is zero only if every coordinate is finite (x * 0 is
/// NaN for an infinite or NaN x).
#[inline]
pub(super) fn kick_and_drift(m: ChunkMotion, dt: f64, dom: Aabb) -> Drift {
    let ChunkMotion {
        x,
        v,
        w,
        f,
        t,
        kf,
        x0,
    } = m;
    // Plain comparisons rather than f64::max and min: those also order NaNs, which costs a
    // chain of extra instructions per particle, and a NaN fails the finite test anyway (a
    // NaN compares false, so it is skipped here just as max and min skip it).
    let (mut worst, mut lo, mut hi, mut zero) = (0.0f64, x[0], x[0], DVec3::ZERO);
    for k in 0..x.len() {
        let (kv, kw) = kf[k];
        let vk = v[k] + f[k] * kv;
        v[k] = vk;
        w[k] += t[k] * kw;
        let xk = x[k] + vk * dt;
        x[k] = xk;
        let d2 = (xk - x0[k]).length_squared();
        worst = if d2 > worst { d2 } else { worst };
        lo = DVec3::select(xk.cmplt(lo), xk, lo);
        hi = DVec3::select(xk.cmpgt(hi), xk, hi);
        zero += xk * 0.0;
    }
    Drift {
        max_disp2: worst,
        positions_ok: zero == DVec3::ZERO
            && plausible_position(lo, dom)
            && plausible_position(hi, dom),
    }
}

/// One chunk's end of the particle phase: it passed the cheap test (with the next step's
/// drift results when it applied them), or it was checked exactly (the first failure).
pub(super) enum ChunkResult {
    Passed(Option<Drift>),
    Checked(Option<(usize, Failure)>),
}

impl Simulation {
    /// The next step's drift results, once the particle phase found no failure: each chunk
    /// it drifted, and the chunks the cheap test flagged but the exact one passed (a spin
    /// whose square overflows, say), drifted now, in the same operations.
    pub(super) fn finish_drift(&mut self, results: &[ChunkResult]) -> Drift {
        let (dt, dom) = (self.dt, self.domain);
        let p = &mut self.particles;
        let mut all = Drift::none();
        for (c, r) in results.iter().enumerate() {
            let d = match r {
                ChunkResult::Passed(Some(d)) => *d,
                _ => {
                    let rows = c * CHUNK..((c + 1) * CHUNK).min(p.len());
                    kick_and_drift(
                        ChunkMotion {
                            x: &mut p.position[rows.clone()],
                            v: &mut p.velocity[rows.clone()],
                            w: &mut p.angular_velocity[rows.clone()],
                            f: &p.force[rows.clone()],
                            t: &p.torque[rows.clone()],
                            kf: &self.kick_factor[rows.clone()],
                            x0: &self.ref_position[rows],
                        },
                        dt,
                        dom,
                    )
                }
            };
            all = all.join(d);
        }
        all
    }

    /// Takes back the next step's drift from the chunks that applied it, when another chunk
    /// failed: the run stops at this step, and its state is this step's end (to rounding).
    pub(super) fn undo_drift(&mut self, results: &[ChunkResult]) {
        let dt = self.dt;
        let p = &mut self.particles;
        for (c, r) in results.iter().enumerate() {
            if let ChunkResult::Passed(Some(_)) = r {
                for i in c * CHUNK..((c + 1) * CHUNK).min(p.len()) {
                    let (kv, kw) = self.kick_factor[i];
                    p.position[i] -= p.velocity[i] * dt;
                    p.velocity[i] -= p.force[i] * kv;
                    p.angular_velocity[i] -= p.torque[i] * kw;
                }
            }
        }
    }
}
