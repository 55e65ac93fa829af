//! Contact laws as slots.
//!
//! A contact is evaluated by a fixed pipeline, as in LAMMPS's granular sub-models:
//!
//! 1. **normal**: elastic normal force and stiffness from the overlap (`hertz`, `jkr`);
//! 2. **damping**: a viscous coefficient from a stiffness (`restitution`), applied to the
//!    normal and the tangential relative velocities;
//! 3. **tangential**: friction with history and a Coulomb cap (`mindlin`, ...);
//! 4. **rolling**: rolling-resistance torques (`cdt`, `epsd`);
//! 5. **extras**: any number of additive effects: normal forces, which may act across a
//!    gap (`capillary`), or torques (`twisting`);
//! 6. **bond**: at most one bond law (`bond`, a parallel bond), acting on top of the
//!    contact laws between particle pairs bonded by [`crate::sim::Simulation::form_bonds`],
//!    also across a gap, until the bond breaks. A scene names it among the extras
//!    (`extra = ["bond"]`); the builder puts it in its own slot.
//!
//! Laws never call each other; the pipeline hands each the outputs it needs. Each law is one
//! file in [`laws`] and one line in its registry. Compatibility is checked once, in
//! [`ContactModel::build`], never inside the time step.
//!
//! The pair phase runs the pipeline on [`LANES`] touching contacts at once
//! ([`LaneLaws::evaluate_lanes`]): each slot's trait has a lane form beside its scalar
//! one, which must give the scalar form's bits lane by lane, and which by default runs the
//! scalar form on each lane (see [`lanes`] and `kernel/ADDING_A_LAW.md`); wall contacts too.
//! Contacts that may end run the scalar pipeline, and so do bonds: once bonds are formed,
//! a simulation runs its pairs one at a time.
//!
//! Sign conventions: the unit normal `n` points from particle i to particle j (or the wall);
//! the overlap `delta_n > 0` in contact; normal forces returned by laws are positive when
//! repulsive; vectors returned are forces and torques *on i* unless stated.

pub mod contact_lanes;
pub mod geometry;
#[macro_use]
pub(crate) mod dispatch;
pub mod lanes;
pub mod laws;
pub mod model;

pub use contact_lanes::{ContactLanes, NormalForceLanes, torques_by_lane, with_lane_history};
pub use geometry::Contact;
pub use lanes::{F, LANES, M, V};
pub use laws::{AnyBond, AnyDamping, AnyExtra, AnyNormal, AnyRolling, AnyTangential};
pub use model::{
    BondStatus, ContactModel, ContactOut, ContactOutLanes, LaneLaws, ModelSpec, PairSpec,
};

use crate::material::Material;
use crate::param::{ParamSpec, Params};
use glam::DVec3;

/// Output of a normal law.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NormalForce {
    /// Elastic (and adhesive) normal force, N; positive pushes the particles apart.
    pub elastic: f64,
    /// Normal contact stiffness dF/d(delta), N/m, used by damping and rolling laws.
    pub stiffness: f64,
    /// The repulsive part that loads friction (EDEM: the Hertz part of JKR), N.
    pub friction_load: f64,
    /// Radius of the contact area, m (sqrt(R* delta) for Hertz).
    pub contact_radius: f64,
}

/// Slot 1: the elastic normal force.
///
/// Every method is forwarded by the registry's enum: a new method goes into its list in
/// `laws/mod.rs` too.
pub trait NormalLaw: Send + Sync {
    fn force(&self, c: &Contact, history: &mut [f64]) -> NormalForce;
    /// How far beyond touching (m, >= 0) an established contact keeps acting, for contact
    /// radius `r_eff`. Neighbour lists keep such pairs.
    fn reach(&self, _r_eff: f64) -> f64 {
        0.0
    }
    /// [`NormalLaw::force`] on [`LANES`] contacts at once (see `lanes.rs`): it must give
    /// `force`'s bits in every lane (`tests/tests/lanes.rs` checks each law). The default
    /// runs `force` lane by lane; a law overrides it for speed.
    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> NormalForceLanes {
        let mut out = NormalForceLanes::ZERO;
        for k in 0..c.count {
            out.set_lane(
                k,
                with_lane_history(history, k, |h| self.force(&c.lane(k), h)),
            );
        }
        out
    }
}

/// Slot 2: a viscous damping coefficient (N s/m) for a spring of `stiffness` acting on `m_eff`.
///
/// Every method is forwarded by the registry's enum: a new method goes into its list in
/// `laws/mod.rs` too.
pub trait DampingLaw: Send + Sync {
    fn coefficient(&self, stiffness: f64, m_eff: f64) -> f64;
    /// [`DampingLaw::coefficient`] lane by lane, with its bits (see
    /// [`NormalLaw::force_lanes`]).
    #[inline(always)]
    fn coefficient_lanes(&self, stiffness: F, m_eff: F) -> F {
        let mut out = F::ZERO;
        for k in 0..LANES {
            out.0[k] = self.coefficient(stiffness.0[k], m_eff.0[k]);
        }
        out
    }
}

/// Slot 3: tangential (friction) force.
///
/// Every method is forwarded by the registry's enum: a new method goes into its list in
/// `laws/mod.rs` too.
pub trait TangentialLaw: Send + Sync {
    /// Current tangential stiffness (N/m); the pipeline turns it into a damping coefficient.
    fn stiffness(&self, c: &Contact, normal: &NormalForce) -> f64;
    /// Tangential force on i. `coulomb_load` is |friction load + normal damping| (N),
    /// `damping` the tangential damping coefficient (N s/m).
    fn force(
        &self,
        c: &Contact,
        coulomb_load: f64,
        stiffness: f64,
        damping: f64,
        history: &mut [f64],
    ) -> DVec3;
    /// [`TangentialLaw::stiffness`] lane by lane, with its bits (see
    /// [`NormalLaw::force_lanes`]).
    #[inline(always)]
    fn stiffness_lanes(&self, c: &ContactLanes, normal: &NormalForceLanes) -> F {
        let mut out = F::ZERO;
        for k in 0..c.count {
            out.0[k] = self.stiffness(&c.lane(k), &normal.lane(k));
        }
        out
    }
    /// [`TangentialLaw::force`] lane by lane, with its bits (see
    /// [`NormalLaw::force_lanes`]).
    #[inline(always)]
    fn force_lanes(
        &self,
        c: &ContactLanes,
        coulomb_load: F,
        stiffness: F,
        damping: F,
        history: &mut [F],
    ) -> V {
        let mut out = V::ZERO;
        for k in 0..c.count {
            let (load, s, eta) = (coulomb_load.0[k], stiffness.0[k], damping.0[k]);
            let f = with_lane_history(history, k, |h| self.force(&c.lane(k), load, s, eta, h));
            out.set_lane(k, f);
        }
        out
    }
}

/// Slot 4: rolling resistance. Returns the torques on i and on j (N m).
///
/// Every method is forwarded by the registry's enum: a new method goes into its list in
/// `laws/mod.rs` too.
pub trait RollingLaw: Send + Sync {
    fn torques(
        &self,
        c: &Contact,
        normal: &NormalForce,
        coulomb_load: f64,
        history: &mut [f64],
    ) -> (DVec3, DVec3);
    /// [`RollingLaw::torques`] lane by lane, with its bits (see
    /// [`NormalLaw::force_lanes`]).
    #[inline(always)]
    fn torques_lanes(
        &self,
        c: &ContactLanes,
        normal: &NormalForceLanes,
        coulomb_load: F,
        history: &mut [F],
    ) -> (V, V) {
        torques_by_lane(c, normal, coulomb_load, history, |c, n, load, h| {
            self.torques(c, n, load, h)
        })
    }
}

/// Slot 5: an additive effect: a normal force (N, positive repulsive), possibly acting
/// across a gap, and/or torques on the two particles.
///
/// Every method is forwarded by the registry's enum: a new method goes into its list in
/// `laws/mod.rs` too.
pub trait ExtraLaw: Send + Sync {
    fn force(&self, c: &Contact, history: &mut [f64]) -> f64;
    /// Torques on i and on j (N m), given the normal law's output and the Coulomb load (N).
    /// Most extras act along the normal only.
    fn torques(
        &self,
        _c: &Contact,
        _normal: &NormalForce,
        _coulomb_load: f64,
        _history: &mut [f64],
    ) -> (DVec3, DVec3) {
        (DVec3::ZERO, DVec3::ZERO)
    }
    /// How far beyond touching (m, >= 0) the effect acts for contact radius `r_eff`. The
    /// neighbour list asks it with the largest particle radius, so it must bound the reach
    /// of every contact of particles up to that radius.
    fn reach(&self, _r_eff: f64) -> f64 {
        0.0
    }
    /// How far beyond touching (m, >= 0) the effect acts for this contact; the pipeline ends
    /// an established contact past it. Override it when the reach depends on more than R*
    /// (a bridge whose volume comes from the grains' masses).
    fn reach_between(&self, c: &Contact) -> f64 {
        self.reach(c.r_eff)
    }
    /// [`ExtraLaw::force`] lane by lane, with its bits (see [`NormalLaw::force_lanes`]).
    /// The pipeline calls it, then `torques_lanes`, as it calls `force`, then `torques`.
    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> F {
        let mut out = F::ZERO;
        for k in 0..c.count {
            out.0[k] = with_lane_history(history, k, |h| self.force(&c.lane(k), h));
        }
        out
    }
    /// [`ExtraLaw::torques`] lane by lane, with its bits (see [`NormalLaw::force_lanes`]).
    #[inline(always)]
    fn torques_lanes(
        &self,
        c: &ContactLanes,
        normal: &NormalForceLanes,
        coulomb_load: F,
        history: &mut [F],
    ) -> (V, V) {
        torques_by_lane(c, normal, coulomb_load, history, |c, n, load, h| {
            self.torques(c, n, load, h)
        })
    }
}

/// The loads an intact bond carries (zero once broken). Sign conventions: `normal_force`
/// is positive in compression (pushing the particles apart, like every normal force here)
/// and negative in tension; the vectors are the force and moments acting *on particle i*
/// (j gets the opposite), with `normal_moment` the twisting moment about the unit normal
/// n (from i to j), i.e. the moment vector `normal_moment * n`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BondLoads {
    /// N, positive in compression.
    pub normal_force: f64,
    /// Shear force on i, in the plane normal to n, N.
    pub shear_force: DVec3,
    /// Twisting moment on i about n, N m.
    pub normal_moment: f64,
    /// Bending moment on i, in the plane normal to n, N m.
    pub shear_moment: DVec3,
}

/// One bond, for output: the stable particle ids (`i < j`), its loads and, once broken,
/// the simulation time at which it broke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondState {
    pub i: u32,
    pub j: u32,
    /// The loads on i (see [`BondLoads`] for the signs); zero for a broken bond.
    pub loads: BondLoads,
    /// `None` while intact; the time (s) of the step in which it broke.
    pub broken_time: Option<f64>,
}

impl BondState {
    pub fn intact(&self) -> bool {
        self.broken_time.is_none()
    }
}

/// Slot 6: a bond between two particles, formed on request
/// ([`crate::sim::Simulation::form_bonds`]) and acting on top of the contact laws, also
/// across a gap, until it breaks. The pipeline owns the bond's status (none, intact,
/// broken) and its breaking time; the law keeps its loads in its history.
///
/// Every method is forwarded by the registry's enum: a new method goes into its list in
/// `laws/mod.rs` too.
pub trait BondLaw: Send + Sync {
    /// Pairs whose centres are closer than `contact_ratio * (r_i + r_j)` bond when bonds are
    /// formed.
    fn contact_ratio(&self) -> f64;
    /// How far beyond touching (m, >= 0) an intact bond between particles of radius up to
    /// `r_max` can be stretched before it must have broken. Neighbour lists keep such pairs.
    fn reach(&self, r_max: f64) -> f64;
    /// Advances an intact bond by one step: updates its loads in `history` and returns the
    /// force on i and the torques on i and j, or `None` when the bond breaks in this step
    /// (the pipeline then marks it broken, records the time and zeroes the history).
    fn force(&self, c: &Contact, history: &mut [f64]) -> Option<ContactOut>;
    /// The loads kept in `history`.
    fn loads(&self, history: &[f64]) -> BondLoads;
    /// The oscillation time scale (s) of a bond between particles of radius `r_i`, `r_j`,
    /// the lighter of mass `mass` (kg): sqrt(m / k) with k the bond's stiffest spring. The
    /// Rayleigh step does not see it; `Simulation::form_bonds` warns when the step is too
    /// long for it.
    fn time_scale(&self, mass: f64, r_i: f64, r_j: f64) -> f64;
}

/// Which slot a law fills.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    Normal,
    Damping,
    Tangential,
    Rolling,
    Extra,
    Bond,
}

impl Slot {
    pub fn name(self) -> &'static str {
        match self {
            Slot::Normal => "normal",
            Slot::Damping => "damping",
            Slot::Tangential => "tangential",
            Slot::Rolling => "rolling",
            Slot::Extra => "extra",
            Slot::Bond => "bond",
        }
    }
}

/// A constructed law for one material pair. A law's `build` wraps itself with `.into()`:
/// `BuiltLaw::Normal(Hertz { .. }.into())`.
pub enum BuiltLaw {
    Normal(AnyNormal),
    Damping(AnyDamping),
    Tangential(AnyTangential),
    Rolling(AnyRolling),
    Extra(AnyExtra),
    Bond(AnyBond),
}

/// What a law's constructor gets: the two materials, their effective moduli and the
/// validated pair parameters.
pub struct LawInput<'a> {
    pub material_i: &'a Material,
    pub material_j: &'a Material,
    /// E*, Pa.
    pub e_eff: f64,
    /// G*, Pa.
    pub g_eff: f64,
    pub params: Params<'a>,
}

/// A registry row: everything the builder needs to know about a law without running it.
pub struct LawEntry {
    pub name: &'static str,
    pub slot: Slot,
    pub summary: &'static str,
    /// Per-pair parameters (e.g. `restitution`), with units and ranges.
    pub params: &'static [ParamSpec],
    /// Names of the per-contact history values (f64) the law keeps.
    pub history: &'static [&'static str],
    /// The law pulls particles together (an adhesive normal law or extra force).
    pub cohesive: bool,
    /// A tangential or rolling law that stays correct when the normal force is adhesive.
    pub allows_cohesion: bool,
    pub build: fn(&LawInput) -> BuiltLaw,
}
