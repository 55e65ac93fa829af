//! The pair phase: every listed pair's force and torques through the contact laws, added to
//! both particles' force sums as they are computed, block by block and phase by phase of
//! the [`PairSchedule`] (see there why the sums come out the same on any number of threads).

use super::team::{Team, map_items};
use crate::contact::{Contact, ContactModel, ContactOut};
use crate::neighbor::schedule::Block;
use crate::neighbor::{PairList, PairSchedule};
use crate::particles::Particles;
use glam::DVec3;

mod lanes;
mod law_sets;

/// How the pair phase and the wall contacts evaluate touching contacts. Every path gives
/// the same bits; the choice is there to show it, and to time one against another.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PairPath {
    /// In lanes, on the widest vector instructions the CPU has (the default), through the
    /// model's compiled law set if it has one (`pair_forces/law_sets.rs`).
    #[default]
    Lanes,
    /// As [`PairPath::Lanes`], but through the slots' enums even where the model's law set
    /// is compiled as its own.
    LanesEnums,
    /// In lanes, on AVX2 at most (as on CPUs without AVX-512).
    LanesAvx2,
    /// In lanes, on the instructions every x86-64 CPU has (SSE2).
    LanesBaseline,
    /// One contact at a time through the laws' scalar forms.
    OneByOne,
}

/// Evaluates every listed pair and adds its force and torques, on both particles, to
/// `force` and `torque` (one row per particle, holding what the sums start from). Returns
/// how many pairs carry force. Run inside the simulation's thread pool, or on `team`.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_pair_forces(
    p: &Particles,
    model: &ContactModel,
    pairs: &mut PairList,
    schedule: &PairSchedule,
    (force, torque): (&mut [DVec3], &mut [DVec3]),
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
    // Bonds are evaluated by the scalar pipeline only: the simulation picks `OneByOne` once
    // bonds are formed.
    debug_assert!(path == PairPath::OneByOne || !pairs_hold_bonds(model, history, stride));
    assert!(force.len() == p.len() && torque.len() == p.len());
    // Each block's history rows (in block order).
    let mut rows: Vec<Option<&mut [f64]>> = Vec::with_capacity(schedule.blocks.len());
    let mut h_rest = &mut history[..];
    for b in &schedule.blocks {
        let len = (row_start[b.rows.end] - row_start[b.rows.start]) as usize * stride;
        let (h, tail) = std::mem::take(&mut h_rest).split_at_mut(len);
        h_rest = tail;
        rows.push(Some(h));
    }
    let ctx = Ctx {
        p,
        model,
        compiled: match path {
            PairPath::LanesEnums | PairPath::OneByOne => None,
            _ => law_sets::CompiledLaws::of(model),
        },
        row_start,
        first,
        partner,
        stride,
        dt,
        time,
    };
    let mut carrying = 0;
    for phase in &schedule.phases {
        // The phase's blocks by where their particles start: their rows of the sums are
        // disjoint (the schedule keeps them so), cut from one pass over the arrays.
        let mut order = phase.clone();
        order.sort_by_key(|&b| schedule.blocks[b].touch.start);
        let mut tasks = Vec::with_capacity(order.len());
        let (mut f_rest, mut t_rest, mut at) = (&mut force[..], &mut torque[..], 0);
        for b in order {
            let block = &schedule.blocks[b];
            let skip = block.touch.start - at;
            let (_, tail) = std::mem::take(&mut f_rest).split_at_mut(skip);
            let (f, tail) = tail.split_at_mut(block.touch.len());
            f_rest = tail;
            let (_, tail) = std::mem::take(&mut t_rest).split_at_mut(skip);
            let (t, tail) = tail.split_at_mut(block.touch.len());
            t_rest = tail;
            at = block.touch.end;
            let h = rows[b].take().expect("each block in one phase");
            tasks.push((block, h, f, t));
        }
        carrying += map_items(team, tasks, |_, (block, h, f, t)| match path {
            PairPath::OneByOne => ctx.block(block, h, f, t),
            lanes => ctx.block_lanes(lanes, block, h, f, t),
        })
        .into_iter()
        .sum::<usize>();
    }
    carrying
}

/// Whether any history row holds an intact bond (for a debug check).
fn pairs_hold_bonds(model: &ContactModel, history: &[f64], stride: usize) -> bool {
    model.has_bond()
        && history
            .chunks_exact(stride)
            .any(|row| model.bond_intact(row))
}

/// What every block reads.
struct Ctx<'a> {
    p: &'a Particles,
    model: &'a ContactModel,
    /// The model's laws as a compiled set, unless it has none or the path takes the enums.
    compiled: Option<law_sets::CompiledLaws<'a>>,
    row_start: &'a [u32],
    first: &'a [u32],
    partner: &'a [u32],
    stride: usize,
    dt: f64,
    time: f64,
}

impl Ctx<'_> {
    /// One block's pairs in list order; `force` and `torque` are the sums of particles
    /// `block.touch`, `history` the block's history rows. Returns the pairs carrying force.
    fn block(
        &self,
        block: &Block,
        history: &mut [f64],
        force: &mut [DVec3],
        torque: &mut [DVec3],
    ) -> usize {
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
