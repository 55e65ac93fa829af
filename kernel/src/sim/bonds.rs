//! Bonds between particles: forming them, reporting them (intact and broken, loads and
//! breaking times), counting them, and keeping as retired those whose pairs a rebuild drops.

use super::Simulation;
use super::time_step::bond_step_warning;
use crate::contact::{BondState, BondStatus};

impl Simulation {
    /// Bonds every listed pair closer than the bond law's contact radius sum that has never
    /// been bonded (a broken bond never re-forms). Returns how many bonds formed; none
    /// without a bond law. New bonds carry no load. Call it between steps; the result does
    /// not depend on the thread count.
    pub fn form_bonds(&mut self) -> usize {
        if !self.model.has_bond() {
            return 0;
        }
        let p = &self.particles;
        let list = &mut self.pairs;
        let stride = list.stride;
        let mut formed = 0;
        let mut shortest = f64::INFINITY;
        for k in 0..list.len() {
            let (i, j) = (list.i[k] as usize, list.j[k] as usize);
            let h = &mut list.history[k * stride..(k + 1) * stride];
            let key = (p.id[i].min(p.id[j]), p.id[i].max(p.id[j]));
            if self.retired_bonds.contains_key(&key) {
                continue;
            }
            let (a, b) = (p.material[i] as usize, p.material[j] as usize);
            let r = (p.radius[i], p.radius[j]);
            if self
                .model
                .form_bond(a, b, r, (p.position[j] - p.position[i]).length(), h)
            {
                formed += 1;
                let mass = p.mass[i].min(p.mass[j]);
                if let Some(t) = self.model.bond_time_scale(a, b, mass, r) {
                    shortest = shortest.min(t);
                }
            }
        }
        self.bonded |= formed > 0;
        if let Some(w) = bond_step_warning(self.dt, shortest) {
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
        }
        formed
    }

    /// Every bond ever formed, intact or broken, ordered by particle ids (`i < j`, stable
    /// ids, not indices), with the loads on particle i (zero once broken) and the time it
    /// broke.
    pub fn bonds(&self) -> Vec<BondState> {
        let p = &self.particles;
        let list = &self.pairs;
        let stride = list.stride;
        let mut out: Vec<BondState> = (0..list.len())
            .filter_map(|k| {
                let (i, j) = (list.i[k] as usize, list.j[k] as usize);
                let h = &list.history[k * stride..(k + 1) * stride];
                let (loads, broken_time) =
                    self.model
                        .bond_loads(p.material[i] as usize, p.material[j] as usize, h)?;
                // The list keeps each pair in the row of its smaller id.
                debug_assert!(p.id[i] < p.id[j]);
                Some(BondState {
                    i: p.id[i],
                    j: p.id[j],
                    loads,
                    broken_time,
                })
            })
            .collect();
        out.extend(self.retired_bonds.iter().map(|(&(i, j), &t)| BondState {
            i,
            j,
            loads: Default::default(),
            broken_time: Some(t),
        }));
        out.sort_unstable_by_key(|b| (b.i, b.j));
        out
    }

    /// Numbers of intact and of broken bonds.
    pub fn bond_counts(&self) -> (usize, usize) {
        if !self.bonded {
            return (0, 0);
        }
        let list = &self.pairs;
        let stride = list.stride;
        let (mut intact, mut broken) = (0, self.retired_bonds.len());
        for k in 0..list.len() {
            match self
                .model
                .bond_status(&list.history[k * stride..(k + 1) * stride])
            {
                BondStatus::Intact => intact += 1,
                BondStatus::Broken(_) => broken += 1,
                BondStatus::None => {}
            }
        }
        (intact, broken)
    }

    /// The bonded pairs of the current list by (smaller id, larger id), with their status.
    /// `old_of_new`: a reorder applied to the particles since the list was built.
    pub(super) fn bonded_pairs(&self, old_of_new: Option<&[u32]>) -> Vec<((u32, u32), BondStatus)> {
        let p = &self.particles;
        let ids: std::borrow::Cow<[u32]> = match old_of_new {
            None => (&p.id[..]).into(),
            Some(order) => {
                let mut ids = vec![0; order.len()];
                for (new, &old) in order.iter().enumerate() {
                    ids[old as usize] = p.id[new];
                }
                ids.into()
            }
        };
        let list = &self.pairs;
        let stride = list.stride;
        (0..list.len())
            .filter_map(|k| {
                let status = self
                    .model
                    .bond_status(&list.history[k * stride..(k + 1) * stride]);
                let (a, b) = (ids[list.i[k] as usize], ids[list.j[k] as usize]);
                (status != BondStatus::None).then_some(((a.min(b), a.max(b)), status))
            })
            .collect()
    }

    /// Keeps the bonds a rebuild dropped from the list. A broken one keeps its time; an
    /// intact one can only have been dropped stretched beyond the bond law's reach, where its
    /// tensile stress exceeds the strength, so it breaks now, as it would have in this step.
    pub(super) fn retire_dropped_bonds(&mut self, before: Vec<((u32, u32), BondStatus)>) {
        let mut after: Vec<(u32, u32)> = self
            .bonded_pairs(None)
            .into_iter()
            .map(|(k, _)| k)
            .collect();
        after.sort_unstable();
        for (key, status) in before {
            if after.binary_search(&key).is_err() {
                let time = match status {
                    BondStatus::Broken(t) => t,
                    _ => self.time,
                };
                self.retired_bonds.insert(key, time);
            }
        }
    }
}
