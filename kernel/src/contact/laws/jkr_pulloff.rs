//! `jkr_pulloff`: the JKR force of `jkr`, its neck broken at the pull-off force (LAMMPS's
//! `pair_style granular` `jkr`).
//!
//! The force is `jkr`'s (see `jkr.rs`, with gamma the surface energy, J/m^2):
//!   delta = a^2/R* - sqrt(4 pi gamma a / E*),   F = 4 E* a^3 / (3 R*) - 4 sqrt(pi gamma E*) a^(3/2),
//! and the contact forms on touching. It breaks where F is least, F_min = -3 pi gamma R*, at
//!   delta_m = a_m^2/R* - sqrt(4 pi gamma a_m / E*),   a_m = [9 pi gamma R*^2 / (4 E*)]^(1/3),
//! as under load control, instead of following the curve to the displacement-controlled
//! delta_c (`jkr`, EDEM's "Hertz-Mindlin with JKR"), about 2.1 times as far. The work to
//! separate a pair is therefore smaller: the area under the curve from delta_m to 0 instead
//! of delta_c to 0. LAMMPS keeps a contact while delta > delta_m (its `touch()` for `jkr`,
//! checked against LAMMPS in tests/golden/lammps/, case `pp_jkr_pulloff`).
//!
//! Which to choose: `jkr` to reproduce an EDEM calibration (the study's), `jkr_pulloff` to
//! reproduce a LAMMPS one. docs/physics.md, "Cohesion: JKR", has what each does to a heap.
//!
//! Reference: Johnson, Kendall, Roberts (1971) Proc. R. Soc. A 324:301; LAMMPS
//! documentation, `pair_style granular` (normal model `jkr`).
//!
//! ```
//! use tilth_kernel::contact::laws::jkr::Jkr;
//! let jkr = Jkr::new(7.03125e6, 0.356);
//! let r = 5e-4;
//! // The break is at the force minimum, -3 pi gamma R*, short of delta_c:
//! let a_m = (9.0 * std::f64::consts::PI * 0.356 * r * r / (4.0 * 7.03125e6f64)).cbrt();
//! assert!((jkr.force_at_radius(a_m, r) + 3.0 * std::f64::consts::PI * 0.356 * r).abs() < 1e-12);
//! assert!(jkr.pulloff_overlap(r) > jkr.critical_overlap(r));
//! ```

use super::jkr::{Jkr, SURFACE_ENERGY};
use crate::contact::{
    BuiltLaw, Contact, ContactLanes, F, LawEntry, LawInput, NormalForce, NormalForceLanes,
    NormalLaw, Slot,
};

pub const ENTRY: LawEntry = LawEntry {
    name: "jkr_pulloff",
    slot: Slot::Normal,
    summary: "JKR adhesive normal force, broken at the pull-off force (LAMMPS granular jkr)",
    params: &[SURFACE_ENERGY],
    history: &["jkr_sqrt_contact_radius"],
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Normal(JkrPulloff(Jkr::new(input.e_eff, input.params.get(&SURFACE_ENERGY))).into())
}

/// `jkr`'s force with the neck broken at the force minimum.
pub struct JkrPulloff(pub Jkr);

impl NormalLaw for JkrPulloff {
    #[inline]
    fn force(&self, c: &Contact, history: &mut [f64]) -> NormalForce {
        self.0
            .force_breaking_at(c, history, self.0.pulloff_overlap(c.r_eff))
    }

    fn reach(&self, r_eff: f64) -> f64 {
        -self.0.pulloff_overlap(r_eff)
    }

    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> NormalForceLanes {
        self.0.force_lanes_with(c, history, |c, h| self.force(c, h))
    }
}
