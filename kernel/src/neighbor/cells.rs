//! Linked cells: particles binned into a uniform grid by a counting sort.

use glam::DVec3;

pub struct CellGrid {
    origin: DVec3,
    inv_cell: f64,
    dims: [usize; 3],
    /// The axes from the fastest-varying in the cells' linear order to the slowest. A
    /// particle's neighbours lie within one layer of cells across the slowest axis, so in
    /// cell order they are up to about one layer's particles away in index. That distance
    /// sets how far each pair-phase block reaches beyond its own rows, and so how many rows
    /// a block needs to keep its neighbours apart (`PairSchedule`). So the slowest axis is the one whose
    /// layers hold the fewest points, as each point sees its own (see `axis_order`), and
    /// the fastest the one of fewer cells of the other two. A settled bed 60 x 60 mm wide
    /// and 40 mm deep, in cells of 2.5 mm: layers across x of 24 x 16 cells, where layers
    /// across z hold 24 x 24 (its bounding box does not show it while a few particles are
    /// still falling far above the bed).
    axes: [usize; 3],
    /// Particles of cell c are `items[start[c]..start[c + 1]]`, in ascending index.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    /// Bins `points` into cells no smaller than `min_cell` (m). The cell count is capped at
    /// four per point so a few stray particles cannot blow up memory.
    pub fn build(points: &[DVec3], min_cell: f64) -> CellGrid {
        Self::build_capped(points, min_cell, 4)
    }

    /// [`CellGrid::build`] with at most `cells_per_point` cells a point (at least 64 in
    /// all). Where the cap binds, cells grow past `min_cell` and a search through them
    /// scans (cell / min_cell)^3 times the points it needs.
    pub fn build_capped(points: &[DVec3], min_cell: f64, cells_per_point: usize) -> CellGrid {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in points {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if points.is_empty() {
            lo = DVec3::ZERO;
            hi = DVec3::ZERO;
        }
        // A zero or non-finite cell (no particles yet) would never satisfy the cap below.
        let min_cell = if min_cell > 0.0 && min_cell.is_finite() {
            min_cell
        } else {
            1.0
        };
        let extent = (hi - lo).max(DVec3::splat(min_cell));
        let mut cell = min_cell;
        let max_cells = (cells_per_point * points.len()).max(64) as f64;
        loop {
            let d = (extent / cell).floor() + DVec3::ONE;
            if d.x * d.y * d.z <= max_cells || !cell.is_finite() {
                break;
            }
            cell *= 1.25;
        }
        let d = (extent / cell).floor() + DVec3::ONE;
        let dims = [d.x as usize, d.y as usize, d.z as usize];
        let inv_cell = 1.0 / cell;
        let ncell = dims[0] * dims[1] * dims[2];
        let mut grid = CellGrid {
            origin: lo,
            inv_cell,
            dims,
            axes: [0, 1, 2],
            start: vec![0; ncell + 1],
            items: vec![0; points.len()],
        };
        grid.axes = grid.axis_order(points);
        let cells: Vec<u32> = points
            .iter()
            .map(|p| grid.linear(grid.coords(*p)) as u32)
            .collect();
        for &c in &cells {
            grid.start[c as usize + 1] += 1;
        }
        for c in 0..ncell {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill = grid.start.clone();
        for (i, &c) in cells.iter().enumerate() {
            grid.items[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        grid
    }

    /// Every binned index, cell by cell: a spatially coherent order for the particles.
    pub fn cell_order(&self) -> &[u32] {
        &self.items
    }

    #[inline]
    fn coords(&self, p: DVec3) -> [usize; 3] {
        let q = (p - self.origin) * self.inv_cell;
        [
            (q.x.max(0.0) as usize).min(self.dims[0] - 1),
            (q.y.max(0.0) as usize).min(self.dims[1] - 1),
            (q.z.max(0.0) as usize).min(self.dims[2] - 1),
        ]
    }

    #[inline]
    fn linear(&self, c: [usize; 3]) -> usize {
        let [fast, mid, slow] = self.axes;
        (c[slow] * self.dims[mid] + c[mid]) * self.dims[fast] + c[fast]
    }

    /// Calls `f(run)` for each run of binned points in the 27 cells around `p`: the cells of
    /// one row of the 3 x 3 x 3 block are consecutive, so each row is one slice.
    #[inline]
    pub fn for_each_near_run(&self, p: DVec3, mut f: impl FnMut(&[u32])) {
        let (runs, count, _) = self.near_runs(p);
        runs[..count].iter().for_each(|run| f(run));
    }

    /// The runs of [`CellGrid::for_each_near_run`] at once: up to nine slices (fewer at
    /// the grid's faces), the count of them, and how many points they hold together.
    #[inline]
    pub fn near_runs(&self, p: DVec3) -> ([&[u32]; 9], usize, usize) {
        let mut runs: [&[u32]; 9] = [&[]; 9];
        let (mut count, mut points) = (0, 0);
        let c = self.coords(p);
        let [fast, mid, slow] = self.axes;
        let lo = |k: usize| c[k].saturating_sub(1);
        let hi = |k: usize| (c[k] + 1).min(self.dims[k] - 1);
        for s in lo(slow)..=hi(slow) {
            for m in lo(mid)..=hi(mid) {
                let row = (s * self.dims[mid] + m) * self.dims[fast];
                let (a, b) = (row + lo(fast), row + hi(fast));
                let run = &self.items[self.start[a] as usize..self.start[b + 1] as usize];
                runs[count] = run;
                count += 1;
                points += run.len();
            }
        }
        (runs, count, points)
    }

    /// Calls `f(j)` for every binned point in the 27 cells around `p`.
    #[inline]
    pub fn for_each_near(&self, p: DVec3, mut f: impl FnMut(u32)) {
        self.for_each_near_run(p, |run| run.iter().for_each(|&j| f(j)));
    }
}

impl CellGrid {
    /// The linear order's axes, fastest first (see [`CellGrid`]'s `axes`). The slowest is
    /// the axis whose layers' counts have the smallest sum of squares: the sum, over the
    /// points, of the count of each point's own layer, which is what a block of rows reaches
    /// past its own (ties: z, then y, then x, the order before this choice). The fastest is
    /// the one of fewer cells of the other two (ties: the lower axis).
    fn axis_order(&self, points: &[DVec3]) -> [usize; 3] {
        let dims = self.dims;
        let mut count: [Vec<u32>; 3] = dims.map(|d| vec![0; d]);
        for p in points {
            let c = self.coords(*p);
            for a in 0..3 {
                count[a][c[a]] += 1;
            }
        }
        // The sum of squares: each point's own layer's count, summed over the points.
        let seen = count.map(|c| c.into_iter().map(|k| (k as u64).pow(2)).sum::<u64>());
        let slow = [2, 1, 0]
            .into_iter()
            .min_by_key(|&a| seen[a])
            .expect("three axes");
        let mut rest = [0, 1, 2].into_iter().filter(|&a| a != slow);
        let (a, b) = (rest.next().unwrap(), rest.next().unwrap());
        let (fast, mid) = if dims[b] < dims[a] { (b, a) } else { (a, b) };
        [fast, mid, slow]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_single_point_grids_terminate() {
        let g = CellGrid::build(&[], 0.0);
        let mut n = 0;
        g.for_each_near(DVec3::ZERO, |_| n += 1);
        assert_eq!(n, 0);
        let g = CellGrid::build(&[DVec3::ONE], 0.0);
        g.for_each_near(DVec3::ONE, |_| n += 1);
        assert_eq!(n, 1);
    }

    /// Points on a jittered lattice filling a box of `n` points along each axis, spacing 1.
    fn lattice(n: [usize; 3]) -> Vec<DVec3> {
        let mut points = vec![];
        for x in 0..n[0] {
            for y in 0..n[1] {
                for z in 0..n[2] {
                    let jitter = ((x * 7 + y * 13 + z * 29) % 10) as f64 * 0.03;
                    points.push(DVec3::new(x as f64, y as f64, z as f64) + jitter);
                }
            }
        }
        points
    }

    #[test]
    fn cells_grow_past_the_minimum_only_where_the_cap_binds() {
        // 1,000 points in a 10 x 10 x 10 lattice of spacing 1 and one far off: a box of
        // 100 x 10 x 10 = 10,000 cells of 1. Four cells a point (4,004) cannot hold it,
        // so the cells grow by 1.25 until they fit; 32 a point (32,032) can.
        let mut points = lattice([10, 10, 10]);
        points.push(DVec3::new(99.0, 0.0, 0.0));
        let capped = CellGrid::build_capped(&points, 1.0, 4);
        let dims = capped.dims.iter().product::<usize>();
        assert!(dims <= 4 * points.len(), "{dims} cells");
        assert!(1.0 / capped.inv_cell > 1.0);
        let roomy = CellGrid::build_capped(&points, 1.0, 32);
        assert_eq!(roomy.inv_cell, 1.0);
        assert_eq!(roomy.dims, [100, 10, 10]);
    }

    #[test]
    fn near_runs_find_every_point_within_a_cell_whichever_axis_is_longest() {
        for n in [[12, 5, 4], [4, 12, 5], [5, 4, 12], [6, 6, 6]] {
            let points = lattice(n);
            let cell = 1.5;
            let g = CellGrid::build(&points, cell);
            for (i, &p) in points.iter().enumerate() {
                let mut near = vec![];
                g.for_each_near(p, |j| near.push(j as usize));
                near.sort();
                let expected: Vec<usize> = (0..points.len())
                    .filter(|&j| (points[j] - p).length() < cell)
                    .collect();
                for j in &expected {
                    assert!(near.binary_search(j).is_ok(), "{n:?}: {j} near {i}");
                }
            }
        }
    }

    #[test]
    fn in_cell_order_neighbours_lie_within_a_layer_across_the_longest_axis() {
        // 24 x 10 x 6 points: the layer across the longest axis holds 10 x 6 cells. Five
        // stragglers far out along the shortest axis make it the longest of the bounding
        // box (as particles still falling above a bed do), not of the fullest layer.
        for n in [[24, 10, 6], [6, 24, 10], [10, 6, 24]] {
            let mut points = lattice(n);
            let short = (0..3).min_by_key(|&a| n[a]).unwrap();
            for k in 0..5 {
                let mut far = DVec3::ZERO;
                far[short] = 40.0 + 3.0 * k as f64;
                points.push(far);
            }
            let g = CellGrid::build(&points, 1.0);
            let mut index = vec![0; points.len()];
            for (k, &i) in g.cell_order().iter().enumerate() {
                index[i as usize] = k;
            }
            let reach = (0..points.len())
                .flat_map(|i| {
                    let points = &points;
                    (0..points.len())
                        .filter(move |&j| (points[j] - points[i]).length() < 1.0)
                        .map(move |j| (i, j))
                })
                .map(|(i, j)| index[i].abs_diff(index[j]))
                .max()
                .unwrap();
            // Two layers of cells and two rows at most (a neighbour is within one cell
            // along each axis), and at least half a layer: a neighbour across the longest
            // axis is a layer away. With z the slowest axis, as before the choice, the
            // first case reaches 240.
            let (layer, row) = (10 * 6, 10);
            assert!(reach <= 2 * layer + 2 * row, "{n:?}: reach {reach}");
            assert!(reach >= layer / 2, "{n:?}: reach {reach}");
        }
    }
}
