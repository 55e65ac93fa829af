//! The pair phase: every listed pair's force and torques through the contact laws, added to
//! both particles' partial sums as they are computed, block by block of the
//! [`PairSchedule`] (see there why the sums come out the same on any number of threads).

use super::team::{Team, map_items};
use crate::contact::{Contact, ContactModel, ContactOut};
use crate::neighbor::pairs::zeroed;
use crate::neighbor::schedule::Block;
use crate::neighbor::{PairList, PairSchedule};
use crate::particles::Particles;
use glam::DVec3;

mod lanes;

/// How the pair phase evaluates touching contacts. Every path gives the same bits; the
/// choice is there to show it, and to time one against another.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PairPath {
    /// In lanes, on the widest vector instructions the CPU has (the default).
    #[default]
    Lanes,
    /// In lanes, on AVX2 at most (as on CPUs without AVX-512).
    LanesAvx2,
    /// In lanes, on the instructions every x86-64 CPU has (SSE2).
    LanesBaseline,
    /// One contact at a time through the laws' scalar forms.
    OneByOne,
}

/// Each block's partial sums of force and torque (see [`PairSchedule`]).
#[derive(Debug, Default)]
pub(super) struct PartialSums {
    pub force: Vec<DVec3>,
    pub torque: Vec<DVec3>,
}

/// Evaluates every listed pair and adds its force and torques, on both particles, to the
/// partial sums of its block. Returns how many pairs carry force. Run inside the
/// simulation's thread pool, or on `team`.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_pair_forces(
    p: &Particles,
    model: &ContactModel,
    pairs: &mut PairList,
    schedule: &PairSchedule,
    sums: &mut PartialSums,
    (dt, time): (f64, f64),
    path: PairPath,
    team: Option<&Team>,
) -> usize {
    let PairList {
        row_start,
        i: first,
        j: partner,
        history,
        stride,
        ..
    } = pairs;
    let stride = *stride;
    // Sized at a new schedule only (each block zeroes its own sums below), with an eighth
    // to spare rather than doubling: at 100,000 particles they are 10 MB.
    if sums.force.len() != schedule.sums_len {
        zeroed(&mut sums.force, schedule.sums_len);
        zeroed(&mut sums.torque, schedule.sums_len);
    }
    // Each block's history rows and partial sums (both in block order).
    let mut tasks = Vec::with_capacity(schedule.blocks.len());
    let (mut h_rest, mut f_rest, mut t_rest) =
        (&mut history[..], &mut sums.force[..], &mut sums.torque[..]);
    for b in &schedule.blocks {
        let len = (row_start[b.rows.end] - row_start[b.rows.start]) as usize * stride;
        let (h, tail) = std::mem::take(&mut h_rest).split_at_mut(len);
        h_rest = tail;
        let (f, tail) = std::mem::take(&mut f_rest).split_at_mut(b.touch.len());
        f_rest = tail;
        let (t, tail) = std::mem::take(&mut t_rest).split_at_mut(b.touch.len());
        t_rest = tail;
        tasks.push((b, h, f, t));
    }
    let ctx = Ctx {
        p,
        model,
        row_start,
        first,
        partner,
        stride,
        dt,
        time,
    };
    // Bonds are evaluated by the scalar pipeline only.
    let path = if model.has_bond() {
        PairPath::OneByOne
    } else {
        path
    };
    map_items(team, tasks, |_, (block, h, f, t)| match path {
        PairPath::OneByOne => ctx.block(block, h, f, t),
        lanes => ctx.block_lanes(lanes, block, h, f, t),
    })
    .into_iter()
    .sum()
}

/// What every block reads.
struct Ctx<'a> {
    p: &'a Particles,
    model: &'a ContactModel,
    row_start: &'a [u32],
    first: &'a [u32],
    partner: &'a [u32],
    stride: usize,
    dt: f64,
    time: f64,
}

impl Ctx<'_> {
    /// One block's pairs in list order; `force` and `torque` are the block's partial sums
    /// (of particles `block.touch`), `history` its history rows. Returns the pairs carrying
    /// force.
    fn block(
        &self,
        block: &Block,
        history: &mut [f64],
        force: &mut [DVec3],
        torque: &mut [DVec3],
    ) -> usize {
        force.fill(DVec3::ZERO);
        torque.fill(DVec3::ZERO);
        let (lo, stride) = (block.touch.start, self.stride);
        let base = self.row_start[block.rows.start] as usize;
        let mut carrying = 0;
        // One flat loop over the pairs: nested in rows, the compiler kept particle i's
        // state in registers across the row and ran short of them for the laws.
        let end = self.row_start[block.rows.end] as usize;
        for k in base..end {
            let (i, j) = (self.first[k] as usize, self.partner[k] as usize);
            let h = &mut history[(k - base) * stride..(k - base + 1) * stride];
            if let Some(o) = pair_force(self.p, self.model, i, j, h, self.dt, self.time) {
                force[i - lo] += o.force;
                torque[i - lo] += o.torque_i;
                force[j - lo] -= o.force;
                torque[j - lo] += o.torque_j;
                carrying += (o.force != DVec3::ZERO) as usize;
            }
        }
        carrying
    }
}

/// The force of listed pair (i, j), or `None` when they do not interact. `time` stamps a
/// bond that breaks.
#[inline]
fn pair_force(
    p: &Particles,
    model: &ContactModel,
    i: usize,
    j: usize,
    h: &mut [f64],
    dt: f64,
    time: f64,
) -> Option<ContactOut> {
    let d = p.position[j] - p.position[i];
    let dist2 = d.length_squared();
    let rsum = p.radius[i] + p.radius[j];
    if h[crate::contact::model::ACTIVE] == 0.0 && dist2 >= rsum * rsum && !model.bond_intact(h) {
        return None;
    }
    let dist = dist2.sqrt();
    if dist == 0.0 {
        return None;
    }
    let c = Contact::between_particles(p, i, j, d, dist, dt);
    model.evaluate_pair(p.material[i] as usize, p.material[j] as usize, &c, time, h)
}
