//! How the pair phase splits its work so that every particle's force sum comes out in the
//! same order on any number of threads.
//!
//! The rows of the pair list are cut into a number of blocks set by the list alone (its
//! particle count and how far its pairs reach), never by the thread count. A block's pairs touch an index interval of
//! particles: its own rows and their partners (particles are in cell order, so partners
//! are near in index). Each block adds its pairs' forces, as they are computed and in list
//! order, to partial sums of its own covering that interval, so blocks run in parallel
//! without sharing a sum. Each particle's force is then gravity plus the partial sums of
//! the blocks that touch it, in block order: an order fixed by the list alone.
//!
//! This is LIGGGHTS's pair loop (each pair's force added to both particles as it is
//! computed) made deterministic. It replaced per-pair force records summed in a separate
//! pass, which wrote and read 72 bytes per listed pair every step (BENCHMARKS.md,
//! seventeenth sitting).

use super::{CHUNK, chunks_per_task};
use crate::contact::model::ACTIVE;
use rayon::prelude::*;
use std::ops::Range;

/// Rows per block, at least: enough that a block's own rows outnumber the partners it
/// shares with its neighbours (about one layer of cells: 1,000 to 2,000 particles in the
/// settling bed), so the partial sums add little.
pub const MIN_BLOCK_ROWS: usize = 2048;

/// Blocks at most: enough for two threads to balance uneven blocks.
pub const MAX_BLOCKS: usize = 16;

/// Partial sums per particle, at most. In cell order the blocks together touch about twice
/// the particles (100,000 particles in the settling bed: 2.0-2.1). Out of cell order (a new
/// scene's particles before the first sort, a factory's newcomers) a block's partners reach
/// across the whole list and 16 blocks would hold 16 sums per particle (48 bytes each).
pub const MAX_SUMS_PER_PARTICLE: usize = 4;

/// Extra work of an established contact, in listed pairs: it runs the laws, where a listed
/// pair out of contact is a distance test. Without it, blocks of equal pairs took unequal
/// time and two threads sped the pair phase up 1.65x; with it 1.80x (4 and 12 gave the
/// same; BENCHMARKS.md, seventeenth sitting).
pub const CONTACT_WEIGHT: usize = 4;

/// A block of rows and the particles its pairs touch.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Rows (particles as first member of their pairs).
    pub rows: Range<usize>,
    /// Every particle a pair of these rows touches: the rows and their partners.
    pub touch: Range<usize>,
    /// Where its partial sums start in the schedule's sum arrays (`touch.len()` of them).
    pub offset: usize,
}

/// The blocks of a pair list.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PairSchedule {
    /// In row order; together they cover every row once.
    pub blocks: Vec<Block>,
    /// Partial sums of all blocks together.
    pub sums_len: usize,
}

impl PairSchedule {
    /// The schedule of the list whose row `p` is `partner[row_start[p]..row_start[p + 1]]`,
    /// pair k's history at `history[k * stride..]`. Blocks are cut at equal work: a row
    /// counts one, a listed pair one, and an established contact (its `ACTIVE` flag set)
    /// [`CONTACT_WEIGHT`] more. When the blocks' partial sums would exceed
    /// [`MAX_SUMS_PER_PARTICLE`] per particle, the block count is halved until they fit (one
    /// block touches at most every particle once).
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
        let mut count = n.div_ceil(MIN_BLOCK_ROWS).clamp(1, MAX_BLOCKS);
        loop {
            let s = Self::with_blocks(count, &cum, row_start, partner);
            if count == 1 || s.sums_len <= MAX_SUMS_PER_PARTICLE * n {
                return s;
            }
            count /= 2;
        }
    }

    /// `count` blocks cut at equal shares of the cumulative work `cum` (`cum[r]`: the work of
    /// rows `0..r`).
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
            if b == count {
                return n;
            }
            let target = b * total / count;
            cum.partition_point(|&c| c < target).min(n)
        };
        let mut offset = 0;
        let blocks = (0..count)
            .map(|b| {
                let rows = cut(b)..cut(b + 1);
                let pairs = row_start[rows.start] as usize..row_start[rows.end] as usize;
                let (mut lo, mut hi) = (rows.start, rows.end);
                for &j in &partner[pairs] {
                    lo = lo.min(j as usize);
                    hi = hi.max(j as usize + 1);
                }
                let block = Block {
                    rows,
                    touch: lo..hi,
                    offset,
                };
                offset += hi - lo;
                block
            })
            .collect();
        PairSchedule {
            blocks,
            sums_len: offset,
        }
    }
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

    /// The blocks cover the rows once, in order; every pair lies in its block's interval;
    /// the partial sums do not overlap.
    fn check(s: &PairSchedule, n: usize, row_start: &[u32], partner: &[u32]) {
        let covered: Vec<usize> = s.blocks.iter().flat_map(|b| b.rows.clone()).collect();
        assert_eq!(covered, (0..n).collect::<Vec<_>>());
        let mut offset = 0;
        for b in &s.blocks {
            assert_eq!(b.offset, offset);
            offset += b.touch.len();
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
        assert_eq!(s.sums_len, offset);
    }

    #[test]
    fn blocks_reach_as_far_as_their_partners() {
        // A chain, each particle paired with the next, and one long pair from the first
        // particle to the last.
        let n = 5 * MIN_BLOCK_ROWS;
        let mut pairs: Vec<(u32, u32)> = (0..n as u32 - 1).map(|i| (i, i + 1)).collect();
        pairs.insert(1, (0, n as u32 - 1));
        let (row_start, partner) = list(n, &pairs);
        let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
        check(&s, n, &row_start, &partner);
        assert_eq!(s.blocks.len(), 5);
        assert_eq!(s.blocks[0].touch, 0..n);
        let b = MIN_BLOCK_ROWS;
        assert_eq!(s.blocks[1].touch, b..2 * b + 1);
        assert_eq!(s.blocks[4].touch, 4 * b..n);
        // The last particle's sum takes shares from the first block and the last.
        let last: Vec<usize> = (s.blocks.iter())
            .filter(|x| x.touch.contains(&(n - 1)))
            .map(|x| x.rows.start / b)
            .collect();
        assert_eq!(last, vec![0, 4]);
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
        for n in [0, 1, 100, MIN_BLOCK_ROWS + 1, 40 * MIN_BLOCK_ROWS] {
            let (row_start, partner) = list(n, &[]);
            let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
            check(&s, n, &row_start, &partner);
            let expected = n.div_ceil(MIN_BLOCK_ROWS).clamp(1, MAX_BLOCKS);
            assert_eq!(s.blocks.len(), expected, "n = {n}");
        }
    }

    #[test]
    fn blocks_merge_when_pairs_reach_across_the_list() {
        // Out of cell order: the first half's particles paired with the second half's,
        // mirrored, so every block of 16 would touch most of the list.
        let n = MAX_BLOCKS * MIN_BLOCK_ROWS;
        let pairs: Vec<(u32, u32)> = (0..n as u32 / 2).map(|i| (i, n as u32 - 1 - i)).collect();
        let (row_start, partner) = list(n, &pairs);
        let s = PairSchedule::build(&row_start, &partner, &vec![0.0; partner.len()], 1);
        check(&s, n, &row_start, &partner);
        assert!(s.sums_len <= MAX_SUMS_PER_PARTICLE * n, "{}", s.sums_len);
        // The largest halving of 16 that fits: twice as many blocks would not.
        let count = s.blocks.len();
        assert!(count < MAX_BLOCKS);
        let cum: Vec<usize> = {
            let mut c = vec![0];
            for r in 0..n {
                c.push(c[r] + 1 + (row_start[r + 1] - row_start[r]) as usize);
            }
            c
        };
        let finer = PairSchedule::with_blocks(2 * count, &cum, &row_start, &partner);
        assert!(
            finer.sums_len > MAX_SUMS_PER_PARTICLE * n,
            "{}",
            finer.sums_len
        );
    }
}
