//! The pair phase: every listed pair's force and torques through the contact laws, added to
//! both particles' partial sums as they are computed, block by block of the
//! [`PairSchedule`] (see there why the sums come out the same on any number of threads).

use super::team::{Team, map_items};
use crate::contact::{Contact, ContactModel, ContactOut};
use crate::neighbor::pairs::resized;
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

/// Each block's partial sums of force and torque (see [`PairSchedule`]). Zero between
/// steps: the particle phase zeroes each sum as it adds it ([`PartialSums::by_chunk`]), so
/// the pair phase adds to them without zeroing them first (a pass over 96 bytes per
/// particle that took 4-5 % of a settling-bed run; BENCHMARKS.md, twenty-third sitting).
#[derive(Debug, Default)]
pub(super) struct PartialSums {
    pub force: Vec<DVec3>,
    pub torque: Vec<DVec3>,
}

/// The partial sums of one block for particles `start..start + force.len()`, lent to the
/// particle-phase chunk holding those particles.
pub(super) struct SumRows<'a> {
    pub start: usize,
    pub force: &'a mut [DVec3],
    pub torque: &'a mut [DVec3],
}

impl PartialSums {
    /// The sums cut for chunks of `chunk` particles out of `n`: every block's rows for
    /// chunk c, in block order, are `rows[bounds[c]..bounds[c + 1]]`.
    pub fn by_chunk(
        &mut self,
        schedule: &PairSchedule,
        n: usize,
        chunk: usize,
    ) -> (Vec<SumRows<'_>>, Vec<usize>) {
        // What is left of each block's sums: the particles below the current chunk are cut off.
        let mut rest: Vec<SumRows> = Vec::with_capacity(schedule.blocks.len());
        let (mut f, mut t) = (&mut self.force[..], &mut self.torque[..]);
        for b in &schedule.blocks {
            let (bf, tail) = std::mem::take(&mut f).split_at_mut(b.touch.len());
            f = tail;
            let (bt, tail) = std::mem::take(&mut t).split_at_mut(b.touch.len());
            t = tail;
            rest.push(SumRows {
                start: b.touch.start,
                force: bf,
                torque: bt,
            });
        }
        let chunks = n.div_ceil(chunk);
        let mut rows = Vec::with_capacity(2 * chunks + rest.len());
        let mut bounds = Vec::with_capacity(chunks + 1);
        bounds.push(0);
        for c in 0..chunks {
            let end = ((c + 1) * chunk).min(n);
            for r in &mut rest {
                if r.start < end && !r.force.is_empty() {
                    let len = (end - r.start).min(r.force.len());
                    let (f, tail) = std::mem::take(&mut r.force).split_at_mut(len);
                    r.force = tail;
                    let (t, tail) = std::mem::take(&mut r.torque).split_at_mut(len);
                    r.torque = tail;
                    rows.push(SumRows {
                        start: r.start,
                        force: f,
                        torque: t,
                    });
                    r.start += len;
                }
            }
            bounds.push(rows.len());
        }
        (rows, bounds)
    }
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
    // Bonds are evaluated by the scalar pipeline only: the simulation picks `OneByOne` once
    // bonds are formed.
    debug_assert!(path == PairPath::OneByOne || !pairs_hold_bonds(model, history, stride));
    // Sized at a new schedule only, with an eighth to spare rather than doubling: at
    // 100,000 particles they are 10 MB. Zero, as the last particle phase left them, so
    // only what they grow by needs zeroing (all of it was, serially, at every rebuild).
    if sums.force.len() != schedule.sums_len {
        resized(&mut sums.force, schedule.sums_len);
        resized(&mut sums.torque, schedule.sums_len);
    }
    debug_assert!(
        sums.force
            .iter()
            .chain(&sums.torque)
            .all(|&s| s == DVec3::ZERO)
    );
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
    map_items(team, tasks, |_, (block, h, f, t)| match path {
        PairPath::OneByOne => ctx.block(block, h, f, t),
        lanes => ctx.block_lanes(lanes, block, h, f, t),
    })
    .into_iter()
    .sum()
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
    /// One block's pairs in list order; `force` and `torque` are the block's partial sums
    /// (of particles `block.touch`, zero on entry), `history` its history rows. Returns the pairs carrying
    /// force.
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
