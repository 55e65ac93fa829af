//! The particle phase's wall contacts: each particle's listed wall features through the
//! contact laws, with the wall's material.
//!
//! Out of the particle loop (and out of line) because few particles touch a wall: kept
//! inline, its code filled the loop's registers, and the running force sums of every
//! particle went through the stack.

use crate::contact::{Contact, ContactModel};
use crate::wall::{Hit, Wall};
use glam::DVec3;
use std::ops::Range;

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

/// Adds to `(f, t)` the force and torque of the body's wall contacts, rows `rows` of the
/// list, and records each row's force and contact point (zero force where it does not
/// touch). Rows come grouped by wall; within a group (a mesh), nearer triangles shadow
/// contacts whose closest point lies on them. `hits` is scratch space.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(super) fn add_wall_forces(
    body: &Body,
    rows: Range<usize>,
    list: &WallList,
    mine: &mut WallRows,
    walls: &[Wall],
    model: &ContactModel,
    stride: usize,
    dt: f64,
    hits: &mut Vec<(f64, usize, Hit)>,
    (mut f, mut t): (DVec3, DVec3),
) -> (DVec3, DVec3) {
    let (mut e, end) = (rows.start, rows.end);
    while e < end {
        let w = list.wall[e] as usize;
        let mut g = e;
        while g < end && list.wall[g] as usize == w {
            g += 1;
        }
        let wall = &walls[w];
        let local = body.x - wall.offset;
        hits.clear();
        for q in e..g {
            let h = wall.shape.hit(list.feature[q], local);
            hits.push((h.distance, q, h));
        }
        if hits.len() > 1 {
            hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
        for a in 0..hits.len() {
            let (_, q, h) = hits[a];
            let lq = q - mine.base;
            let hist = &mut mine.history[lq * stride..(lq + 1) * stride];
            let shadowed = (0..a).any(|b| {
                let (_, qb, hb) = hits[b];
                mine.force[qb - mine.base] != DVec3::ZERO
                    && wall.shape.feature_distance(hb.feature, h.point) <= 1e-9 * body.radius
            });
            let contact = if shadowed {
                None
            } else {
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
            };
            let res = contact
                .and_then(|ct| model.evaluate(body.material, wall.material as usize, &ct, hist));
            match res {
                Some(o) => {
                    f += o.force;
                    t += o.torque_i;
                    mine.force[lq] = o.force;
                    mine.point[lq] = h.point + wall.offset;
                }
                None => {
                    if shadowed {
                        hist.fill(0.0);
                    }
                    mine.force[lq] = DVec3::ZERO;
                }
            }
        }
        e = g;
    }
    (f, t)
}
