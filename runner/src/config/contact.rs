//! `[contact]` (which law fills each slot) and `[[pairs]]` (coefficients per material pair).
//! `tilth laws` lists every law with its parameters, units and ranges.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use tilth_kernel::contact::PairSpec;

/// Law names from the registry, one per slot; only `normal` is required.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSection {
    /// Elastic normal force, e.g. "hertz" or "jkr".
    pub normal: String,
    /// Viscous damping, e.g. "restitution"; none when omitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<String>,
    /// Friction, e.g. "mindlin"; frictionless when omitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tangential: Option<String>,
    /// Rolling resistance, e.g. "epsd" or "cdt"; none when omitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rolling: Option<String>,
    /// Additive normal forces, e.g. ["capillary"].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extra: Vec<String>,
}

/// The coefficients of one material pair (order does not matter). Every key other than
/// `materials` is a law parameter; the model builder refuses keys the chosen laws do not take,
/// names the allowed ones and checks each value's range.
#[derive(Debug, Deserialize, Serialize)]
pub struct PairSection {
    /// The two material names, e.g. ["soil", "steel"].
    pub materials: [String; 2],
    /// Law parameters, e.g. restitution = 0.45 (units as `tilth laws` lists them).
    #[serde(flatten)]
    pub params: BTreeMap<String, f64>,
}

impl PairSection {
    pub fn to_spec(&self) -> PairSpec {
        PairSpec {
            materials: (self.materials[0].clone(), self.materials[1].clone()),
            params: self.params.clone(),
        }
    }
}
