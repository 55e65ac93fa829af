//! The law sets the pair phase compiles as kernels of their own, as LIGGGHTS compiles a
//! pair style per contact-model combination (its `style_contact_model.h`).
//!
//! A model whose laws are one of these sets ([`ContactModel::typed_laws`]) runs its touching
//! pairs through [`TypedModel`]: the lane pipeline compiled for those law types. Any other
//! model runs them through the slots' enums (`LaneLaws` for `ContactModel`), the same
//! pipeline compiled once for every law. Both give the same bits (the same lane forms, in the
//! same order); a set here only makes it faster: 15-18 % off the settling bed's pair phase
//! on AVX2. A new law needs no line here; a law set in
//! common use may get one.
//!
//! An empty slot in a model matches any law of a set's slot, and a model without extras
//! matches any set's extra; a model with more than one extra law takes the enums.

use super::Ctx;
use super::PairPath;
use crate::contact::dispatch::OfAny;
use crate::contact::laws::{
    cdt::Cdt, epsd::Epsd, hertz::Hertz, jkr::Jkr, jkr_lammps::JkrLammps, mindlin::Mindlin,
    restitution::Restitution, sjkr::Sjkr,
};
use crate::contact::model::TypedModel;
use crate::contact::{AnyExtra, Contact, ContactModel, ExtraLaw};
use crate::neighbor::schedule::Block;
use glam::DVec3;

/// The extra slot of a set without extra laws: no value exists, so a model with an extra
/// law never matches it.
pub(super) enum NoExtra {}

impl ExtraLaw for NoExtra {
    fn force(&self, _c: &Contact, _history: &mut [f64]) -> f64 {
        match *self {}
    }
}

impl OfAny<AnyExtra> for NoExtra {
    fn of_any(_any: &AnyExtra) -> Option<&Self> {
        None
    }
}

/// `compiled_sets! { Name(normal, damping, tangential, rolling, extra), ... }`: the enum of
/// the sets, how a model finds its own (the first that matches), and the pair phase's
/// dispatch on it.
macro_rules! compiled_sets {
    ($($(#[$doc:meta])* $name:ident($n:ty, $d:ty, $t:ty, $r:ty, $x:ty),)*) => {
        /// A model's laws as one of the compiled sets.
        pub(super) enum CompiledLaws<'a> {
            $($(#[$doc])* $name(TypedModel<'a, $n, $d, $t, $r, $x>),)*
        }

        impl<'a> CompiledLaws<'a> {
            /// The first set `model`'s laws match, if any.
            pub(super) fn of(model: &'a ContactModel) -> Option<CompiledLaws<'a>> {
                $(
                    if let Some(t) = model.typed_laws::<$n, $d, $t, $r, $x>() {
                        return Some(CompiledLaws::$name(t));
                    }
                )*
                None
            }
        }

        impl Ctx<'_> {
            /// One block's pairs through the lanes, by the model's compiled law set if it
            /// has one (and `path` is not [`PairPath::LanesEnums`]).
            pub(super) fn block_lanes(
                &self,
                path: PairPath,
                block: &Block,
                history: &mut [f64],
                force: &mut [DVec3],
                torque: &mut [DVec3],
            ) -> usize {
                match &self.compiled {
                    $(
                        Some(CompiledLaws::$name(laws)) => {
                            self.block_lanes_by(laws, path, block, history, force, torque)
                        }
                    )*
                    None => self.block_lanes_by(self.model, path, block, history, force, torque),
                }
            }
        }
    };
}

compiled_sets! {
    /// Hertz-Mindlin with constant-torque rolling resistance, and LIGGGHTS's simplified JKR
    /// or no cohesion: the settling bed with `--cohesion sjkr`, the decks' own laws.
    HertzMindlinCdt(Hertz, Restitution, Mindlin, Cdt, Sjkr),
    /// Hertz-Mindlin with JKR and constant-torque rolling resistance: the settling bed's
    /// default (`--cohesion jkr`), EDEM's "Hertz-Mindlin with JKR".
    JkrMindlinCdt(Jkr, Restitution, Mindlin, Cdt, NoExtra),
    /// The same with EPSD rolling resistance: the study's model (`models/li2022.toml`)
    /// until its bonds form.
    JkrMindlinEpsd(Jkr, Restitution, Mindlin, Epsd, NoExtra),
    /// The study's model with LAMMPS's JKR (`jkr_lammps`).
    JkrLammpsMindlinEpsd(JkrLammps, Restitution, Mindlin, Epsd, NoExtra),
}

#[cfg(test)]
mod tests {
    use super::CompiledLaws;
    use crate::contact::{ContactModel, ModelSpec, PairSpec};
    use crate::material::Material;

    /// A one-material model of these laws with every coefficient they need.
    fn model(normal: &str, rolling: Option<&str>, extra: &[&str]) -> ContactModel {
        let spec = ModelSpec {
            normal: normal.into(),
            damping: Some("restitution".into()),
            tangential: Some("mindlin".into()),
            rolling: rolling.map(Into::into),
            extra: extra.iter().map(|x| x.to_string()).collect(),
        };
        let params = [
            ("restitution", 0.45),
            ("friction", 0.6),
            ("rolling_friction", 0.15),
            ("surface_energy", 0.356),
            ("cohesion_energy_density", 0.356),
            ("twisting_friction", 0.1),
            ("twisting_damping", 0.1),
        ];
        let keys: Vec<&str> = spec
            .extra
            .iter()
            .map(String::as_str)
            .chain([normal, "restitution", "mindlin"])
            .chain(rolling)
            .collect();
        let needed = |k: &str| match k {
            "surface_energy" => keys.contains(&"jkr") || keys.contains(&"jkr_lammps"),
            "cohesion_energy_density" => keys.contains(&"sjkr"),
            "twisting_friction" | "twisting_damping" => keys.contains(&"twisting"),
            "rolling_friction" => rolling.is_some(),
            _ => true,
        };
        let soil = Material::new("soil", 5e6, 0.3, 2600.0).unwrap();
        ContactModel::build(
            &[soil],
            &spec,
            &[PairSpec {
                materials: ("soil".into(), "soil".into()),
                params: params
                    .iter()
                    .filter(|(k, _)| needed(k))
                    .map(|&(k, v)| (k.to_string(), v))
                    .collect(),
            }],
        )
        .unwrap()
    }

    fn set_of(m: &ContactModel) -> &'static str {
        match CompiledLaws::of(m) {
            Some(CompiledLaws::HertzMindlinCdt(_)) => "HertzMindlinCdt",
            Some(CompiledLaws::JkrMindlinCdt(_)) => "JkrMindlinCdt",
            Some(CompiledLaws::JkrMindlinEpsd(_)) => "JkrMindlinEpsd",
            Some(CompiledLaws::JkrLammpsMindlinEpsd(_)) => "JkrLammpsMindlinEpsd",
            None => "enums",
        }
    }

    #[test]
    fn each_model_finds_its_compiled_set_or_takes_the_enums() {
        // The settling bed with either cohesion, the study's laws, and models with an empty
        // slot or no extra, which any set with that slot's law takes.
        assert_eq!(
            set_of(&model("hertz", Some("cdt"), &["sjkr"])),
            "HertzMindlinCdt"
        );
        assert_eq!(set_of(&model("hertz", Some("cdt"), &[])), "HertzMindlinCdt");
        assert_eq!(set_of(&model("hertz", None, &[])), "HertzMindlinCdt");
        assert_eq!(set_of(&model("jkr", Some("cdt"), &[])), "JkrMindlinCdt");
        assert_eq!(set_of(&model("jkr", None, &[])), "JkrMindlinCdt");
        assert_eq!(set_of(&model("jkr", Some("epsd"), &[])), "JkrMindlinEpsd");
        assert_eq!(
            set_of(&model("jkr_lammps", Some("epsd"), &[])),
            "JkrLammpsMindlinEpsd"
        );
        // No set: a law outside every set, an extra the set has not, two extras.
        assert_eq!(set_of(&model("hertz", Some("epsd"), &[])), "enums");
        assert_eq!(set_of(&model("jkr", Some("cdt"), &["sjkr"])), "enums");
        assert_eq!(
            set_of(&model("hertz", Some("cdt"), &["sjkr", "twisting"])),
            "enums"
        );
    }
}
