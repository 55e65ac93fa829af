//! A chunk's wall contacts in lanes: the touching contacts of a chunk's particles with walls
//! of which they list one feature (every plane, disc, cylinder and cone; a mesh when one
//! triangle is near), gathered [`LANES`] at a time and
//! evaluated through the laws' lane forms ([`LaneLaws::evaluate_lanes`]). Each wall
//! shape finds its own closest point, so the geometry is computed one contact at a time and
//! packed ([`ContactLanes::gather`]); the laws, most of the work, run in lanes. Contacts
//! that do not touch (which may end) and a mesh's contacts where several triangles are near
//! (the nearer shadow the others) go through the one-at-a-time pipeline. Every contact writes its own slot, so the order
//! of evaluation does not reach the sums.
//!
//! Compiled once per instruction set, as the pair phase's lanes (`sim/pair_forces/lanes.rs`).

use super::{
    ChunkBodies, WallCtx, WallOut, WallRows, evaluate_row, group_one_by_one, groups, wall_contact,
};
use crate::contact::{Contact, ContactLanes, F, LANES, LaneLaws};
#[cfg(target_arch = "x86_64")]
use crate::sim::PairPath;
use crate::wall::Hit;
use glam::DVec3;

/// Up to [`LANES`] touching wall contacts of one material pair waiting for evaluation,
/// filled lane by lane as they come: each one's row (of the chunk's wall rows, also its
/// output slot), contact point (world), contact and history.
struct WallBatch {
    count: usize,
    materials: (usize, usize),
    row: [usize; LANES],
    point: [DVec3; LANES],
    contacts: ContactLanes,
    history: Vec<F>,
}

impl WallBatch {
    fn new(stride: usize) -> WallBatch {
        WallBatch {
            count: 0,
            materials: (0, 0),
            row: [0; LANES],
            point: [DVec3::ZERO; LANES],
            contacts: ContactLanes::ZERO,
            history: vec![F::ZERO; stride],
        }
    }

    /// Adds the contact of row `lq` (history from `history`) in the next lane.
    #[inline(always)]
    fn push(&mut self, lq: usize, point: DVec3, contact: &Contact, history: &[f64]) {
        let l = self.count;
        self.row[l] = lq;
        self.point[l] = point;
        self.contacts.set_lane(l, contact);
        for (h, &x) in self.history.iter_mut().zip(history) {
            h.0[l] = x;
        }
        self.count += 1;
    }
}

/// [`super::chunk_wall_forces`] on the lane path: on the widest vector instructions the CPU
/// has that `ctx.path` allows.
pub(super) fn chunk_wall_forces_lanes(
    ctx: &WallCtx,
    bodies: &ChunkBodies,
    mine: &mut WallRows,
    out: &mut [WallOut],
    hits: &mut Vec<(f64, usize, Hit)>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        let avx512 = matches!(ctx.path, PairPath::Lanes | PairPath::LanesEnums);
        let avx2 = matches!(
            ctx.path,
            PairPath::Lanes | PairPath::LanesEnums | PairPath::LanesAvx2
        );
        if avx512 && std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { lanes_avx512(ctx, bodies, mine, out, hits) };
        }
        if avx2 && std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { lanes_avx2(ctx, bodies, mine, out, hits) };
        }
    }
    lanes_body(ctx, bodies, mine, out, hits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2,avx")]
unsafe fn lanes_avx512(
    ctx: &WallCtx,
    bodies: &ChunkBodies,
    mine: &mut WallRows,
    out: &mut [WallOut],
    hits: &mut Vec<(f64, usize, Hit)>,
) {
    lanes_body(ctx, bodies, mine, out, hits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx")]
unsafe fn lanes_avx2(
    ctx: &WallCtx,
    bodies: &ChunkBodies,
    mine: &mut WallRows,
    out: &mut [WallOut],
    hits: &mut Vec<(f64, usize, Hit)>,
) {
    lanes_body(ctx, bodies, mine, out, hits)
}

/// Inlined into each instruction set's copy above.
#[inline(always)]
fn lanes_body(
    ctx: &WallCtx,
    bodies: &ChunkBodies,
    mine: &mut WallRows,
    out: &mut [WallOut],
    hits: &mut Vec<(f64, usize, Hit)>,
) {
    // Made at the chunk's first touching contact: most chunks have none.
    let mut batch: Option<WallBatch> = None;
    for k in 0..bodies.x.len() {
        let i = bodies.first + k;
        let rows = ctx.start[i] as usize..ctx.start[i + 1] as usize;
        if rows.is_empty() {
            continue;
        }
        let body = bodies.body(k);
        for (w, group) in groups(&ctx.list, rows) {
            let wall = &ctx.walls[w];
            let q = group.start;
            if group.len() > 1 {
                group_one_by_one(ctx, &body, w, group, mine, out, hits);
                continue;
            }
            let h = wall.shape.hit(ctx.list.feature[q], body.x - wall.offset);
            let lq = q - mine.base;
            let contact = match wall_contact(&body, wall, &h, ctx.dt) {
                Some(c) if c.overlap > 0.0 => c,
                other => {
                    evaluate_row(ctx, &body, wall, other, &h, (lq, lq), false, mine, out);
                    continue;
                }
            };
            let b = batch.get_or_insert_with(|| WallBatch::new(ctx.stride));
            let materials = (body.material, wall.material as usize);
            if b.count > 0 && b.materials != materials {
                flush(ctx, b, mine, out);
            }
            b.materials = materials;
            let at = lq * ctx.stride;
            let point = h.point + wall.offset;
            b.push(lq, point, &contact, &mine.history[at..at + ctx.stride]);
            if b.count == LANES {
                flush(ctx, b, mine, out);
            }
        }
    }
    if let Some(b) = &mut batch {
        flush(ctx, b, mine, out);
    }
}

/// Evaluates the batch's contacts, writes each one's slot, history, force and contact
/// point, and empties the batch.
#[inline(always)]
fn flush(ctx: &WallCtx, batch: &mut WallBatch, mine: &mut WallRows, out: &mut [WallOut]) {
    let count = batch.count;
    if count == 0 {
        return;
    }
    batch.count = 0;
    // Lanes past `count` repeat lane 0: finite values whose results are dropped.
    let first = batch.contacts.lane(0);
    for l in count..LANES {
        batch.contacts.set_lane(l, &first);
        for h in batch.history.iter_mut() {
            h.0[l] = h.0[0];
        }
    }
    batch.contacts.count = count;
    let stride = ctx.stride;
    let (a, b) = batch.materials;
    let res = ctx
        .model
        .evaluate_lanes(a, b, &batch.contacts, &mut batch.history);
    for l in 0..count {
        let lq = batch.row[l];
        let Some(o) = &res else {
            // No laws for this material pair: as the scalar pipeline, nothing, and the
            // history untouched.
            out[lq] = WallOut::NONE;
            mine.force[lq] = DVec3::ZERO;
            continue;
        };
        for (v, h) in batch.history.iter().enumerate() {
            mine.history[lq * stride + v] = h.0[l];
        }
        let f = o.force.lane(l);
        out[lq] = WallOut {
            force: f,
            torque: o.torque_i.lane(l),
            adds: true,
        };
        mine.force[lq] = f;
        mine.point[lq] = batch.point[l];
    }
}
