//! The particle phase's wall contacts: each particle's listed wall features through the
//! contact laws, with the wall's material.
//!
//! A chunk's wall contacts are evaluated before its particles are summed, out of the
//! particle loop: kept inline, their code filled the loop's registers and the running force
//! sums of every particle went through the stack; taken together, the touching contacts
//! with a wall of one listed feature go through the laws' lane forms like the pair phase's.

use super::PairPath;
#[cfg(doc)]
use crate::contact::LANES;
use crate::contact::{Contact, ContactModel};
use crate::wall::{Hit, Wall};
use glam::DVec3;
use std::ops::Range;

mod lanes;

/// One task's rows of the wall-contact list: rows `base..base + force.len()` of the whole
/// list, with their history (`stride` values a row), force and contact point; and the
/// task's share of each wall's force and torque.
pub(super) struct WallRows<'a> {
    pub base: usize,
    pub history: &'a mut [f64],
    pub force: &'a mut [DVec3],
    pub point: &'a mut [DVec3],
    pub shares: &'a mut [(DVec3, DVec3)],
}

impl WallRows<'_> {
    /// Sets each wall's share to the opposite of what it did to these rows' particles,
    /// summed in row order: force, and torque about the wall's reference point.
    pub fn add_wall_shares(&mut self, list: &WallList, walls: &[Wall]) {
        self.shares.fill((DVec3::ZERO, DVec3::ZERO));
        for (q, (&f, &point)) in self.force.iter().zip(self.point.iter()).enumerate() {
            if f != DVec3::ZERO {
                let w = list.wall[self.base + q] as usize;
                let wall = &walls[w];
                let arm = point - (wall.shape.reference_point() + wall.offset);
                let share = &mut self.shares[w];
                share.0 -= f;
                share.1 += arm.cross(-f);
            }
        }
    }
}

/// What a wall contact reads of its particle: position, radius, mass, inertia, material,
/// velocity and spin after the first half kick.
pub(super) struct Body {
    pub x: DVec3,
    pub radius: f64,
    pub mass: f64,
    pub inertia: f64,
    pub material: usize,
    pub v: DVec3,
    pub w: DVec3,
}

/// The list's read-only side: which wall and which feature each row is.
pub(super) struct WallList<'a> {
    pub wall: &'a [u16],
    pub feature: &'a [u32],
}

/// What every chunk's wall contacts read: the list, where each particle's rows start, the
/// walls, the contact model and its history stride, the step, and how to evaluate.
pub(super) struct WallCtx<'a> {
    pub list: WallList<'a>,
    pub start: &'a [u32],
    pub walls: &'a [Wall],
    pub model: &'a ContactModel,
    pub stride: usize,
    pub dt: f64,
    /// [`PairPath::OneByOne`] evaluates every contact alone; the lane paths take touching
    /// contacts with a wall of one listed feature [`LANES`] at a time (see `lanes.rs`).
    pub path: PairPath,
}

/// One wall contact's force and torque on its particle, in the order the particle adds
/// them: slot `s` of a particle's rows is its `s`-th addition; `adds` false where nothing
/// is added (no contact, or a shadowed one).
#[derive(Debug, Clone, Copy)]
pub(super) struct WallOut {
    pub force: DVec3,
    pub torque: DVec3,
    pub adds: bool,
}

impl WallOut {
    pub const NONE: WallOut = WallOut {
        force: DVec3::ZERO,
        torque: DVec3::ZERO,
        adds: false,
    };
}

/// The particles of one chunk, as wall contacts read them: particle `first + k` is at
/// `x[k]` with velocity `v[k]` and spin `w[k]`; radius, mass, inertia and material are
/// the whole arrays.
pub(super) struct ChunkBodies<'a> {
    pub first: usize,
    pub x: &'a [DVec3],
    pub v: &'a [DVec3],
    pub w: &'a [DVec3],
    pub radius: &'a [f64],
    pub mass: &'a [f64],
    pub inertia: &'a [f64],
    pub material: &'a [u16],
}

impl ChunkBodies<'_> {
    #[inline(always)]
    fn body(&self, k: usize) -> Body {
        let i = self.first + k;
        Body {
            x: self.x[k],
            radius: self.radius[i],
            mass: self.mass[i],
            inertia: self.inertia[i],
            material: self.material[i] as usize,
            v: self.v[k],
            w: self.w[k],
        }
    }
}

/// Evaluates every wall contact of a chunk's particles before the particles are summed:
/// `out[s]` is slot `s` of the chunk's rows (see [`WallOut`]), and each row's force and
/// contact point are recorded in `mine`. The particle then adds its slots in order, as the
/// one-at-a-time loop added each contact: the sums get the same bits on every path.
pub(super) fn chunk_wall_forces(
    ctx: &WallCtx,
    bodies: &ChunkBodies,
    mine: &mut WallRows,
    out: &mut [WallOut],
    hits: &mut Vec<(f64, usize, Hit)>,
) {
    if ctx.path == PairPath::OneByOne {
        for k in 0..bodies.x.len() {
            let i = bodies.first + k;
            let rows = ctx.start[i] as usize..ctx.start[i + 1] as usize;
            if !rows.is_empty() {
                let body = bodies.body(k);
                for (w, group) in groups(&ctx.list, rows) {
                    group_one_by_one(ctx, &body, w, group, mine, out, hits);
                }
            }
        }
        return;
    }
    lanes::chunk_wall_forces_lanes(ctx, bodies, mine, out, hits);
}

/// Rows `rows` cut into runs of one wall: `(wall, rows)`.
fn groups<'a>(
    list: &'a WallList,
    rows: Range<usize>,
) -> impl Iterator<Item = (usize, Range<usize>)> + 'a {
    let end = rows.end;
    let mut e = rows.start;
    std::iter::from_fn(move || {
        if e >= end {
            return None;
        }
        let w = list.wall[e] as usize;
        let mut g = e;
        while g < end && list.wall[g] as usize == w {
            g += 1;
        }
        let group = e..g;
        e = g;
        Some((w, group))
    })
}

/// The body's contacts with wall `w`, rows `rows`, one at a time, nearest first: nearer
/// features (a mesh's triangles) shadow contacts whose closest point lies on them. Writes
/// slots `rows` of `out` in that order. `hits` is scratch space.
#[inline(never)]
fn group_one_by_one(
    ctx: &WallCtx,
    body: &Body,
    w: usize,
    rows: Range<usize>,
    mine: &mut WallRows,
    out: &mut [WallOut],
    hits: &mut Vec<(f64, usize, Hit)>,
) {
    let wall = &ctx.walls[w];
    let local = body.x - wall.offset;
    hits.clear();
    for q in rows.clone() {
        let h = wall.shape.hit(ctx.list.feature[q], local);
        hits.push((h.distance, q, h));
    }
    if hits.len() > 1 {
        hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
    for a in 0..hits.len() {
        let (_, q, h) = hits[a];
        let lq = q - mine.base;
        let slot = rows.start - mine.base + a;
        let shadowed = (0..a).any(|b| {
            let (_, qb, hb) = hits[b];
            mine.force[qb - mine.base] != DVec3::ZERO
                && wall.shape.feature_distance(hb.feature, h.point) <= 1e-9 * body.radius
        });
        let contact = if shadowed {
            None
        } else {
            wall_contact(body, wall, &h, ctx.dt)
        };
        evaluate_row(
            ctx,
            body,
            wall,
            contact,
            &h,
            (lq, slot),
            shadowed,
            mine,
            out,
        );
    }
}

/// Evaluates the contact `contact` (none: beyond contact or shadowed) of row `lq` one at a
/// time and writes slot `slot` and the row's force and contact point; a shadowed contact's
/// history is cleared.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn evaluate_row(
    ctx: &WallCtx,
    body: &Body,
    wall: &Wall,
    contact: Option<Contact>,
    h: &Hit,
    (lq, slot): (usize, usize),
    shadowed: bool,
    mine: &mut WallRows,
    out: &mut [WallOut],
) {
    let hist = &mut mine.history[lq * ctx.stride..(lq + 1) * ctx.stride];
    let res = contact.and_then(|ct| {
        ctx.model
            .evaluate(body.material, wall.material as usize, &ct, hist)
    });
    match res {
        Some(o) => {
            out[slot] = WallOut {
                force: o.force,
                torque: o.torque_i,
                adds: true,
            };
            mine.force[lq] = o.force;
            mine.point[lq] = h.point + wall.offset;
        }
        None => {
            if shadowed {
                hist.fill(0.0);
            }
            out[slot] = WallOut::NONE;
            mine.force[lq] = DVec3::ZERO;
        }
    }
}

/// The contact of `body` with `wall` at hit `h` (shape frame), if the centre is off the
/// surface.
#[inline(always)]
fn wall_contact(body: &Body, wall: &Wall, h: &Hit, dt: f64) -> Option<Contact> {
    Contact::with_wall(
        body.x,
        body.x - h.normal * h.distance,
        body.radius,
        body.mass,
        body.inertia,
        body.v,
        body.w,
        wall.velocity,
        dt,
    )
}
