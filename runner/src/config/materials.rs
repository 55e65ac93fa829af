//! `[materials.NAME]`: bulk materials of particles and walls.

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use tilth_kernel::material::Material;

/// One material. Give exactly one of `youngs_modulus` and `shear_modulus`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSection {
    /// Young's modulus E, Pa.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// Shear modulus G, Pa (E = 2 G (1 + nu)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shear_modulus: Option<f64>,
    /// Poisson ratio nu, in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Density rho, kg/m^3.
    pub density: f64,
}

/// The kernel materials, in name order (the order of their indices).
pub fn resolve(sections: &BTreeMap<String, MaterialSection>) -> Result<Vec<Material>> {
    if sections.is_empty() {
        bail!("no materials: add at least one [materials.NAME] table");
    }
    let mut out = vec![];
    for (name, m) in sections {
        let mat = match (m.youngs_modulus, m.shear_modulus) {
            (Some(e), None) => Material::new(name, e, m.poisson_ratio, m.density)?,
            (None, Some(g)) => Material::from_shear_modulus(name, g, m.poisson_ratio, m.density)?,
            _ => {
                bail!("materials.{name}: give exactly one of youngs_modulus and shear_modulus (Pa)")
            }
        };
        out.push(mat);
    }
    if out.len() > u16::MAX as usize {
        bail!("too many materials ({}); at most {}", out.len(), u16::MAX);
    }
    Ok(out)
}
