//! The pair phase in lanes: a block's touching pairs gathered [`LANES`] at a time and
//! evaluated through the laws' lane forms ([`LaneLaws::evaluate_lanes`]), each
//! pair's output then added to the force sums in list order, as the scalar loop adds it.
//! A pair the lanes do not take (an established contact that no longer touches, which may
//! end; coincident centres) goes through the scalar pipeline between two batches, so the
//! sums see every pair in list order and come out with the scalar loop's bits.
//!
//! The body is compiled once per instruction set (AVX-512, AVX2, the baseline), for the
//! slots' enums and for each compiled law set (`law_sets.rs`), and the CPU's best is
//! picked at run time: the lane loops become vector instructions of the
//! width the CPU has. IEEE operations give the same bits on each.

use super::{Ctx, PairPath, pair_force};
use crate::contact::lanes::{F, LANES, V, map};
use crate::contact::model::ACTIVE;
use crate::contact::{ContactLanes, LaneLaws, contact_lanes::SpheresLanes};
use crate::neighbor::schedule::Block;
use glam::DVec3;

/// Up to [`LANES`] pairs waiting for evaluation: their particles, the start of their
/// history rows in the block's, their material pair, and room for their bodies (kept:
/// filled afresh for each batch, not zeroed).
struct Batch {
    i: [usize; LANES],
    j: [usize; LANES],
    at: [usize; LANES],
    count: usize,
    materials: (usize, usize),
    spheres: SpheresLanes,
}

/// A pair whose `|d|^2 < (r_i + r_j)^2 * SURELY_TOUCHING` (and `> 0`) touches as `Contact`
/// decides it, `r_i + r_j - sqrt(|d|^2) > 0`, whatever the rounding: the square and the
/// product carry at most 2.3e-16 relative error (two roundings of 1.1e-16), leaving
/// `|d|^2 < (r_i + r_j)^2 (1 - 7.7e-16)`; the exact root is then below
/// `(r_i + r_j)(1 - 3.8e-16)`, and its rounding (1.1e-16 at most) keeps it below
/// `r_i + r_j`. A difference of two distinct finite doubles has the sign of the exact one.
/// Pairs nearer the edge take the exact test.
const SURELY_TOUCHING: f64 = 1.0 - 1e-15;

thread_local! {
    /// Each thread's list of a block's candidate pairs, kept from block to block: a block's
    /// is too large for the allocator's per-thread cache, and two threads allocating it at
    /// once would wait on its lock.
    static CANDIDATES: std::cell::Cell<Vec<u32>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Writes to `out` the block's pairs that may interact, in list order, and returns how
/// many: the position `k` of each in the block's list, with bit 31 set when it surely
/// touches (see [`SURELY_TOUCHING`]). `first`, `partner` and the history rows are the
/// block's. The scalar loop's test (a model with bonds does not come here), negated as
/// written there, NaN included.
///
/// A small function of its own, not inlined into the block: inside the block's body, the
/// compiler ran short of registers and reloaded the slices from the stack at every pair.
#[inline(never)]
fn find_candidates(
    first: &[u32],
    partner: &[u32],
    position: &[DVec3],
    radius: &[f64],
    (history, stride): (&[f64], usize),
    out: &mut [u32],
) -> usize {
    let len = first.len();
    assert!(partner.len() == len && out.len() >= len && history.len() >= len * stride);
    assert!(ACTIVE < stride);
    let np = position.len().min(radius.len());
    let mut n = 0;
    // Without a branch: whether a listed pair interacts is close to a coin toss, which the
    // branch predictor loses.
    for k in 0..len {
        let (i, j) = (first[k] as usize, partner[k] as usize);
        assert!(i.max(j) < np);
        // SAFETY: `i, j < np` (checked above), `n <= k < len <= out.len()` and
        // `k * stride + ACTIVE < (k + 1) * stride <= len * stride <= history.len()` (checked
        // before the loop).
        unsafe {
            let d = *position.get_unchecked(j) - *position.get_unchecked(i);
            let rsum = radius.get_unchecked(i) + radius.get_unchecked(j);
            let (dist2, rr) = (d.length_squared(), rsum * rsum);
            // `&`, not `&&`: both sides are cheap, and a second branch would be mispredicted.
            let skip = (*history.get_unchecked(k * stride + ACTIVE) == 0.0) & (dist2 >= rr);
            // Touching for certain, as `Contact` decides it (`r_i + r_j - |d| > 0` and
            // `|d| != 0`), without the square root: see [`SURELY_TOUCHING`].
            let surely = (dist2 > 0.0) & (dist2 < rr * SURELY_TOUCHING);
            *out.get_unchecked_mut(n) = k as u32 | (surely as u32) << 31;
            n += !skip as usize;
        }
    }
    n
}

impl Ctx<'_> {
    /// [`Ctx::block`] through the lanes, with `laws` (the model or its compiled law set), on
    /// the widest vector instructions the CPU has that `path` allows.
    #[inline(always)]
    pub(super) fn block_lanes_by<E: LaneLaws>(
        &self,
        laws: &E,
        path: PairPath,
        block: &Block,
        history: &mut [f64],
        force: &mut [DVec3],
        torque: &mut [DVec3],
    ) -> usize {
        #[cfg(target_arch = "x86_64")]
        {
            let avx512 = matches!(path, PairPath::Lanes | PairPath::LanesEnums);
            let avx2 = avx512 || path == PairPath::LanesAvx2;
            if avx512 && std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has the features the function is compiled for.
                return unsafe { self.block_lanes_avx512(laws, block, history, force, torque) };
            }
            if avx2 && std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: as above.
                return unsafe { self.block_lanes_avx2(laws, block, history, force, torque) };
            }
        }
        self.block_lanes_body(laws, block, history, force, torque)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2,avx")]
    unsafe fn block_lanes_avx512<E: LaneLaws>(
        &self,
        laws: &E,
        block: &Block,
        history: &mut [f64],
        force: &mut [DVec3],
        torque: &mut [DVec3],
    ) -> usize {
        self.block_lanes_body(laws, block, history, force, torque)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx")]
    unsafe fn block_lanes_avx2<E: LaneLaws>(
        &self,
        laws: &E,
        block: &Block,
        history: &mut [f64],
        force: &mut [DVec3],
        torque: &mut [DVec3],
    ) -> usize {
        self.block_lanes_body(laws, block, history, force, torque)
    }

    /// Inlined into each instruction set's copy above.
    #[inline(always)]
    fn block_lanes_body<E: LaneLaws>(
        &self,
        laws: &E,
        block: &Block,
        history: &mut [f64],
        force: &mut [DVec3],
        torque: &mut [DVec3],
    ) -> usize {
        let p = self.p;
        let (lo, stride) = (block.touch.start, self.stride);
        let base = self.row_start[block.rows.start] as usize;
        let end = self.row_start[block.rows.end] as usize;
        let mut candidates = CANDIDATES.take();
        candidates.clear();
        candidates.resize(end - base, 0);
        let n = find_candidates(
            &self.first[base..end],
            &self.partner[base..end],
            &p.position,
            &p.radius,
            (&history[..], stride),
            &mut candidates,
        );
        let mut carrying = 0;
        let mut lanes_history = vec![F::ZERO; stride];
        let mut batch = Batch {
            i: [0; LANES],
            j: [0; LANES],
            at: [0; LANES],
            count: 0,
            materials: (0, 0),
            spheres: SpheresLanes::ZERO,
        };
        for &c in &candidates[..n] {
            let kk = (c & !(1 << 31)) as usize;
            let k = base + kk;
            let (i, j) = (self.first[k] as usize, self.partner[k] as usize);
            let at = kk * stride;
            let touching = c >> 31 != 0 || {
                let d = p.position[j] - p.position[i];
                let dist = d.length_squared().sqrt();
                // As `Contact` computes it.
                let overlap = p.radius[i] + p.radius[j] - dist;
                overlap > 0.0 && dist != 0.0
            };
            let materials = (p.material[i] as usize, p.material[j] as usize);
            if touching {
                if batch.count > 0 && batch.materials != materials {
                    carrying += self.flush(
                        laws,
                        &mut batch,
                        history,
                        &mut lanes_history,
                        force,
                        torque,
                        lo,
                    );
                }
                batch.materials = materials;
                (batch.i[batch.count], batch.j[batch.count]) = (i, j);
                batch.at[batch.count] = at;
                batch.count += 1;
                if batch.count == LANES {
                    carrying += self.flush(
                        laws,
                        &mut batch,
                        history,
                        &mut lanes_history,
                        force,
                        torque,
                        lo,
                    );
                }
                continue;
            }
            carrying += self.flush(
                laws,
                &mut batch,
                history,
                &mut lanes_history,
                force,
                torque,
                lo,
            );
            let h = &mut history[at..at + stride];
            if let Some(o) = pair_force(p, self.model, i, j, h, self.dt, self.time) {
                force[i - lo] += o.force;
                torque[i - lo] += o.torque_i;
                force[j - lo] -= o.force;
                torque[j - lo] += o.torque_j;
                carrying += (o.force != DVec3::ZERO) as usize;
            }
        }
        carrying += self.flush(
            laws,
            &mut batch,
            history,
            &mut lanes_history,
            force,
            torque,
            lo,
        );
        CANDIDATES.set(candidates);
        carrying
    }

    /// Evaluates the batch's pairs and adds their outputs to the force sums in list
    /// order; empties the batch. Returns the pairs carrying force.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn flush<E: LaneLaws>(
        &self,
        laws: &E,
        batch: &mut Batch,
        history: &mut [f64],
        lanes_history: &mut [F],
        force: &mut [DVec3],
        torque: &mut [DVec3],
        lo: usize,
    ) -> usize {
        let count = batch.count;
        if count == 0 {
            return 0;
        }
        batch.count = 0;
        let p = self.p;
        let stride = self.stride;
        // Each lane's particles and history row; lanes past `count` repeat lane 0: finite
        // values whose results are dropped.
        let mut i = [0usize; LANES];
        let mut j = [0usize; LANES];
        let mut at = [0usize; LANES];
        for l in 0..LANES {
            let from = if l < count { l } else { 0 };
            (i[l], j[l], at[l]) = (batch.i[from], batch.j[from], batch.at[from]);
        }
        let n = p.len();
        assert!(i.iter().chain(&j).all(|&q| q < n));
        assert!(at.iter().all(|&a| a + stride <= history.len()));
        // Component by component over the lanes, which the compiler turns into vector
        // gathers: a few per cent off the pair phase against loading lane by lane into the
        // batch (2-12 % by the measure).
        // SAFETY (both macros): every index was checked against its slice's length above
        // (a slice of `DVec3` viewed as `f64` holds three per particle).
        macro_rules! scalar {
            ($src:expr, $idx:ident) => {
                map!(|l| unsafe { *$src.get_unchecked($idx[l]) })
            };
        }
        macro_rules! vector {
            ($src:expr, $idx:ident) => {{
                let src: &[f64] = bytemuck::cast_slice($src);
                V {
                    x: map!(|l| unsafe { *src.get_unchecked(3 * $idx[l]) }),
                    y: map!(|l| unsafe { *src.get_unchecked(3 * $idx[l] + 1) }),
                    z: map!(|l| unsafe { *src.get_unchecked(3 * $idx[l] + 2) }),
                }
            }};
        }
        let s = &mut batch.spheres;
        // As `Contact` computes them: `d = x_j - x_i`, `dist = sqrt(d . d)`.
        s.d = vector!(&p.position, j) - vector!(&p.position, i);
        s.dist = s.d.length();
        s.r = (scalar!(p.radius, i), scalar!(p.radius, j));
        s.m = (scalar!(p.mass, i), scalar!(p.mass, j));
        s.inertia = (scalar!(p.inertia, i), scalar!(p.inertia, j));
        s.v = (vector!(&p.velocity, i), vector!(&p.velocity, j));
        s.w = (
            vector!(&p.angular_velocity, i),
            vector!(&p.angular_velocity, j),
        );
        for (v, h) in lanes_history.iter_mut().enumerate() {
            // SAFETY: `at[l] + v < at[l] + stride <= history.len()`, checked above.
            *h = map!(|l| unsafe { *history.get_unchecked(at[l] + v) });
        }
        let c = ContactLanes::between_spheres(s, self.dt, count);
        let (a, b) = batch.materials;
        let Some(out) = laws.evaluate_lanes(a, b, &c, lanes_history) else {
            return 0;
        };
        let mut carrying = 0;
        // Each lane's particles and history row as gathered above.
        for l in 0..count {
            let (i, j, at) = (i[l], j[l], at[l]);
            for (v, h) in lanes_history.iter().enumerate() {
                // SAFETY: `at + v < at + stride <= history.len()`, checked above.
                unsafe { *history.get_unchecked_mut(at + v) = h.0[l] };
            }
            let f = out.force.lane(l);
            force[i - lo] += f;
            torque[i - lo] += out.torque_i.lane(l);
            force[j - lo] -= f;
            torque[j - lo] += out.torque_j.lane(l);
            carrying += (f != DVec3::ZERO) as usize;
        }
        carrying
    }
}

#[cfg(test)]
mod tests {
    use super::SURELY_TOUCHING;
    use rand::{Rng, SeedableRng};

    /// Just below the threshold, for radii spread over six decades (and so over the
    /// doubles' mantissas), the exact test agrees: `r - sqrt(d2) > 0`.
    #[test]
    fn a_pair_surely_touching_touches_by_the_exact_test() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200_000 {
            let rsum: f64 = 10f64.powf(rng.random_range(-6.0..0.0));
            let rr = rsum * rsum;
            let edge = rr * SURELY_TOUCHING;
            for ulps in 1..8u64 {
                let d2 = f64::from_bits(edge.to_bits() - ulps);
                assert!(
                    rsum - d2.sqrt() > 0.0,
                    "r {rsum:e}, |d|^2 {d2:e} ({ulps} ulps below the threshold)"
                );
            }
        }
    }
}
