//! `jkr`: Johnson-Kendall-Roberts adhesive elastic normal force (EDEM "Hertz-Mindlin with JKR").
//!
//! With surface energy gamma (J/m^2), the contact radius a (m) follows from the overlap:
//!   delta = a^2/R* - sqrt(4 pi gamma a / E*),
//! and the normal force (N, positive repulsive) is
//!   F = 4 E* a^3 / (3 R*) - 4 sqrt(pi gamma E*) a^(3/2).
//! The contact forms on touching and keeps pulling at negative overlap down to
//!   delta_c = a_c^2/R* - sqrt(4 pi gamma a_c / E*),  a_c = [9 pi gamma R*^2 / (2 E*) (3/4 - 1/sqrt(2))]^(1/3),
//! where it breaks. The least force on the curve is F_min = -3 pi gamma R* (so gamma here is half
//! the work of adhesion; EDEM's page prints 3/2 pi gamma R*, see docs/physics.md). Friction is loaded
//! by the repulsive Hertz part 4 E* a^3 / (3 R*), the normal stiffness is S_n = 2 E* a.
//!
//! a is found on the stable branch by Newton's method on s = sqrt(a):
//! f(s) = s^4 - c R* s - delta R* = 0, c = sqrt(4 pi gamma / E*); f is convex for s > 0, so Newton
//! started right of the largest root descends onto it monotonically. The last s is kept in the
//! contact history as the next step's start (two or three iterations instead of ten).
//!
//! Reference: Johnson, Kendall, Roberts (1971) Proc. R. Soc. A 324:301; EDEM 2020 documentation.
//!
//! ```
//! use tilth_kernel::contact::laws::jkr::Jkr;
//! let jkr = Jkr::new(7.03125e6, 0.356);
//! let r = 5e-4;
//! // The minimum of F over a is -3 pi gamma R*:
//! let a_min = (3.0 * (std::f64::consts::PI * 0.356 * 7.03125e6f64).sqrt() * r / (2.0 * 7.03125e6)).powf(2.0 / 3.0);
//! let f = jkr.force_at_radius(a_min, r);
//! assert!((f + 3.0 * std::f64::consts::PI * 0.356 * r).abs() < 1e-12);
//! ```

use crate::contact::{
    ContactLanes, F, LANES, M, NormalForceLanes, with_lane_history,BuiltLaw, Contact, LawEntry, LawInput, NormalForce, NormalLaw, Slot};
use crate::param::{Bound, ParamSpec};
use std::f64::consts::PI;

pub const SURFACE_ENERGY: ParamSpec = ParamSpec {
    key: "surface_energy",
    unit: "J/m^2",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "JKR surface energy gamma (EDEM convention)",
};

/// The history a contact of [`Jkr`] keeps: sqrt(a), Newton's next start (see the module).
pub const HISTORY: &[&str] = &["jkr_sqrt_contact_radius"];

pub const ENTRY: LawEntry = LawEntry {
    name: "jkr",
    slot: Slot::Normal,
    summary: "JKR adhesive normal force (EDEM Hertz-Mindlin with JKR)",
    params: &[SURFACE_ENERGY],
    history: HISTORY,
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Normal(Jkr::new(input.e_eff, input.params.get(&SURFACE_ENERGY)).into())
}

pub struct Jkr {
    e_eff: f64,
    gamma: f64,
    /// c = sqrt(4 pi gamma / E*), m^(1/2).
    c: f64,
    /// 4 sqrt(pi gamma E*).
    adhesion: f64,
}

impl Jkr {
    pub fn new(e_eff: f64, gamma: f64) -> Jkr {
        Jkr { e_eff, gamma, c: (4.0 * PI * gamma / e_eff).sqrt(), adhesion: 4.0 * (PI * gamma * e_eff).sqrt() }
    }

    /// F(a) = 4 E* a^3 / (3 R*) - 4 sqrt(pi gamma E*) a^(3/2), N.
    pub fn force_at_radius(&self, a: f64, r_eff: f64) -> f64 {
        4.0 * self.e_eff * a.powi(3) / (3.0 * r_eff) - self.adhesion * a.powf(1.5)
    }

    /// delta(a) = a^2/R* - sqrt(4 pi gamma a / E*), m.
    pub fn overlap_at_radius(&self, a: f64, r_eff: f64) -> f64 {
        a * a / r_eff - self.c * a.sqrt()
    }

    /// The pull-off force F_po = 3 pi gamma R* (N): minus the least force on the curve.
    pub fn pulloff_force(&self, r_eff: f64) -> f64 {
        3.0 * PI * self.gamma * r_eff
    }

    /// [`Jkr::pulloff_force`] lane by lane.
    #[inline(always)]
    pub fn pulloff_force_lanes(&self, r_eff: F) -> F {
        (3.0 * PI * self.gamma) * r_eff
    }

    /// The overlap of the force minimum F_min = -3 pi gamma R* (m, <= 0) for contact radius
    /// R*: delta(a_m), a_m = [9 pi gamma R*^2 / (4 E*)]^(1/3), where `jkr_lammps` breaks.
    pub fn pulloff_overlap(&self, r_eff: f64) -> f64 {
        let a_m = (9.0 * PI * self.gamma * r_eff * r_eff / (4.0 * self.e_eff)).cbrt();
        self.overlap_at_radius(a_m, r_eff)
    }

    /// The breaking overlap delta_c (m, <= 0) for contact radius R*.
    pub fn critical_overlap(&self, r_eff: f64) -> f64 {
        let a_c = (9.0 * PI * self.gamma * r_eff * r_eff / (2.0 * self.e_eff) * (0.75 - 0.5f64.sqrt())).cbrt();
        self.overlap_at_radius(a_c, r_eff)
    }

    /// Contact radius a (m) on the stable branch for overlap `delta` >= delta_c, starting
    /// Newton's method from `s_guess` = sqrt(a) when it is usable.
    pub fn contact_radius(&self, delta: f64, r_eff: f64, s_guess: f64) -> f64 {
        let s = self.sqrt_contact_radius(delta, r_eff, s_guess);
        s * s
    }

    /// s = sqrt(a), m^(1/2): what Newton's method solves for, and all the force needs
    /// (a = s^2, a^(3/2) = s^3, no square root).
    #[inline]
    pub fn sqrt_contact_radius(&self, delta: f64, r_eff: f64, s_guess: f64) -> f64 {
        let cr = self.c * r_eff;
        let dr = delta * r_eff;
        // f'(s) = 4 s^3 - cR > 0 is required for a monotone descent from the right.
        let mut s = if s_guess > 0.0 && 4.0 * s_guess.powi(3) > cr * 1.5 {
            s_guess
        } else {
            // f(s0) >= 0 for s0 = (cR)^(1/3) + (|delta| R)^(1/4).
            cr.cbrt() + dr.abs().sqrt().sqrt()
        };
        for _ in 0..60 {
            let s3 = s * s * s;
            let f = s3 * s - cr * s - dr;
            let fp = 4.0 * s3 - cr;
            if fp <= 0.0 {
                break;
            }
            let step = f / fp;
            s -= step;
            // Quadratic convergence: after a step of relative size 1e-8 the error left is
            // of order 1e-16, at the limit of f64.
            if step.abs() <= 1e-8 * s {
                break;
            }
        }
        s
    }
}

impl NormalLaw for Jkr {
    #[inline]
    fn force(&self, c: &Contact, history: &mut [f64]) -> NormalForce {
        self.force_breaking_at(c, history, |r| self.critical_overlap(r))
    }

    fn reach(&self, r_eff: f64) -> f64 {
        -self.critical_overlap(r_eff)
    }

    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> NormalForceLanes {
        self.force_lanes_with(c, history, |c, h| self.force(c, h))
    }
}

impl Jkr {
    /// The force of a contact whose neck breaks at the overlap `break_overlap(R*)` (m, <= 0),
    /// asked only in tension: `jkr` passes delta_c, `jkr_lammps` the overlap of the force
    /// minimum.
    #[inline]
    pub fn force_breaking_at(
        &self,
        c: &Contact,
        history: &mut [f64],
        break_overlap: impl Fn(f64) -> f64,
    ) -> NormalForce {
        // In tension the JKR neck exists only if it never broke: it forms on touching
        // (history set) and breaks for good at `break_overlap` (history cleared). Another
        // law with a longer reach (a liquid bridge) can keep the pair in contact beyond it,
        // where the stable branch may no longer exist.
        if c.overlap <= 0.0 && (self.gamma == 0.0 || history[0] == 0.0 || c.overlap <= break_overlap(c.r_eff)) {
            history[0] = 0.0;
            return NormalForce::default();
        }
        let s = self.sqrt_contact_radius(c.overlap, c.r_eff, history[0]);
        history[0] = s;
        let a = s * s;
        // 4 E* a^3 / (3 R*) without the division: on the curve a^2 / R* = delta + c sqrt(a).
        let hertz = 4.0 / 3.0 * self.e_eff * a * (c.overlap + self.c * s);
        NormalForce {
            elastic: hertz - self.adhesion * a * s,
            stiffness: 2.0 * self.e_eff * a,
            friction_load: hertz,
            contact_radius: a,
        }
    }

    /// The lanes' forces: lanes with a negative overlap (a neck in tension, or none) go
    /// through `one` (the law's own `force`) lane by lane; the pair phase gives touching
    /// contacts only, whose force does not depend on where the neck breaks.
    #[inline(always)]
    pub fn force_lanes_with(
        &self,
        c: &ContactLanes,
        history: &mut [F],
        one: impl Fn(&Contact, &mut [f64]) -> NormalForce,
    ) -> NormalForceLanes {
        let live = M(std::array::from_fn(|k| k < c.count));
        if (c.overlap.le(F::ZERO) & live).any() {
            let mut out = NormalForceLanes::ZERO;
            for k in 0..c.count {
                out.set_lane(k, with_lane_history(history, k, |h| one(&c.lane(k), h)));
            }
            return out;
        }
        let s = self.sqrt_contact_radius_lanes(c.overlap, c.r_eff, history[0]);
        history[0] = s;
        let a = s * s;
        let hertz = 4.0 / 3.0 * self.e_eff * a * (c.overlap + self.c * s);
        NormalForceLanes {
            elastic: hertz - self.adhesion * a * s,
            stiffness: 2.0 * self.e_eff * a,
            friction_load: hertz,
            contact_radius: a,
        }
    }
    /// [`Jkr::sqrt_contact_radius`] lane by lane: each lane takes the Newton steps it would
    /// take alone, and keeps its value once it stops.
    #[inline(always)]
    fn sqrt_contact_radius_lanes(&self, delta: F, r_eff: F, s_guess: F) -> F {
        let cr = self.c * r_eff;
        let dr = delta * r_eff;
        let mut s = s_guess;
        for k in 0..LANES {
            let g = s_guess.0[k];
            if !(g > 0.0 && 4.0 * g.powi(3) > cr.0[k] * 1.5) {
                s.0[k] = cr.0[k].cbrt() + dr.0[k].abs().sqrt().sqrt();
            }
        }
        let mut going = M::splat(true);
        for _ in 0..60 {
            let s3 = s * s * s;
            let f = s3 * s - cr * s - dr;
            let fp = 4.0 * s3 - cr;
            going = going & !fp.le(F::ZERO);
            let step = f / fp;
            let next = s - step;
            s = F::select(going, next, s);
            going = going & !step.abs().le(1e-8 * next);
            if !going.any() {
                break;
            }
        }
        s
    }
}
