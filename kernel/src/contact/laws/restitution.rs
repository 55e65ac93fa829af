//! `restitution`: viscous damping set from a coefficient of restitution e.
//!
//! beta = ln(e) / sqrt(ln(e)^2 + pi^2); for a spring of stiffness S (N/m) acting on m* (kg),
//! eta = -2 sqrt(5/6) beta sqrt(S m*)  (N s/m), and the damping force is -eta v.
//! Applied to the normal (S = S_n) and the tangential (S = S_t) relative velocity.
//!
//! Reference: Tsuji et al. (1992); EDEM "Hertz-Mindlin (no slip)"; LIGGGHTS `hertz`;
//! LAMMPS `damping coeff_restitution`. e = 1 gives no damping.
//!
//! ```
//! use tilth_kernel::contact::laws::restitution::beta;
//! assert!((beta(0.45) - 0.45f64.ln() / (0.45f64.ln().powi(2) + std::f64::consts::PI.powi(2)).sqrt()).abs() < 1e-15);
//! assert_eq!(beta(1.0), 0.0);
//! ```

use crate::contact::{BuiltLaw, DampingLaw, F, LawEntry, LawInput, Slot};
use crate::param::{Bound, ParamSpec};

pub const RESTITUTION: ParamSpec = ParamSpec {
    key: "restitution",
    unit: "-",
    min: Bound::Open(0.0),
    max: Bound::Closed(1.0),
    default: None,
    doc: "coefficient of restitution",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "restitution",
    slot: Slot::Damping,
    summary: "viscous damping from a coefficient of restitution (EDEM / LIGGGHTS Hertz damping)",
    params: &[RESTITUTION],
    history: &[],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    let b = beta(input.params.get(&RESTITUTION));
    BuiltLaw::Damping(Restitution { factor: -2.0 * (5.0f64 / 6.0).sqrt() * b }.into())
}

/// beta = ln(e) / sqrt(ln(e)^2 + pi^2) (dimensionless, <= 0).
pub fn beta(e: f64) -> f64 {
    let l = e.ln();
    l / (l * l + std::f64::consts::PI.powi(2)).sqrt()
}

pub struct Restitution {
    /// -2 sqrt(5/6) beta.
    factor: f64,
}

impl DampingLaw for Restitution {
    #[inline]
    fn coefficient(&self, stiffness: f64, m_eff: f64) -> f64 {
        self.factor * (stiffness * m_eff).sqrt()
    }

    #[inline(always)]
    fn coefficient_lanes(&self, stiffness: F, m_eff: F) -> F {
        self.factor * (stiffness * m_eff).sqrt()
    }
}
