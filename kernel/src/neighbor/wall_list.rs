//! The wall-contact list: for every particle, the wall features within reach of its surface,
//! with per-contact history carried across rebuilds (matched by wall and feature).

use super::{CHUNK, chunks_per_task};
use crate::particles::Particles;
use crate::wall::Wall;
use glam::DVec3;
use rayon::prelude::*;

/// Wall contacts of every particle, grouped by particle then (wall, feature) ascending.
#[derive(Debug, Default, Clone)]
pub(crate) struct WallContacts {
    /// Contacts of particle p: `start[p]..start[p + 1]`.
    pub start: Vec<u32>,
    pub wall: Vec<u16>,
    pub feature: Vec<u32>,
    pub history: Vec<f64>,
    /// Force on the particle and contact point (world) of the last step.
    pub force: Vec<DVec3>,
    pub point: Vec<DVec3>,
}

impl WallContacts {
    /// A list for no particles.
    pub fn empty() -> WallContacts {
        WallContacts {
            start: vec![0],
            ..Default::default()
        }
    }

    /// Bytes of heap memory held.
    pub fn heap_bytes(&self) -> usize {
        self.start.capacity() * 4
            + self.wall.capacity() * 2
            + self.feature.capacity() * 4
            + self.history.capacity() * 8
            + (self.force.capacity() + self.point.capacity()) * 24
    }
}

/// Lists, for every particle, the wall features within `extra` of its surface, carrying the
/// history of contacts that were already listed.
pub(crate) fn build_wall_contacts(
    p: &Particles,
    walls: &[Wall],
    old: &WallContacts,
    extra: f64,
    stride: usize,
    old_of_new: Option<&[u32]>,
) -> WallContacts {
    let n = p.len();
    if walls.is_empty() {
        return WallContacts {
            start: vec![0; n + 1],
            ..Default::default()
        };
    }
    struct Chunk {
        counts: Vec<u32>,
        wall: Vec<u16>,
        feature: Vec<u32>,
        history: Vec<f64>,
    }
    let chunks: Vec<Chunk> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .with_max_len(chunks_per_task())
        .map(|c| {
            let mut out = Chunk {
                counts: vec![],
                wall: vec![],
                feature: vec![],
                history: vec![],
            };
            let mut hits = vec![];
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let before = out.wall.len();
                let oi = old_of_new.map_or(i, |m| m[i] as usize);
                let old_row = if oi + 1 < old.start.len() {
                    old.start[oi] as usize..old.start[oi + 1] as usize
                } else {
                    0..0
                };
                let mut k = old_row.start;
                for (w, wall) in walls.iter().enumerate() {
                    if !wall.active {
                        continue;
                    }
                    hits.clear();
                    wall.shape
                        .hits(p.position[i] - wall.offset, p.radius[i] + extra, &mut hits);
                    for h in &hits {
                        let key = (w as u16, h.feature);
                        while k < old_row.end && (old.wall[k], old.feature[k]) < key {
                            k += 1;
                        }
                        if k < old_row.end && (old.wall[k], old.feature[k]) == key {
                            out.history
                                .extend_from_slice(&old.history[k * stride..(k + 1) * stride]);
                        } else {
                            out.history.extend(std::iter::repeat_n(0.0, stride));
                        }
                        out.wall.push(w as u16);
                        out.feature.push(h.feature);
                    }
                }
                out.counts.push((out.wall.len() - before) as u32);
            }
            out
        })
        .collect();
    let mut wc = WallContacts {
        start: Vec::with_capacity(n + 1),
        ..Default::default()
    };
    wc.start.push(0);
    for c in chunks {
        for cnt in c.counts {
            let last = *wc.start.last().unwrap();
            wc.start.push(last + cnt);
        }
        wc.wall.extend(c.wall);
        wc.feature.extend(c.feature);
        wc.history.extend(c.history);
    }
    wc.force = vec![DVec3::ZERO; wc.wall.len()];
    wc.point = vec![DVec3::ZERO; wc.wall.len()];
    wc
}
