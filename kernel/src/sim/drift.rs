//! The first half kick and drift (v += F dt/2m, omega += T dt/2I, x += v dt) of a chunk of
//! particles, with what it finds for the neighbour list and the failure checks. A step
//! runs it in a pass of its own, or, within [`Simulation::run`], in the step before's
//! particle phase as soon as a chunk's second half kick is done.

use super::checks::{Failure, plausible_position};
use super::flat::{FLAT, GROUP, length_squared, load3, on_widest, repeat3, spread3, store3};
use super::{Aabb, Simulation};
use crate::contact::lanes::{F, LANES, map};
use crate::neighbor::CHUNK;
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

on_widest! {
    /// The first half kick and the drift of one chunk (v += F dt/2m, omega += T dt/2I,
    /// x += v dt), with its largest displacement from `x0` and the cheap position test: the
    /// chunk's bounding box, and a sum that is zero only if every coordinate is finite (x * 0 is
    /// NaN for an infinite or NaN x).
    ///
    /// Compiled once per instruction set, as the pair phase is (`sim/pair_forces/lanes.rs`),
    /// and run on the CPU's widest. Each operation is the scalar one of each coordinate, so the
    /// state has the same bits on every path; the scan's results do not depend on the order in
    /// which it sees the coordinates (a NaN fails every comparison, in any order).
    pub(super) fn kick_and_drift(m: ChunkMotion, dt: f64, dom: Aabb) -> Drift => kick_and_drift_body
}

/// Inlined into each instruction set's copy above.
#[inline(always)]
fn kick_and_drift_body(m: ChunkMotion, dt: f64, dom: Aabb) -> Drift {
    let ChunkMotion {
        x,
        v,
        w,
        f,
        t,
        kf,
        x0,
    } = m;
    let n = x.len();
    // Plain comparisons rather than f64::max and min: those also order NaNs, which costs a
    // chain of extra instructions per particle, and a NaN fails the finite test anyway (a
    // NaN compares false, so it is skipped here just as max and min skip it).
    let first = x[0];
    let start = repeat3(first.to_array());
    let (mut worst, mut lo, mut hi, mut zero) = (F::ZERO, start, start, [F::ZERO; 3]);
    let whole = n - n % GROUP;
    {
        // The vectors as flat coordinates: the loop is element-wise but for the kick
        // factors (one per particle, spread over its three coordinates) and the squared
        // displacement (three coordinates summed per particle).
        let xf: &mut [f64] = bytemuck::cast_slice_mut(&mut x[..whole]);
        let vf: &mut [f64] = bytemuck::cast_slice_mut(&mut v[..whole]);
        let wf: &mut [f64] = bytemuck::cast_slice_mut(&mut w[..whole]);
        let ff: &[f64] = bytemuck::cast_slice(&f[..whole]);
        let tf: &[f64] = bytemuck::cast_slice(&t[..whole]);
        let x0f: &[f64] = bytemuck::cast_slice(&x0[..whole]);
        for g in 0..whole / GROUP {
            let (at, kf) = (g * FLAT, &kf[g * GROUP..(g + 1) * GROUP]);
            let kv = spread3(map!(|k| kf[k].0));
            let kw = spread3(map!(|k| kf[k].1));
            let (fs, ts, x0s) = (load3(ff, at), load3(tf, at), load3(x0f, at));
            let (mut vs, mut ws, mut xs) = (load3(vf, at), load3(wf, at), load3(xf, at));
            let mut dx = [F::ZERO; 3];
            for r in 0..3 {
                vs[r] += fs[r] * kv[r];
                ws[r] += ts[r] * kw[r];
                xs[r] += vs[r] * dt;
                dx[r] = xs[r] - x0s[r];
                lo[r] = F::select(xs[r].lt(lo[r]), xs[r], lo[r]);
                hi[r] = F::select(xs[r].gt(hi[r]), xs[r], hi[r]);
                zero[r] += xs[r] * 0.0;
            }
            store3(vf, at, vs);
            store3(wf, at, ws);
            store3(xf, at, xs);
            let d2 = length_squared(&dx);
            worst = F::select(d2.gt(worst), d2, worst);
        }
    }
    let mut worst = worst
        .0
        .into_iter()
        .fold(0.0f64, |a, b| if b > a { b } else { a });
    let (mut lo3, mut hi3, mut zero3) = (first, first, DVec3::ZERO);
    for c in 0..FLAT {
        let (r, k, axis) = (c / LANES, c % LANES, c % 3);
        let (l, h) = (lo[r].0[k], hi[r].0[k]);
        lo3[axis] = if l < lo3[axis] { l } else { lo3[axis] };
        hi3[axis] = if h > hi3[axis] { h } else { hi3[axis] };
        zero3[axis] += zero[r].0[k];
    }
    let (mut lo, mut hi, mut zero) = (lo3, hi3, zero3);
    for k in whole..n {
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

#[cfg(test)]
mod tests {
    use super::super::sum_and_kick::tests::{first_difference, values};
    use super::*;

    /// One particle at a time, as the drift was written before the flat loop: the oracle.
    fn one_at_a_time(m: ChunkMotion, dt: f64, dom: Aabb) -> Drift {
        let ChunkMotion {
            x,
            v,
            w,
            f,
            t,
            kf,
            x0,
        } = m;
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

    #[test]
    fn the_flat_drift_gives_the_bits_of_one_particle_at_a_time() {
        let mut x = values(11);
        let vec3 = |x: &mut dyn FnMut() -> f64| DVec3::new(x(), x(), x());
        let wide = Aabb {
            min: DVec3::splat(-1e6),
            max: DVec3::splat(1e6),
        };
        let narrow = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        for n in [128usize, 77, 5, 1] {
            for (dom, bad) in [
                (wide, None),
                (narrow, None),
                (wide, Some(f64::NAN)),
                (wide, Some(f64::INFINITY)),
            ] {
                let rows = |x: &mut dyn FnMut() -> f64| (0..n).map(|_| vec3(x)).collect::<Vec<_>>();
                let (mut x1, mut v1, mut w1) = (rows(&mut x), rows(&mut x), rows(&mut x));
                let (f, t, x0) = (rows(&mut x), rows(&mut x), rows(&mut x));
                let kf: Vec<(f64, f64)> = (0..n).map(|_| (x(), x())).collect();
                if let Some(b) = bad {
                    x1[n / 2].y = b;
                }
                let (mut x2, mut v2, mut w2) = (x1.clone(), v1.clone(), w1.clone());
                let dt = 1e-3;
                let want = one_at_a_time(
                    ChunkMotion {
                        x: &mut x1,
                        v: &mut v1,
                        w: &mut w1,
                        f: &f,
                        t: &t,
                        kf: &kf,
                        x0: &x0,
                    },
                    dt,
                    dom,
                );
                let got = kick_and_drift(
                    ChunkMotion {
                        x: &mut x2,
                        v: &mut v2,
                        w: &mut w2,
                        f: &f,
                        t: &t,
                        kf: &kf,
                        x0: &x0,
                    },
                    dt,
                    dom,
                );
                assert_eq!(got.max_disp2.to_bits(), want.max_disp2.to_bits(), "n {n}");
                assert_eq!(got.positions_ok, want.positions_ok, "n {n}, {bad:?}");
                // The cases test what they are meant to: a bad coordinate fails, a wide box
                // passes the rest.
                if bad.is_some() || dom.max.x > 1.0 {
                    assert_eq!(want.positions_ok, bad.is_none(), "n {n}");
                }
                for (what, a, b) in [
                    ("position", &x2, &x1),
                    ("velocity", &v2, &v1),
                    ("spin", &w2, &w1),
                ] {
                    assert_eq!(first_difference(a, b), None, "n {n}: {what}");
                }
            }
        }
    }
}
