//! Linked cells: particles binned into a uniform grid by a counting sort.

use glam::DVec3;

pub struct CellGrid {
    origin: DVec3,
    inv_cell: f64,
    dims: [usize; 3],
    /// Particles of cell c are `items[start[c]..start[c + 1]]`, in ascending index.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    /// Bins `points` into cells no smaller than `min_cell` (m). The cell count is capped at
    /// a few per point so a few stray particles cannot blow up memory.
    pub fn build(points: &[DVec3], min_cell: f64) -> CellGrid {
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
        let max_cells = (4 * points.len()).max(64) as f64;
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
            start: vec![0; ncell + 1],
            items: vec![0; points.len()],
        };
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
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
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
        let lo = |k: usize| c[k].saturating_sub(1);
        let hi = |k: usize| (c[k] + 1).min(self.dims[k] - 1);
        for z in lo(2)..=hi(2) {
            for y in lo(1)..=hi(1) {
                let row = (z * self.dims[1] + y) * self.dims[0];
                let (a, b) = (row + lo(0), row + hi(0));
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
}
