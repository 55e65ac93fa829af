//! Keeping the neighbour lists: the particles' periodic reorder into cell order, and the
//! rebuild of the pair list, its phase schedule and the wall contact list, which carries
//! every contact's history across (and keeps bonded pairs listed).

use super::Simulation;
use crate::neighbor::{CellGrid, PairSchedule, build_wall_contacts};

impl Simulation {
    /// Puts the particles in cell order; the next rebuild carries history through the
    /// permutation.
    pub(super) fn sort_particles(&mut self) {
        let p = &self.particles;
        let r_max = p.radius.iter().copied().fold(0.0, f64::max);
        // Cells from the particle size alone, so the order does not depend on the skin (nor
        // the bits: a test runs two skins). A quarter over the diameter, so that the cut of
        // the usual skins (up to half a radius) spans one layer of cells, not two: in cells
        // of one diameter a partner could lie two layers away in index, and each block of
        // the pair schedule reached twice as far beyond its rows (settled bed: 2.1 partial
        // sums a particle in cells of 2 r, 1.8 in cells of 2.5 r).
        let grid = CellGrid::build(&p.position, 2.5 * r_max);
        let order = grid.cell_order().to_vec();
        self.particles.permute(&order);
        self.refresh_kick_factor();
        self.pending_order = Some(order);
    }

    /// Rebuilds the pair list, its phase schedule and the wall contact list for the current
    /// positions (through a pending reorder), carrying every contact's history; intact bonds
    /// keep their pairs listed, and the bonds the new list drops are retired.
    pub(super) fn rebuild(&mut self) {
        self.rebuilds += 1;
        let bonded_before = self
            .bonded
            .then(|| self.bonded_pairs(self.pending_order.as_deref()));
        let p = &self.particles;
        let extra = self.extra;
        let pairs = &mut self.pairs;
        let walls = &self.walls;
        let old = &self.walls_near;
        let stride = self.model.history_stride();
        let order = self.pending_order.take();
        let model = &self.model;
        let bonded = self.bonded;
        let keep = |h: &[f64]| model.bond_intact(h);
        let (new_walls, schedule) = self.pool.install(|| {
            // Intact bonds keep their pairs in the list, however far they stretch.
            let keep: Option<crate::neighbor::pairs::PairFilter<'_>> = bonded.then_some(&keep);
            pairs.rebuild_keeping(&p.position, &p.radius, &p.id, extra, order.as_deref(), keep);
            let walls = build_wall_contacts(p, walls, old, extra, stride, order.as_deref());
            let schedule =
                PairSchedule::build(&pairs.row_start, &pairs.j, &pairs.history, pairs.stride);
            (walls, schedule)
        });
        self.walls_near = new_walls;
        self.schedule = schedule;
        self.ref_position.clone_from(&self.particles.position);
        for (r, w) in self.wall_ref_offset.iter_mut().zip(&self.walls) {
            *r = w.offset;
        }
        if let Some(before) = bonded_before {
            self.retire_dropped_bonds(before);
        }
    }
}
