//! The law registry: one line per law. The file `NAME.rs` beside this one holds the law, a
//! type `Type`, and its [`LawEntry`] named `ENTRY`; the line `NAME: Type,` under the law's
//! slot below declares the module, registers the entry and lets the pipeline call `Type`
//! without `dyn` (see `contact/dispatch.rs`). See `kernel/ADDING_A_LAW.md`.

use super::{
    BondLaw, BondLoads, Contact, ContactLanes, ContactOut, DampingLaw, ExtraLaw, F, LawEntry,
    NormalForce, NormalForceLanes, NormalLaw, RollingLaw, TangentialLaw, V,
};
use glam::DVec3;

/// `module: Type,` per law, grouped by slot. Each line declares the module, lists its
/// `ENTRY` in [`REGISTRY`] and adds `Type` as a variant of its slot's enum.
macro_rules! registry {
    (
        normal { $($n:ident: $nt:ident,)* }
        damping { $($d:ident: $dt:ident,)* }
        tangential { $($t:ident: $tt:ident,)* }
        rolling { $($r:ident: $rt:ident,)* }
        extra { $($x:ident: $xt:ident,)* }
        bond { $($b:ident: $bt:ident,)* }
    ) => {
        $(pub mod $n;)* $(pub mod $d;)* $(pub mod $t;)* $(pub mod $r;)* $(pub mod $x;)* $(pub mod $b;)*

        /// Every law the model builder knows, grouped by slot.
        pub static REGISTRY: &[&LawEntry] = &[
            $(&$n::ENTRY,)* $(&$d::ENTRY,)* $(&$t::ENTRY,)* $(&$r::ENTRY,)* $(&$x::ENTRY,)* $(&$b::ENTRY,)*
        ];

        // Each list below names every method of its trait (see `contact/dispatch.rs`).
        law_enum!(
            /// Any registered normal law.
            AnyNormal: NormalLaw [$($nt($n::$nt))*] {
                fn force(&self, c: &Contact, history: &mut [f64]) -> NormalForce;
                fn reach(&self, r_eff: f64) -> f64;
                fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> NormalForceLanes;
            }
        );
        law_enum!(
            /// Any registered damping law.
            AnyDamping: DampingLaw [$($dt($d::$dt))*] {
                fn coefficient(&self, stiffness: f64, m_eff: f64) -> f64;
                fn coefficient_lanes(&self, stiffness: F, m_eff: F) -> F;
            }
        );
        law_enum!(
            /// Any registered tangential law.
            AnyTangential: TangentialLaw [$($tt($t::$tt))*] {
                fn stiffness(&self, c: &Contact, normal: &NormalForce) -> f64;
                fn force(
                    &self,
                    c: &Contact,
                    coulomb_load: f64,
                    stiffness: f64,
                    damping: f64,
                    history: &mut [f64]
                ) -> DVec3;
                fn stiffness_lanes(&self, c: &ContactLanes, normal: &NormalForceLanes) -> F;
                fn force_lanes(
                    &self,
                    c: &ContactLanes,
                    coulomb_load: F,
                    stiffness: F,
                    damping: F,
                    history: &mut [F]
                ) -> V;
            }
        );
        law_enum!(
            /// Any registered rolling law.
            AnyRolling: RollingLaw [$($rt($r::$rt))*] {
                fn torques(
                    &self,
                    c: &Contact,
                    normal: &NormalForce,
                    coulomb_load: f64,
                    history: &mut [f64]
                ) -> (DVec3, DVec3);

                fn torques_lanes(
                    &self,
                    c: &ContactLanes,
                    normal: &NormalForceLanes,
                    coulomb_load: F,
                    history: &mut [F]
                ) -> (V, V);
            }
        );
        law_enum!(
            /// Any registered extra law.
            AnyExtra: ExtraLaw [$($xt($x::$xt))*] {
                fn force(&self, c: &Contact, history: &mut [f64]) -> f64;
                fn torques(
                    &self,
                    c: &Contact,
                    normal: &NormalForce,
                    coulomb_load: f64,
                    history: &mut [f64]
                ) -> (DVec3, DVec3);
                fn reach(&self, r_eff: f64) -> f64;
                fn reach_between(&self, c: &Contact) -> f64;
                fn force_lanes(&self, c: &ContactLanes, history: &mut [F]) -> F;
                fn torques_lanes(
                    &self,
                    c: &ContactLanes,
                    normal: &NormalForceLanes,
                    coulomb_load: F,
                    history: &mut [F]
                ) -> (V, V);
            }
        );
        law_enum!(
            /// Any registered bond law.
            AnyBond: BondLaw [$($bt($b::$bt))*] {
                fn contact_ratio(&self) -> f64;
                fn reach(&self, r_max: f64) -> f64;
                fn force(&self, c: &Contact, history: &mut [f64]) -> Option<ContactOut>;
                fn loads(&self, history: &[f64]) -> BondLoads;
                fn time_scale(&self, mass: f64, r_i: f64, r_j: f64) -> f64;
            }
        );
    };
}

registry! {
    normal {
        hertz: Hertz,
        jkr: Jkr,
        jkr_lammps: JkrLammps,
    }
    damping {
        restitution: Restitution,
    }
    tangential {
        mindlin: Mindlin,
        mindlin_incremental: MindlinIncremental,
        coulomb_viscous: CoulombViscous,
    }
    rolling {
        cdt: Cdt,
        epsd: Epsd,
    }
    extra {
        capillary: Capillary,
        capillary_moisture: CapillaryMoisture,
        twisting: Twisting,
        plastic_adhesion: PlasticAdhesion,
        sjkr: Sjkr,
    }
    bond {
        bond: Bond,
    }
}

#[cfg(test)]
mod tests {
    use super::REGISTRY;

    #[test]
    fn names_are_unique_within_a_slot() {
        for (i, a) in REGISTRY.iter().enumerate() {
            for b in &REGISTRY[i + 1..] {
                assert!(
                    !(a.name == b.name && a.slot == b.slot),
                    "duplicate law {}",
                    a.name
                );
            }
        }
    }
}
