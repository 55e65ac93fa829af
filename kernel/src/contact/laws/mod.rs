//! The law registry: one line per law. The file `NAME.rs` beside this one holds the law and
//! its [`LawEntry`] named `ENTRY`; listing `NAME` below declares the module and registers it.
//! See `kernel/ADDING_A_LAW.md`.

use super::LawEntry;

macro_rules! registry {
    ($($law:ident),* $(,)?) => {
        $(pub mod $law;)*
        /// Every law the model builder knows, in no particular order.
        pub static REGISTRY: &[&LawEntry] = &[$(&$law::ENTRY),*];
    };
}

registry! {
    hertz,
    jkr,
    restitution,
    mindlin,
    mindlin_incremental,
    coulomb_viscous,
    cdt,
    epsd,
    capillary,
    capillary_moisture,
    twisting,
    plastic_adhesion,
    sjkr,
    bond,
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
