//! `jkr_lammps`: JKR adhesion as LAMMPS's `pair_style granular` `jkr` has it: `jkr`'s force,
//! the neck broken at the force minimum and friction loaded by the force plus twice the
//! pull-off force.
//!
//! The force is `jkr`'s (see `jkr.rs`, with gamma the surface energy, J/m^2):
//!   delta = a^2/R* - sqrt(4 pi gamma a / E*),   F = 4 E* a^3 / (3 R*) - 4 sqrt(pi gamma E*) a^(3/2),
//! and the contact forms on touching. Two things differ from `jkr` (EDEM's documented law):
//! - the neck breaks where F is least, F_min = -3 pi gamma R* = -F_po, at
//!   delta_m = a_m^2/R* - sqrt(4 pi gamma a_m / E*), a_m = [9 pi gamma R*^2 / (4 E*)]^(1/3),
//!   as under load control (LAMMPS keeps a contact while delta > delta_m), instead of
//!   following the curve to the displacement-controlled delta_c, 2.07 times as far;
//! - the Coulomb load (friction's and rolling resistance's) is |F + 2 F_po| (LAMMPS's
//!   `Fncrit`), 6 pi gamma R* at no net force, where `jkr` takes the Hertz part
//!   4 E* a^3 / (3 R*), 12 pi gamma R* there.
//!
//! Which to choose: `jkr` to reproduce an EDEM calibration (the study's), `jkr_lammps` a
//! LAMMPS one. docs/physics.md, "Cohesion: JKR", has what each does to the study's funnel test.
//! The break is checked against LAMMPS's own pull (tests/golden/lammps/, `pp_jkr_pulloff`).
//!
//! Reference: Johnson, Kendall, Roberts (1971) Proc. R. Soc. A 324:301; LAMMPS
//! documentation, `pair_style granular` (normal model `jkr`, the critical force for friction).
//!
//! ```
//! use tilth_kernel::contact::laws::jkr::Jkr;
//! let jkr = Jkr::new(7.03125e6, 0.356);
//! let r = 5e-4;
//! // The break is at the force minimum, -3 pi gamma R*, short of delta_c:
//! let a_m = (9.0 * std::f64::consts::PI * 0.356 * r * r / (4.0 * 7.03125e6f64)).cbrt();
//! assert!((jkr.force_at_radius(a_m, r) + jkr.pulloff_force(r)).abs() < 1e-12);
//! assert!(jkr.pulloff_overlap(r) > jkr.critical_overlap(r));
//! ```

use super::jkr::{HISTORY, Jkr, SURFACE_ENERGY};
use crate::contact::{
    BuiltLaw, Contact, ContactLanes, F, LawEntry, LawInput, NormalForce, NormalForceLanes,
    NormalLaw, Slot,
};

pub const ENTRY: LawEntry = LawEntry {
    name: "jkr_lammps",
    slot: Slot::Normal,
    summary: "JKR adhesive normal force as LAMMPS's granular jkr (broken at the force minimum, friction loaded by |F + 2 F_pulloff|)",
    params: &[SURFACE_ENERGY],
    // The force is Jkr's, so is its history.
    history: HISTORY,
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Normal(JkrLammps(Jkr::new(input.e_eff, input.params.get(&SURFACE_ENERGY))).into())
}

/// `jkr`'s force with LAMMPS's break and Coulomb load.
pub struct JkrLammps(pub Jkr);

impl NormalLaw for JkrLammps {
    #[inline]
    fn force(&self, c: &Contact, history: &mut [f64]) -> NormalForce {
        let mut out = self
            .0
            .force_breaking_at(c, history, |r| self.0.pulloff_overlap(r));
        if out.contact_radius > 0.0 {
            out.friction_load = (out.elastic + 2.0 * self.0.pulloff_force(c.r_eff)).abs();
        }
        out
    }

    fn reach(&self, r_eff: f64) -> f64 {
        -self.0.pulloff_overlap(r_eff)
    }

    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> NormalForceLanes {
        let mut out = self.0.force_lanes_with(c, history, |c, h| self.force(c, h));
        // The lanes of a broken neck (no contact radius) keep their zero load.
        let load = (out.elastic + 2.0 * self.0.pulloff_force_lanes(c.r_eff)).abs();
        out.friction_load = F::select(out.contact_radius.le(F::ZERO), out.friction_load, load);
        out
    }
}
