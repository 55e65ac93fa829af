//! How the pair phase splits its work so that every particle's force sum comes out in the
//! same order on any number of threads.
//!
//! The rows of the pair list are cut into a number of blocks set by the list alone (its
//! particle count), never by the thread count. A block's pairs touch an index interval of
//! particles: its own rows and their partners (particles are in cell order, so partners
//! are near in index). The blocks are then grouped into phases, again by the list alone:
//! within a phase no two blocks touch the same particle. The pair phase runs the phases in
//! order and the blocks of a phase in parallel, each adding its pairs' forces, as they are
//! computed and in list order, straight into the particles' force sums. Each particle's
//! force is therefore gravity, then the shares of the blocks that touch it, in phase order:
//! an order fixed by the list alone.
//!
//! This is LIGGGHTS's pair loop (each pair's force added to both particles as it is
//! computed) made deterministic, as a graph colouring of the blocks (as in
//! Kokkos-based DEM and MD codes that colour their work to avoid atomics). It replaced
//! partial sums of their own per block, summed per particle afterwards: in cell order the
//! blocks touch about twice the particles, so the particle phase read and zeroed 192 bytes
//! a particle every step; and before them, per-pair
//! force records summed in a separate pass, 72 bytes per listed pair.

use super::{CHUNK, chunks_per_task};
use crate::contact::model::ACTIVE;
use rayon::prelude::*;
use std::ops::Range;

/// Rows per block, at least: enough that a block's own rows outnumber the partners it
/// shares with its neighbours (about one layer of cells: 1,000 to 2,000 particles in the
/// settling bed), so that in cell order a block touches only its neighbours' particles and
/// two phases hold all blocks.
pub const MIN_BLOCK_ROWS: usize = 2048;

/// Blocks at most: enough for two threads to balance uneven blocks.
pub const MAX_BLOCKS: usize = 16;

/// Extra work of an established contact, in listed pairs: it runs the laws, where a listed
/// pair out of contact is a distance test. Without it, blocks of equal pairs took unequal
/// time and two threads sped the pair phase up 1.65x; with it 1.80x (4 and 12 gave the
/// same).
pub const CONTACT_WEIGHT: usize = 4;

/// A block of rows and the particles its pairs touch.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Rows (particles as first member of their pairs).
    pub rows: Range<usize>,
    /// Every particle a pair of these rows touches: the rows and their partners.
    pub touch: Range<usize>,
}

/// The blocks of a pair list.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PairSchedule {
    /// In row order; together they cover every row once.
    pub blocks: Vec<Block>,
    /// The blocks (indices into `blocks`) in the order the pair phase runs them: phase by
    /// phase, each phase's blocks in row order, their `touch` intervals disjoint.
    pub phases: Vec<Vec<usize>>,
}

impl PairSchedule {
    /// The schedule of the list whose row `p` is `partner[row_start[p]..row_start[p + 1]]`,
    /// pair k's history at `history[k * stride..]`. Blocks are cut at equal work: a row
    /// counts one, a listed pair one, and an established contact (its `ACTIVE` flag set)
    /// [`CONTACT_WEIGHT`] more, then moved so that neighbours alone share particles (see
    /// [`PairSchedule::with_blocks`]). From four blocks on, their count is a multiple of
    /// four, so that in cell order (two phases) each of two threads gets as many blocks of
    /// each phase.
    pub fn build(
        row_start: &[u32],
        partner: &[u32],
        history: &[f64],
        stride: usize,
    ) -> PairSchedule {
        let n = row_start.len().saturating_sub(1);
        // Each row's work in parallel (it reads every pair's history), then the running
        // sum: serial, it kept the other thread waiting at every rebuild.
        let mut cum = vec![0usize; n + 1];
        cum[1..]
            .par_chunks_mut(CHUNK)
            .enumerate()
            .with_max_len(chunks_per_task())
            .for_each(|(c, w)| {
                for (r, w) in (c * CHUNK..).zip(w) {
                    let pairs = row_start[r] as usize..row_start[r + 1] as usize;
                    *w = 1
                        + pairs.len()
                        + CONTACT_WEIGHT
                            * pairs
                                .filter(|&k| history[k * stride + ACTIVE] != 0.0)
                                .count();
                }
            });
        for r in 0..n {
            cum[r + 1] += cum[r];
        }
        Self::with_blocks(block_count(n), &cum, row_start, partner)
    }

    /// Up to `count` blocks cut at equal shares of the cumulative work `cum` (`cum[r]`: the
    /// work of rows `0..r`), each moved on as far as keeping its neighbours apart needs.
    fn with_blocks(
        count: usize,
        cum: &[usize],
        row_start: &[u32],
        partner: &[u32],
    ) -> PairSchedule {
        let n = cum.len() - 1;
        let total = cum[n];
        let cut = |b: usize| -> usize {
            if b == 0 {
                return 0;
            }
            if b >= count {
                return n;
            }
            let target = b * total / count;
            cum.partition_point(|&c| c < target).min(n)
        };
        // Each row's nearest and farthest particle in index (itself or a partner), in one
        // walk over the partners.
        let near: Vec<(usize, usize)> = (0..n)
            .map(|r| {
                let pairs = row_start[r] as usize..row_start[r + 1] as usize;
                (partner[pairs].iter()).fold((r, r + 1), |(lo, hi), &j| {
                    (lo.min(j as usize), hi.max(j as usize + 1))
                })
            })
            .collect();
        // `reach_back[r]`: the lowest particle rows `r..` touch.
        let mut reach_back = vec![n; n + 1];
        for r in (0..n).rev() {
            reach_back[r] = reach_back[r + 1].min(near[r].0);
        }
        let mut blocks: Vec<Block> = Vec::with_capacity(count);
        // Each block ends at least where the rows after it reach back no further than the
        // end of what the block before touches: then each block shares particles with its
        // neighbours only, and two phases hold them all. (At equal work alone, a block of
        // few rows in the dense part of a settling bed reached past its neighbours, and a
        // phase of one block left a thread idle.) Not when that would take in more than the
        // next three blocks' work, as a list out of cell order would have it: more phases
        // then, rather than one block for the whole list.
        let (mut start, mut need) = (0, 0);
        for b in 0..count {
            if b > 0 && start == n {
                break;
            }
            let planned = cut(b + 1).max(start);
            let apart = reach_back.partition_point(|&lo| lo < need).min(n);
            let end = if apart > planned && apart <= cut(b + 4) {
                apart
            } else {
                planned
            };
            if end == start && b > 0 {
                // Taken in by the block before.
                continue;
            }
            let (mut lo, mut hi) = (start, end);
            for &(l, h) in &near[start..end] {
                (lo, hi) = (lo.min(l), hi.max(h));
            }
            blocks.push(Block {
                rows: start..end,
                touch: lo..hi,
            });
            (start, need) = (end, hi);
        }
        let phases = phases_of(&blocks);
        PairSchedule { blocks, phases }
    }
}

/// Blocks for `n` rows: one per [`MIN_BLOCK_ROWS`] up to [`MAX_BLOCKS`], rounded down to a
/// multiple of four from four on.
fn block_count(n: usize) -> usize {
    let count = n.div_ceil(MIN_BLOCK_ROWS).clamp(1, MAX_BLOCKS);
    if count >= 4 { count / 4 * 4 } else { count }
}

/// Phases of blocks whose `touch` intervals are disjoint within each: each block, in row
/// order, joins the first phase where it overlaps no block. Two phases when each block
/// shares particles with its neighbours only, as [`PairSchedule::with_blocks`] cuts them
/// in cell order.
fn phases_of(blocks: &[Block]) -> Vec<Vec<usize>> {
    let disjoint = |a: &Range<usize>, b: &Range<usize>| a.end <= b.start || b.end <= a.start;
    let mut phases: Vec<Vec<usize>> = Vec::new();
    for (b, block) in blocks.iter().enumerate() {
        let free = phases
            .iter()
            .position(|ph| ph.iter().all(|&o| disjoint(&blocks[o].touch, &block.touch)));
        match free {
            Some(k) => phases[k].push(b),
            None => phases.push(vec![b]),
        }
    }
    phases
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows and partners of a list from its pairs (i < j), grouped by i.
    fn list(n: usize, pairs: &[(u32, u32)]) -> (Vec<u32>, Vec<u32>) {
        let mut row_start = vec![0u32; n + 1];
        for &(i, _) in pairs {
            row_start[i as usize + 1] += 1;
        }
        for p in 0..n {
            row_start[p + 1] += row_start[p];
        }
        (row_start, pairs.iter().map(|&(_, j)| j).collect())
    }

    /// Rows and partners of a list from its pairs (either order), grouped by the first.
    fn list_any(n: usize, pairs: &[(u32, u32)]) -> (Vec<u32>, Vec<u32>) {
        let mut sorted = pairs.to_vec();
        sorted.sort_by_key(|&(i, _)| i);
        let mut row_start = vec![0u32; n + 1];
        for &(i, _) in &sorted {
            row_start[i as usize + 1] += 1;
        }
        for p in 0..n {
            row_start[p + 1] += row_start[p];
        }
        (row_start, sorted.iter().map(|&(_, j)| j).collect())
    }

    /// The blocks cover the rows once, in order; every pair lies in its block's interval;
    /// the phases hold every block once, in row order within each, and no two blocks of a
    /// phase touch the same particle; and there are as few phases as the most blocks that
    /// share one particle (fewer cannot keep them apart).
    fn check(s: &PairSchedule, n: usize, row_start: &[u32], partner: &[u32]) {
        let covered: Vec<usize> = s.blocks.iter().flat_map(|b| b.rows.clone()).collect();
        assert_eq!(covered, (0..n).collect::<Vec<_>>());
        for b in &s.blocks {
            for i in b.rows.clone() {
                assert!(b.touch.contains(&i));
                for &j in &partner[row_start[i] as usize..row_start[i + 1] as usize] {
                    assert!(
                        b.touch.contains(&(j as usize)),
                        "pair ({i}, {j}) outside {b:?}"
                    );
                }
            }
        }
        let mut seen: Vec<usize> = s.phases.iter().flatten().copied().collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..s.blocks.len()).collect::<Vec<_>>());
        let mut sharing = vec![0usize; n];
        for phase in &s.phases {
            assert!(phase.windows(2).all(|w| w[0] < w[1]), "{phase:?}");
            let mut touched = vec![false; n];
            for &b in phase {
                for i in s.blocks[b].touch.clone() {
                    assert!(!touched[i], "particle {i} twice in phase {phase:?}");
                    touched[i] = true;
                    sharing[i] += 1;
                }
            }
        }
        let most = sharing.iter().copied().max().unwrap_or(0).max(1);
        assert_eq!(s.phases.len(), most, "{:?}", s.phases);
    }

    #[test]
    fn blocks_reach_as_far_as_their_partners() {
        // A chain, each particle paired with the next, and one long pair from the first
        // particle to the last.
        let n = 4 * MIN_BLOCK_ROWS;
        let mut pairs: Vec<(u32, u32)> = (0..n as u32 - 1).map(|i| (i, i + 1)).collect();
        pairs.insert(1, (0, n as u32 - 1));
        let (row_start, partner) = list(n, &pairs);
        let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
        check(&s, n, &row_start, &partner);
        // The long pair takes the first block's reach to the end, and the next block goes
        // as far, so that no third block shares the first's particles.
        let b = MIN_BLOCK_ROWS;
        let cuts: Vec<_> = s
            .blocks
            .iter()
            .map(|x| (x.rows.clone(), x.touch.clone()))
            .collect();
        assert_eq!(cuts, vec![(0..b, 0..n), (b..n, b..n)]);
        assert_eq!(s.phases, vec![vec![0], vec![1]]);
    }

    #[test]
    fn blocks_grow_past_a_dense_part_reaching_back() {
        // A chain, and in the first quarter each particle also paired with the 1,500
        // before it: a dense part whose equal-work blocks are thinner than its reach.
        let n = 8 * MIN_BLOCK_ROWS;
        let mut pairs: Vec<(u32, u32)> = vec![];
        for i in 0..n as u32 - 1 {
            if i < n as u32 / 4 {
                pairs.extend((i.saturating_sub(1500)..i).map(|j| (i, j)));
            }
            pairs.push((i, i + 1));
        }
        let (row_start, partner) = list_any(n, &pairs);
        let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
        check(&s, n, &row_start, &partner);
        // At equal work alone, the first blocks would be thinner than 1,500 rows.
        let first_cut = s.blocks[0].rows.end;
        assert!(first_cut < 1500, "{:?}", s.blocks);
        assert_eq!(s.phases.len(), 2, "{:?}", s.blocks);
    }

    #[test]
    fn established_contacts_weigh_more_in_the_cuts() {
        // A chain over two blocks' worth of rows; the first quarter's pairs in contact.
        let n = 2 * MIN_BLOCK_ROWS;
        let pairs: Vec<(u32, u32)> = (0..n as u32 - 1).map(|i| (i, i + 1)).collect();
        let (row_start, partner) = list(n, &pairs);
        let stride = 3;
        let mut history = vec![0.0; partner.len() * stride];
        for k in 0..n / 4 {
            history[k * stride + ACTIVE] = 1.0;
        }
        let s = PairSchedule::build(&row_start, &partner, &history, stride);
        check(&s, n, &row_start, &partner);
        let weight = |r: usize| {
            let pairs = row_start[r] as usize..row_start[r + 1] as usize;
            1 + pairs.len()
                + CONTACT_WEIGHT
                    * pairs
                        .filter(|&k| history[k * stride + ACTIVE] != 0.0)
                        .count()
        };
        let work: Vec<usize> = s
            .blocks
            .iter()
            .map(|b| b.rows.clone().map(weight).sum())
            .collect();
        // The cut moves toward the contacts, and the blocks' work differs by at most the
        // heaviest row.
        assert!(s.blocks[0].rows.end < n / 2, "{:?}", s.blocks);
        assert!(work[0].abs_diff(work[1]) <= 2 + CONTACT_WEIGHT, "{work:?}");
    }

    #[test]
    fn block_count_follows_the_particle_count_in_cell_order() {
        // One block per MIN_BLOCK_ROWS rows (rounded up) up to 16, a multiple of 4 from 4 on.
        for (n, expected) in [
            (0, 1),
            (1, 1),
            (100, 1),
            (MIN_BLOCK_ROWS + 1, 2),
            (3 * MIN_BLOCK_ROWS, 3),
            (5 * MIN_BLOCK_ROWS, 4),
            (9 * MIN_BLOCK_ROWS + 1, 8),
            (40 * MIN_BLOCK_ROWS, 16),
        ] {
            let (row_start, partner) = list(n, &[]);
            let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
            check(&s, n, &row_start, &partner);
            assert_eq!(s.blocks.len(), expected, "n = {n}");
            assert_eq!(s.phases.len(), 1, "n = {n}: no pairs, nothing shared");
        }
    }

    #[test]
    fn cell_order_takes_two_phases() {
        // Each particle paired with the next 1,000 (a layer of cells), over 8 blocks.
        let n = 8 * MIN_BLOCK_ROWS;
        let pairs: Vec<(u32, u32)> = (0..n as u32)
            .flat_map(|i| (i + 1..(i + 1001).min(n as u32)).map(move |j| (i, j)))
            .collect();
        let (row_start, partner) = list(n, &pairs);
        let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
        check(&s, n, &row_start, &partner);
        assert_eq!(s.blocks.len(), 8);
        assert_eq!(s.phases, vec![vec![0, 2, 4, 6], vec![1, 3, 5, 7]]);
    }

    #[test]
    fn phases_keep_apart_blocks_that_reach_across_the_list() {
        // Out of cell order: the first half's particles paired with the second half's,
        // mirrored, so the first half's blocks nest inside one another.
        let n = MAX_BLOCKS * MIN_BLOCK_ROWS;
        let pairs: Vec<(u32, u32)> = (0..n as u32 / 2).map(|i| (i, n as u32 - 1 - i)).collect();
        let (row_start, partner) = list(n, &pairs);
        let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
        check(&s, n, &row_start, &partner);
        assert!(s.phases.len() > 2, "{:?}", s.phases);
    }
}
