//! The Verlet pair list (half list, j > i) with per-pair contact history.

use super::{CHUNK, CellGrid, chunks_per_task};
use glam::DVec3;
use rayon::prelude::*;

/// Cells a particle at most in the search grid. A poured scene spans far more space than its
/// grains fill: the funnel's box (a 135 mm funnel above its tray, overflow on the floor) holds
/// some 10^5 cells of the cut, more than four a grain while the pour is young. Where the cap
/// binds, cells grow past the cut and each search scans (cell / cut)^3 times the grains it
/// needs (the study-scale funnel's first 0.6 s: lists 1.8x faster at 32 than at 4,
/// BENCHMARKS.md). The grid costs 4 bytes a cell while it lives; which cells a pair is found
/// through does not change the list (rows ascend).
const SEARCH_CELLS_PER_POINT: usize = 32;

/// Decides, from a pair's history row, whether a pair that left the list's reach stays
/// listed (bonded pairs do).
pub type PairFilter<'a> = &'a (dyn Fn(&[f64]) -> bool + Sync);

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
    /// The buffers of the list before this one, refilled by the next rebuild: two lists'
    /// worth of memory at most, and no new allocation (or heap fragmentation) once the
    /// count of pairs stops growing.
    spare: Buffers,
}

/// The vectors of a list, without meaning between rebuilds.
#[derive(Debug, Clone, Default)]
struct Buffers {
    i: Vec<u32>,
    j: Vec<u32>,
    row_start: Vec<u32>,
    history: Vec<f64>,
}

/// One task's rows of a new list: partner counts per row and the partners, row after row.
struct RowChunk {
    counts: Vec<u32>,
    j: Vec<u32>,
}

/// What the first pass of a rebuild reads: the particles, their cells, the list distance
/// beyond touching `extra` (m), and the old list with what keeps its pairs (see
/// [`PairList::rebuild_keeping`]).
struct Search<'a> {
    position: &'a [DVec3],
    radius: &'a [f64],
    id: &'a [u32],
    extra: f64,
    grid: &'a CellGrid,
    old: &'a PairList,
    /// The index each particle had when the old list was built.
    old_of_new: Option<&'a [u32]>,
    /// Its inverse, when pairs are kept: the new index of each old particle.
    new_of_old: Option<&'a [u32]>,
    keep: Option<PairFilter<'a>>,
}

/// One task's part of a rebuild's second pass: the rows of particles `first_row..` (whose
/// pairs start at pair `at` of the new list), their partners, and the new list's slices it
/// fills: first members, partners, row ends and history.
struct RowTask<'a> {
    first_row: usize,
    at: usize,
    chunk: RowChunk,
    i: &'a mut [u32],
    j: &'a mut [u32],
    starts: &'a mut [u32],
    history: &'a mut [f64],
}

impl PairList {
    pub fn empty(stride: usize) -> PairList {
        PairList {
            stride,
            row_start: vec![0],
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
        keep: Option<PairFilter<'_>>,
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
        let grid = CellGrid::build_capped(position, 2.0 * r_max + extra, SEARCH_CELLS_PER_POINT);
        let mut b = std::mem::take(&mut self.spare);
        let old = &*self;
        let stride = self.stride;
        // Two passes, so that a rebuild holds only the old list and the new one: first the
        // partners of every row (4 bytes a pair), then, with the rows' places known, each
        // task copies the carried history straight into its part of the new list.
        // Room for a chunk's partners at the old list's mean with a quarter to spare. Grown
        // by doubling, each chunk's vector was reallocated about eight times, on both
        // threads at once, through glibc's arena lock (`realloc` bypasses the per-thread
        // cache; `strace` counted its futex waits).
        let old_rows = self.row_start.len().saturating_sub(1).max(1);
        let per_row = self.j.len().div_ceil(old_rows).max(4) * 5 / 4;
        let search = Search {
            position,
            radius,
            id,
            extra,
            grid: &grid,
            old,
            old_of_new,
            new_of_old: new_of_old.as_deref(),
            keep,
        };
        let chunks: Vec<RowChunk> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .with_max_len(chunks_per_task())
            .map(|c| search.rows(c * CHUNK..((c + 1) * CHUNK).min(n), per_row))
            .collect();
        let tasks = b.refill(chunks, n, stride);
        // Each row's pairs and their history, carried from the old row of the same particle
        // (zero for a new pair).
        tasks
            .into_par_iter()
            .with_max_len(chunks_per_task())
            .for_each(|task| old.carry_history(old_of_new, task));
        let list = PairList {
            i: b.i,
            j: b.j,
            row_start: b.row_start,
            history: b.history,
            stride,
            spare: Buffers::default(),
        };
        let old = std::mem::replace(self, list);
        self.spare = Buffers {
            i: old.i,
            j: old.j,
            row_start: old.row_start,
            history: old.history,
        };
    }

    /// Fills one task's part of the new list: each row's first members, partners and end,
    /// and each pair's history, carried from the pair of the same particles in this (old)
    /// list, zero for a new pair. Without a reorder both rows ascend in j and merge; after
    /// one, look each partner up.
    fn carry_history(&self, old_of_new: Option<&[u32]>, task: RowTask) {
        let old = self;
        let stride = self.stride;
        let RowTask {
            first_row,
            at,
            chunk,
            i: is,
            j: js,
            starts,
            history: hist,
        } = task;
        js.copy_from_slice(&chunk.j);
        let mut p = 0;
        for (r, &count) in chunk.counts.iter().enumerate() {
            let i = first_row + r;
            let row = p..p + count as usize;
            is[row.clone()].fill(i as u32);
            starts[r] = (at + row.end) as u32;
            let old_row = old.row_of(old_of_new.map_or(i, |m| m[i] as usize));
            let mut k = old_row.start;
            for p in row.clone() {
                let j = chunk.j[p];
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
                let h = &mut hist[p * stride..(p + 1) * stride];
                match found {
                    Some(q) => h.copy_from_slice(&old.history[q * stride..(q + 1) * stride]),
                    None => h.fill(0.0),
                }
            }
            p = row.end;
        }
    }

    /// The pairs in the row of particle `p` (as it was numbered when this list was built);
    /// empty for a particle the list has not seen.
    fn row_of(&self, p: usize) -> std::ops::Range<usize> {
        if p + 1 < self.row_start.len() {
            self.row_start[p] as usize..self.row_start[p + 1] as usize
        } else {
            0..0
        }
    }

    /// Bytes of heap memory held.
    pub fn heap_bytes(&self) -> usize {
        let index = [&self.i, &self.j, &self.row_start];
        capacity_bytes(index, &self.history) + self.spare.heap_bytes()
    }
}

/// Heap bytes of a list's index vectors and history.
fn capacity_bytes(index: [&Vec<u32>; 3], history: &Vec<f64>) -> usize {
    4 * index.iter().map(|v| v.capacity()).sum::<usize>() + 8 * history.capacity()
}

/// Empties `v` and makes room for `len` values: in place when it has the room, else in a
/// new allocation with an eighth to spare (the old one freed first), so that a slowly
/// growing list reallocates now and then, not at every rebuild.
fn room<T>(v: &mut Vec<T>, len: usize) {
    v.clear();
    if v.capacity() < len {
        *v = Vec::new();
        *v = Vec::with_capacity(len + len / 8);
    }
}

/// `v` holding `len` values: what it held before, zeros where it grew (all zeros when it
/// needed a new allocation); in place when it has the room, else as [`room`].
pub(crate) fn resized<T: Default + Clone>(v: &mut Vec<T>, len: usize) {
    if v.capacity() < len {
        room(v, len);
    }
    v.truncate(len);
    v.resize(len, T::default());
}

impl Search<'_> {
    /// The partners of particles `rows` (one task's chunk), with room for `per_row` a row.
    fn rows(&self, rows: std::ops::Range<usize>, per_row: usize) -> RowChunk {
        let mut out = RowChunk {
            counts: Vec::with_capacity(rows.len()),
            j: Vec::with_capacity(rows.len() * per_row),
        };
        let mut near = Vec::with_capacity(64);
        for i in rows {
            self.partners(i, &mut near);
            out.counts.push(near.len() as u32);
            out.j.extend_from_slice(&near);
        }
        out
    }

    /// Sets `near` to particle i's partners, ascending: the particles of larger id whose
    /// surfaces are closer than `extra`, and the old list's kept pairs of i.
    #[inline]
    fn partners(&self, i: usize, near: &mut Vec<u32>) {
        let (position, radius, id, extra) = (self.position, self.radius, self.id, self.extra);
        let old = self.old;
        let stride = old.stride;
        near.clear();
        let (pi, ri) = (position[i], radius[i]);
        let idi = id[i];
        // Room for every candidate at once: sized run by run, the vector's
        // bookkeeping and zero fill came nine times a particle.
        let (runs, count, points) = self.grid.near_runs(pi);
        near.resize(points, 0);
        let mut len = 0;
        for run in &runs[..count] {
            // Whether a candidate is kept is close to a coin toss (about half
            // have the larger id), which a branch predictor loses: write every
            // candidate and advance past the kept ones only. 30 % off the search
            // on the settling bed; the list is the same.
            for &j in *run {
                let ju = j as usize;
                let cut = ri + radius[ju] + extra;
                let close = (position[ju] - pi).length_squared() < cut * cut;
                near[len] = j;
                len += ((id[ju] > idi) & close) as usize;
            }
        }
        near.truncate(len);
        if let Some(keep) = self.keep {
            for q in old.row_of(self.old_of_new.map_or(i, |m| m[i] as usize)) {
                if keep(&old.history[q * stride..(q + 1) * stride]) {
                    let j = match self.new_of_old {
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
    }
}

impl Buffers {
    fn heap_bytes(&self) -> usize {
        let index = [&self.i, &self.j, &self.row_start];
        capacity_bytes(index, &self.history)
    }

    /// Refills the buffers for a new list of `n` rows of `stride` history values a pair,
    /// with the partners `chunks` found, and splits them into the chunks' tasks. Every
    /// value is left for the tasks to write, in parallel: joining the chunks' rows and
    /// zeroing the history first were serial passes while the other thread waited.
    fn refill(&mut self, chunks: Vec<RowChunk>, n: usize, stride: usize) -> Vec<RowTask<'_>> {
        let total: usize = chunks.iter().map(|c| c.j.len()).sum();
        resized(&mut self.i, total);
        resized(&mut self.j, total);
        resized(&mut self.row_start, n + 1);
        resized(&mut self.history, total * stride);
        self.row_start[0] = 0;
        let mut tasks = Vec::with_capacity(chunks.len());
        let (mut is, mut js) = (&mut self.i[..], &mut self.j[..]);
        let (mut starts, mut hist) = (&mut self.row_start[1..], &mut self.history[..]);
        let mut at = 0;
        for (c, chunk) in chunks.into_iter().enumerate() {
            let len = chunk.j.len();
            let (i1, i2) = std::mem::take(&mut is).split_at_mut(len);
            let (j1, j2) = std::mem::take(&mut js).split_at_mut(len);
            let (s1, s2) = std::mem::take(&mut starts).split_at_mut(chunk.counts.len());
            let (h1, h2) = std::mem::take(&mut hist).split_at_mut(len * stride);
            (is, js, starts, hist) = (i2, j2, s2, h2);
            tasks.push(RowTask {
                first_row: c * CHUNK,
                at,
                chunk,
                i: i1,
                j: j1,
                starts: s1,
                history: h1,
            });
            at += len;
        }
        tasks
    }
}
