//! The Verlet pair list (half list, j > i) with per-pair contact history.

use super::{CHUNK, CellGrid};
use glam::DVec3;
use rayon::prelude::*;

/// Pairs (i, j) whose surfaces are closer than `extra` (skin + reach), listed once, in the row
/// of the particle with the smaller id (ids never change, indices do when particles are
/// reordered, so a contact keeps its orientation and its history's sign), grouped by i in
/// ascending j. Each pair owns a history row of `stride` f64 values.
#[derive(Debug, Clone, Default)]
pub struct PairList {
    pub i: Vec<u32>,
    pub j: Vec<u32>,
    /// Pairs of particle p as first member: `row_start[p]..row_start[p + 1]`.
    pub row_start: Vec<u32>,
    pub history: Vec<f64>,
    pub stride: usize,
    /// Pairs of particle p as second member: `rev_pair[rev_start[p]..rev_start[p + 1]]`, ascending.
    pub rev_start: Vec<u32>,
    pub rev_pair: Vec<u32>,
}

struct RowChunk {
    counts: Vec<u32>,
    j: Vec<u32>,
    history: Vec<f64>,
}

impl PairList {
    pub fn empty(stride: usize) -> PairList {
        PairList {
            stride,
            row_start: vec![0],
            rev_start: vec![0],
            ..Default::default()
        }
    }

    pub fn len(&self) -> usize {
        self.j.len()
    }

    pub fn is_empty(&self) -> bool {
        self.j.is_empty()
    }

    /// Rebuilds the list for the current positions, carrying over the history of every pair
    /// that was already listed. `old_of_new[k]` is the index particle k had when the old list
    /// was built (`None`: unchanged). Run inside the simulation's thread pool.
    pub fn rebuild(
        &mut self,
        position: &[DVec3],
        radius: &[f64],
        id: &[u32],
        extra: f64,
        old_of_new: Option<&[u32]>,
    ) {
        self.rebuild_keeping(position, radius, id, extra, old_of_new, None)
    }

    /// Like [`PairList::rebuild`], and also keeps every old pair whose history row `keep`
    /// accepts, however far apart its particles are now (bonded pairs: a bond holds its
    /// pair, so the list need not reach as far as a bond can stretch).
    pub fn rebuild_keeping(
        &mut self,
        position: &[DVec3],
        radius: &[f64],
        id: &[u32],
        extra: f64,
        old_of_new: Option<&[u32]>,
        keep: Option<&(dyn Fn(&[f64]) -> bool + Sync)>,
    ) {
        let n = position.len();
        // New index of each old particle, to bring kept partners across a reorder.
        let new_of_old: Option<Vec<u32>> = old_of_new.filter(|_| keep.is_some()).map(|m| {
            let mut inv = vec![0u32; m.len()];
            for (new, &old) in m.iter().enumerate() {
                inv[old as usize] = new as u32;
            }
            inv
        });
        let r_max = radius.iter().copied().fold(0.0, f64::max);
        let grid = CellGrid::build(position, 2.0 * r_max + extra);
        let old = &*self;
        let stride = self.stride;
        let chunks: Vec<RowChunk> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let rows = c * CHUNK..((c + 1) * CHUNK).min(n);
                let mut out = RowChunk {
                    counts: Vec::with_capacity(rows.len()),
                    j: vec![],
                    history: vec![],
                };
                let mut near = Vec::with_capacity(64);
                for i in rows {
                    near.clear();
                    let (pi, ri) = (position[i], radius[i]);
                    grid.for_each_near(pi, |j| {
                        let ju = j as usize;
                        if id[ju] > id[i] {
                            let cut = ri + radius[ju] + extra;
                            if (position[ju] - pi).length_squared() < cut * cut {
                                near.push(j);
                            }
                        }
                    });
                    // Carry history from the old row of the same particle. Without a reorder
                    // both rows ascend in j and merge; after one, look each partner up.
                    let oi = old_of_new.map_or(i, |m| m[i] as usize);
                    let old_row = if oi + 1 < old.row_start.len() {
                        old.row_start[oi] as usize..old.row_start[oi + 1] as usize
                    } else {
                        0..0
                    };
                    if let Some(keep) = keep {
                        for q in old_row.clone() {
                            if keep(&old.history[q * stride..(q + 1) * stride]) {
                                let j = match &new_of_old {
                                    None => old.j[q],
                                    Some(inv) => inv[old.j[q] as usize],
                                };
                                near.push(j);
                            }
                        }
                        near.sort_unstable();
                        near.dedup();
                    } else {
                        near.sort_unstable();
                    }
                    out.counts.push(near.len() as u32);
                    let mut k = old_row.start;
                    for &j in &near {
                        let found = match old_of_new {
                            None => {
                                while k < old_row.end && old.j[k] < j {
                                    k += 1;
                                }
                                (k < old_row.end && old.j[k] == j).then_some(k)
                            }
                            Some(m) => {
                                let oj = m[j as usize];
                                old_row.clone().find(|&q| old.j[q] == oj)
                            }
                        };
                        match found {
                            Some(q) => out
                                .history
                                .extend_from_slice(&old.history[q * stride..(q + 1) * stride]),
                            None => out.history.extend(std::iter::repeat_n(0.0, stride)),
                        }
                    }
                    out.j.extend_from_slice(&near);
                }
                out
            })
            .collect();

        let total: usize = chunks.iter().map(|c| c.j.len()).sum();
        let mut list = PairList {
            i: Vec::with_capacity(total),
            j: Vec::with_capacity(total),
            row_start: Vec::with_capacity(n + 1),
            history: Vec::with_capacity(total * stride),
            stride,
            rev_start: vec![0; n + 1],
            rev_pair: vec![0; total],
        };
        list.row_start.push(0);
        let mut row = 0u32;
        for c in chunks {
            for &cnt in &c.counts {
                list.i.extend(std::iter::repeat_n(row, cnt as usize));
                let last = *list.row_start.last().unwrap();
                list.row_start.push(last + cnt);
                row += 1;
            }
            list.j.extend_from_slice(&c.j);
            list.history.extend_from_slice(&c.history);
        }
        for &j in &list.j {
            list.rev_start[j as usize + 1] += 1;
        }
        for p in 0..n {
            list.rev_start[p + 1] += list.rev_start[p];
        }
        let mut fill = list.rev_start.clone();
        for (k, &j) in list.j.iter().enumerate() {
            list.rev_pair[fill[j as usize] as usize] = k as u32;
            fill[j as usize] += 1;
        }
        *self = list;
    }

    /// Bytes of heap memory held.
    pub fn heap_bytes(&self) -> usize {
        4 * (self.i.capacity()
            + self.j.capacity()
            + self.row_start.capacity()
            + self.rev_start.capacity()
            + self.rev_pair.capacity())
            + 8 * self.history.capacity()
    }
}
