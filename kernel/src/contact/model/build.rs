//! Building a contact model: the laws named for each slot looked up in the registry and
//! checked as a set, the history layout they share, and every material pair's coefficients
//! checked and its laws constructed.

use super::{BOND_HEAD, ContactModel, HistoryLayout, ModelSpec, PairLaws, PairSpec};
use crate::contact::laws::REGISTRY;
use crate::contact::{BuiltLaw, LawEntry, LawInput, Slot};
use crate::error::{KernelError, Result};
use crate::material::{Material, effective_shear, effective_youngs};
use crate::param::{self, Params};

/// The registry entries of a model's laws: normal first, then damping, tangential, rolling
/// and the extras in their listed order (the bond law among them); and, of these, the
/// tangential, rolling and bond entries on their own.
struct LawSet {
    entries: Vec<&'static LawEntry>,
    tangential: Option<&'static LawEntry>,
    rolling: Option<&'static LawEntry>,
    bond: Option<&'static LawEntry>,
}

fn lookup(slot: Slot, name: &str) -> Result<&'static LawEntry> {
    // The extras list also names the bond law.
    let fits = |e: &LawEntry| e.slot == slot || (slot == Slot::Extra && e.slot == Slot::Bond);
    REGISTRY
        .iter()
        .copied()
        .find(|e| fits(e) && e.name == name)
        .ok_or_else(|| {
            let known: Vec<&str> = REGISTRY
                .iter()
                .filter(|e| fits(e))
                .map(|e| e.name)
                .collect();
            KernelError::UnknownLaw {
                slot: slot.name().into(),
                name: name.into(),
                known: known.join(", "),
            }
        })
}

/// Constructs one pair's laws; the entries come normal first, as `build` orders them.
fn construct(entries: &[&'static LawEntry], input: &LawInput) -> PairLaws {
    let mut built = entries.iter().map(|e| (e.build)(input));
    let Some(BuiltLaw::Normal(normal)) = built.next() else {
        unreachable!("the first entry is the normal law")
    };
    let mut laws = PairLaws {
        normal,
        damping: None,
        tangential: None,
        rolling: None,
        extras: vec![],
        bond: None,
    };
    for b in built {
        match b {
            BuiltLaw::Damping(l) => laws.damping = Some(l),
            BuiltLaw::Tangential(l) => laws.tangential = Some(l),
            BuiltLaw::Rolling(l) => laws.rolling = Some(l),
            BuiltLaw::Extra(l) => laws.extras.push(l),
            BuiltLaw::Bond(l) => laws.bond = Some(l),
            BuiltLaw::Normal(_) => unreachable!("only one normal law"),
        }
    }
    laws
}

impl ContactModel {
    /// Checks the law set and every pair's coefficients, then constructs the laws.
    pub fn build(
        materials: &[Material],
        spec: &ModelSpec,
        pairs: &[PairSpec],
    ) -> Result<ContactModel> {
        for m in materials {
            m.validate()?;
        }
        let laws = law_set(spec)?;
        check_cohesion(&laws.entries)?;
        let layout = history_layout(&laws, spec);
        let table = pair_table(materials, pairs, &laws.entries)?;
        let entries = &laws.entries;
        let has_reach = entries.iter().any(|e| e.cohesive);
        Ok(ContactModel {
            materials: materials.to_vec(),
            pairs: table,
            layout,
            law_names: entries.iter().map(|e| e.name).collect(),
            has_reach,
        })
    }
}

/// Looks up the laws `spec` names, refusing an unknown name, an extra law listed twice
/// and more than one bond law.
fn law_set(spec: &ModelSpec) -> Result<LawSet> {
    let mut entries: Vec<&'static LawEntry> = vec![lookup(Slot::Normal, &spec.normal)?];
    if let Some(d) = &spec.damping {
        entries.push(lookup(Slot::Damping, d)?);
    }
    let tangential = spec
        .tangential
        .as_deref()
        .map(|t| lookup(Slot::Tangential, t))
        .transpose()?;
    let rolling = spec
        .rolling
        .as_deref()
        .map(|r| lookup(Slot::Rolling, r))
        .transpose()?;
    entries.extend(tangential);
    entries.extend(rolling);
    let mut bond: Option<&'static LawEntry> = None;
    for x in &spec.extra {
        let e = lookup(Slot::Extra, x)?;
        if entries.iter().any(|o| o.name == e.name) {
            return Err(KernelError::Invalid(format!(
                "extra law '{x}' is listed twice"
            )));
        }
        if e.slot == Slot::Bond {
            if let Some(b) = bond {
                return Err(KernelError::Invalid(format!(
                    "bond laws '{}' and '{x}' are both listed; a model takes at most one bond law",
                    b.name
                )));
            }
            bond = Some(e);
        }
        entries.push(e);
    }
    Ok(LawSet {
        entries,
        tangential,
        rolling,
        bond,
    })
}

/// Compatibility, once: an adhesive force needs friction and rolling laws that cap on the
/// repulsive load rather than on a possibly negative net normal force.
fn check_cohesion(entries: &[&'static LawEntry]) -> Result<()> {
    if let Some(cohesive) = entries.iter().find(|e| e.cohesive) {
        for e in entries
            .iter()
            .filter(|e| matches!(e.slot, Slot::Tangential | Slot::Rolling))
        {
            if !e.allows_cohesion {
                return Err(KernelError::Invalid(format!(
                    "{} law '{}' cannot be combined with the cohesive law '{}': it caps friction on the net normal force, which adhesion makes negative; choose a {} law that allows cohesion ({})",
                    e.slot.name(),
                    e.name,
                    cohesive.name,
                    e.slot.name(),
                    REGISTRY
                        .iter()
                        .filter(|o| o.slot == e.slot && o.allows_cohesion)
                        .map(|o| o.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
    }
    Ok(())
}

/// Where each law's history goes in a contact's row: the flag, then the normal,
/// tangential, rolling and extra laws' values, then the bond block.
fn history_layout(laws: &LawSet, spec: &ModelSpec) -> HistoryLayout {
    let (entries, tangential, rolling, bond) =
        (&laws.entries, laws.tangential, laws.rolling, laws.bond);
    let mut at = 1;
    let mut take = |n: usize| {
        let r = at..at + n;
        at += n;
        r
    };
    let normal = take(entries[0].history.len());
    let tangential = take(tangential.map_or(0, |e| e.history.len()));
    let rolling = take(rolling.map_or(0, |e| e.history.len()));
    let extras = spec
        .extra
        .iter()
        .map(|x| lookup(Slot::Extra, x).unwrap())
        .filter(|e| e.slot == Slot::Extra)
        .map(|e| take(e.history.len()))
        .collect();
    let contact_len = take(0).start;
    let bond = bond.map(|e| take(BOND_HEAD + e.history.len()).start);
    HistoryLayout {
        normal,
        tangential,
        rolling,
        extras,
        bond,
        contact_len,
        stride: take(0).start,
    }
}

/// Every material pair's laws, `table[a * n + b]` (both orders) for n materials, after
/// checking its materials exist, it is given once, and its coefficients fit the laws'
/// parameters.
fn pair_table(
    materials: &[Material],
    pairs: &[PairSpec],
    entries: &[&'static LawEntry],
) -> Result<Vec<Option<PairLaws>>> {
    let specs: Vec<(&'static str, param::ParamSpec)> = entries
        .iter()
        .flat_map(|e| e.params.iter().map(move |p| (e.name, *p)))
        .collect();
    let n = materials.len();
    let mut table: Vec<Option<PairLaws>> = (0..n * n).map(|_| None).collect();
    for p in pairs {
        let find =
            |name: &str| {
                materials.iter().position(|m| m.name == name).ok_or_else(|| {
                KernelError::Invalid(format!(
                    "pair ({}, {}) names material '{name}', which is not defined; defined: {}",
                    p.materials.0,
                    p.materials.1,
                    materials.iter().map(|m| m.name.as_str()).collect::<Vec<_>>().join(", ")
                ))
            })
            };
        let (a, b) = (find(&p.materials.0)?, find(&p.materials.1)?);
        let context = format!("pairs[{}-{}]", p.materials.0, p.materials.1);
        if table[a * n + b].is_some() {
            return Err(KernelError::Invalid(format!("{context} is given twice")));
        }
        param::validate(&context, &p.params, &specs)?;
        let input = LawInput {
            material_i: &materials[a],
            material_j: &materials[b],
            e_eff: effective_youngs(&materials[a], &materials[b]),
            g_eff: effective_shear(&materials[a], &materials[b]),
            params: Params::new(&p.params),
        };
        table[a * n + b] = Some(construct(entries, &input));
        if a != b {
            table[b * n + a] = Some(construct(entries, &input));
        }
    }
    Ok(table)
}
