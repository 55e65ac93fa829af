//! The particle phase's second half kick for one chunk: each particle's force and torque
//! (gravity and its pairs', as the pair phase left them, then its walls in list order), then
//! v += F dt/2m, omega += T dt/2I and the velocity half of the cheap test; and the rows the
//! next pair phase adds to, set to gravity's force and no torque.
//!
//! Written coordinate by coordinate over the chunk's flat arrays ([`super::flat`]) and
//! compiled once per instruction set, as the pair phase is: each particle's sum takes the
//! same operations in the same order as one particle at a time, so the bits are the same
//! on every path and thread count.

use super::checks::plausible_motion;
use super::flat::{FLAT, GROUP, length_squared, load3, on_widest, repeat3, spread3, store3};
use super::wall_forces::WallOut;
use crate::contact::lanes::{F, LANES, M, map};
use glam::DVec3;

/// One chunk's rows.
pub(super) struct ChunkSums<'a> {
    /// The force and torque sums the pair phase left (gravity and the pairs').
    pub f: &'a mut [DVec3],
    pub t: &'a mut [DVec3],
    pub v: &'a mut [DVec3],
    pub w: &'a mut [DVec3],
    /// The chunk's masses (kg).
    pub mass: &'a [f64],
    /// The chunk's kick factors (dt/2m, dt/2I), when the step kicks.
    pub kick: Option<&'a [(f64, f64)]>,
    /// The rows the next pair phase adds to: set here to m g and zero.
    pub next_f: &'a mut [DVec3],
    pub next_t: &'a mut [DVec3],
}

/// The chunk's walls: particle `k` of the chunk has outputs `outs[start[k] - base..start[k +
/// 1] - base]`.
pub(super) struct ChunkWalls<'a> {
    pub outs: &'a [WallOut],
    pub start: &'a [u32],
    pub base: usize,
}

on_widest! {
    /// Finishes the sums, kicks and readies the next sums of one chunk; returns whether
    /// every kicked particle passed the velocity half of the cheap test.
    pub(super) fn sum_and_kick(
        c: ChunkSums,
        gravity: DVec3,
        walls: ChunkWalls,
        limit2: f64,
    ) -> bool => sum_and_kick_body
}

/// `m g` for each particle into `f` and zero into `t`: where every force sum starts.
#[inline(always)]
pub(super) fn start_sums(f: &mut [DVec3], t: &mut [DVec3], mass: &[f64], gravity: DVec3) {
    let n = f.len();
    let whole = n - n % GROUP;
    let g = repeat3(gravity.to_array());
    let ff: &mut [f64] = bytemuck::cast_slice_mut(&mut f[..whole]);
    for grp in 0..whole / GROUP {
        let m = spread3(map!(|k| mass[grp * GROUP + k]));
        store3(ff, grp * FLAT, std::array::from_fn(|r| g[r] * m[r]));
    }
    for k in whole..n {
        f[k] = gravity * mass[k];
    }
    bytemuck::cast_slice_mut::<DVec3, f64>(t).fill(0.0);
}

/// Inlined into each instruction set's copy above.
#[inline(always)]
fn sum_and_kick_body(c: ChunkSums, gravity: DVec3, walls: ChunkWalls, limit2: f64) -> bool {
    let ChunkSums {
        f,
        t,
        v,
        w,
        mass,
        kick,
        next_f,
        next_t,
    } = c;
    let n = f.len();
    let whole = n - n % GROUP;
    start_sums(next_f, next_t, mass, gravity);
    for k in 0..n {
        let list = walls.start[k] as usize - walls.base..walls.start[k + 1] as usize - walls.base;
        for o in &walls.outs[list] {
            if o.adds {
                f[k] += o.force;
                t[k] += o.torque;
            }
        }
    }
    let Some(kf) = kick else {
        return true;
    };
    let mut ok = M::splat(true);
    {
        let vf: &mut [f64] = bytemuck::cast_slice_mut(&mut v[..whole]);
        let wf: &mut [f64] = bytemuck::cast_slice_mut(&mut w[..whole]);
        let ff: &[f64] = bytemuck::cast_slice(&f[..whole]);
        let tf: &[f64] = bytemuck::cast_slice(&t[..whole]);
        for grp in 0..whole / GROUP {
            let (at, kf) = (grp * FLAT, &kf[grp * GROUP..(grp + 1) * GROUP]);
            let kv = spread3(map!(|k| kf[k].0));
            let kw = spread3(map!(|k| kf[k].1));
            let (fs, ts) = (load3(ff, at), load3(tf, at));
            let (mut vs, mut ws) = (load3(vf, at), load3(wf, at));
            for r in 0..3 {
                vs[r] += fs[r] * kv[r];
                ws[r] += ts[r] * kw[r];
            }
            store3(vf, at, vs);
            store3(wf, at, ws);
            // As `plausible_motion` tests, lane by lane.
            let (v2, w2) = (length_squared(&vs), length_squared(&ws));
            let inf = F::splat(f64::INFINITY);
            ok = ok & v2.le(F::splat(limit2)) & v2.lt(inf) & w2.lt(inf);
        }
    }
    let mut all = !(!ok).any();
    for k in whole..n {
        let (kv, kw) = kf[k];
        let (vk, wk) = (v[k] + f[k] * kv, w[k] + t[k] * kw);
        v[k] = vk;
        w[k] = wk;
        all &= plausible_motion(vk, wk, limit2);
    }
    all
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Deterministic values of all magnitudes and both signs.
    pub(in crate::sim) fn values(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let u = (s >> 11) as f64 / (1u64 << 53) as f64;
            (u - 0.5) * 10f64.powi((s % 7) as i32 - 3)
        }
    }

    /// One particle at a time, as the particle phase summed and kicked before the flat
    /// loops: the oracle for their bits.
    #[allow(clippy::too_many_arguments)]
    fn one_at_a_time(
        (f, t, v, w): (&mut [DVec3], &mut [DVec3], &mut [DVec3], &mut [DVec3]),
        (next_f, next_t): (&mut [DVec3], &mut [DVec3]),
        mass: &[f64],
        kick: &[(f64, f64)],
        gravity: DVec3,
        walls: &ChunkWalls,
        limit2: f64,
    ) -> bool {
        let mut all = true;
        for k in 0..f.len() {
            let (mut fk, mut tk) = (f[k], t[k]);
            for o in &walls.outs
                [walls.start[k] as usize - walls.base..walls.start[k + 1] as usize - walls.base]
            {
                if o.adds {
                    fk += o.force;
                    tk += o.torque;
                }
            }
            f[k] = fk;
            t[k] = tk;
            let (kv, kw) = kick[k];
            v[k] += fk * kv;
            w[k] += tk * kw;
            all &= plausible_motion(v[k], w[k], limit2);
            next_f[k] = gravity * mass[k];
            next_t[k] = DVec3::ZERO;
        }
        all
    }

    /// The first row whose bits differ, if any.
    pub(in crate::sim) fn first_difference(a: &[DVec3], b: &[DVec3]) -> Option<usize> {
        let bits = |v: &DVec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        assert_eq!(a.len(), b.len());
        (0..a.len()).find(|&k| bits(&a[k]) != bits(&b[k]))
    }

    #[test]
    fn the_flat_loops_give_the_bits_of_one_particle_at_a_time() {
        let mut x = values(7);
        let vec3 = |x: &mut dyn FnMut() -> f64| DVec3::new(x(), x(), x());
        for n in [128usize, 77, 5] {
            for fail in [false, true] {
                let mass: Vec<f64> = (0..n).map(|_| x().abs() + 1e-3).collect();
                let kick: Vec<(f64, f64)> = (0..n).map(|_| (x(), x())).collect();
                let v0: Vec<DVec3> = (0..n).map(|_| vec3(&mut x)).collect();
                let w0: Vec<DVec3> = (0..n).map(|_| vec3(&mut x)).collect();
                let mut f0: Vec<DVec3> = (0..n).map(|_| vec3(&mut x)).collect();
                let t0: Vec<DVec3> = (0..n).map(|_| vec3(&mut x)).collect();
                if fail {
                    f0[n / 2] = DVec3::new(f64::NAN, 0.0, 0.0);
                }
                // Wall outputs for every third particle, two for every ninth.
                let mut start = vec![10u32];
                let mut outs = vec![];
                for k in 0..n {
                    let count = (k % 3 == 0) as usize + (k % 9 == 0) as usize;
                    for q in 0..count {
                        outs.push(WallOut {
                            force: vec3(&mut x),
                            torque: vec3(&mut x),
                            adds: q == 0 || k % 2 == 0,
                        });
                    }
                    start.push(start[k] + count as u32);
                }
                let walls = ChunkWalls {
                    outs: &outs,
                    start: &start,
                    base: 10,
                };
                let gravity = DVec3::new(0.1, -0.2, -9.81);
                let limit2 = 1e12;

                let (mut fa, mut ta) = (f0.clone(), t0.clone());
                let (mut va, mut wa) = (v0.clone(), w0.clone());
                let (mut nfa, mut nta) = (vec![DVec3::ONE; n], vec![DVec3::ONE; n]);
                let expected = one_at_a_time(
                    (&mut fa, &mut ta, &mut va, &mut wa),
                    (&mut nfa, &mut nta),
                    &mass,
                    &kick,
                    gravity,
                    &walls,
                    limit2,
                );
                assert_eq!(expected, !fail);

                type Run = fn(ChunkSums, DVec3, ChunkWalls, f64) -> bool;
                let mut paths: Vec<(&str, Run)> = vec![("baseline", sum_and_kick_body)];
                paths.push(("widest", sum_and_kick));
                for (name, run) in paths {
                    let (mut f, mut t) = (f0.clone(), t0.clone());
                    let (mut v, mut w) = (v0.clone(), w0.clone());
                    let (mut nf, mut nt) = (vec![DVec3::ONE; n], vec![DVec3::ONE; n]);
                    let passed = run(
                        ChunkSums {
                            f: &mut f,
                            t: &mut t,
                            v: &mut v,
                            w: &mut w,
                            mass: &mass,
                            kick: Some(&kick),
                            next_f: &mut nf,
                            next_t: &mut nt,
                        },
                        gravity,
                        ChunkWalls {
                            outs: &outs,
                            start: &start,
                            base: 10,
                        },
                        limit2,
                    );
                    assert_eq!(passed, expected, "{name}, n {n}");
                    for (what, got, want) in [
                        ("force", &f, &fa),
                        ("torque", &t, &ta),
                        ("velocity", &v, &va),
                        ("spin", &w, &wa),
                        ("next force", &nf, &nfa),
                        ("next torque", &nt, &nta),
                    ] {
                        assert_eq!(first_difference(got, want), None, "{name}, n {n}: {what}");
                    }
                }
            }
        }
    }
}
