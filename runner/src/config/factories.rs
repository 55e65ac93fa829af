//! `[[factories]]`: particles created in a region at a rate (EDEM "dynamic factory").

use super::check;
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use tilth_kernel::factory::{Basis, Factory, FactorySpec, Region};
use tilth_kernel::material::Material;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FactorySection {
    /// Where particles are created (the whole sphere lies inside).
    pub region: RegionSection,
    /// Material name.
    pub material: String,
    /// Total number of particles to create.
    pub count: usize,
    /// Particles per second; all at once when omitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate: Option<f64>,
    /// Initial velocity, m/s (default at rest).
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Whether size fractions count particles or mass (default "number").
    #[serde(default)]
    pub basis: BasisSection,
    /// Size classes; fractions are normalised.
    pub sizes: Vec<SizeClass>,
    /// When the factory starts, s (default 0).
    #[serde(default)]
    pub start_time: f64,
}

/// `{ type = "box", min, max }` or `{ type = "cylinder", base, radius, height }` (vertical, along z).
#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum RegionSection {
    /// Axis-aligned box, corners in m.
    Box { min: [f64; 3], max: [f64; 3] },
    /// Vertical cylinder: centre of the base (m), radius (m), height (m).
    Cylinder {
        base: [f64; 3],
        radius: f64,
        height: f64,
    },
}

#[derive(Debug, Default, Clone, Copy, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BasisSection {
    #[default]
    Number,
    Mass,
}

/// One size class.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SizeClass {
    /// Particle diameter, m.
    pub diameter: f64,
    /// Share of the class (by number or mass, see `basis`), >= 0; normalised over the classes.
    pub fraction: f64,
}

/// Factory k's seed: a SplitMix64 mix of the scene seed and k, so factories draw independent
/// streams and one scene seed fixes them all.
pub fn factory_seed(seed: u64, k: usize) -> u64 {
    let mut z = seed.wrapping_add((k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

pub fn resolve(
    sections: &[FactorySection],
    materials: &[Material],
    seed: u64,
) -> Result<Vec<Factory>> {
    let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
    let mut out = vec![];
    for (k, f) in sections.iter().enumerate() {
        let key = |s: &str| format!("factories[{k}].{s}");
        let material = check::material(&key("material"), &f.material, &names)?;
        if f.count == 0 {
            bail!("{} = 0; give at least 1", key("count"));
        }
        let rate = match f.rate {
            Some(r) => check::positive(&key("rate"), r, "1/s")?,
            None => f64::INFINITY,
        };
        if f.sizes.is_empty() {
            bail!(
                "{} is empty; give at least one {{ diameter, fraction }}",
                key("sizes")
            );
        }
        let mut sizes = vec![];
        for (c, s) in f.sizes.iter().enumerate() {
            let d = check::positive(&key(&format!("sizes[{c}].diameter")), s.diameter, "m")?;
            let w = check::non_negative(&key(&format!("sizes[{c}].fraction")), s.fraction, "-")?;
            sizes.push((0.5 * d, w));
        }
        let region = match f.region {
            RegionSection::Box { min, max } => {
                let (lo, hi) = (
                    check::vec3(&key("region.min"), min)?,
                    check::vec3(&key("region.max"), max)?,
                );
                if !lo.cmplt(hi).all() {
                    bail!(
                        "{}: min {min:?} must lie below max {max:?} on every axis",
                        key("region")
                    );
                }
                Region::Box { min: lo, max: hi }
            }
            RegionSection::Cylinder {
                base,
                radius,
                height,
            } => Region::Cylinder {
                base: check::vec3(&key("region.base"), base)?,
                radius: check::positive(&key("region.radius"), radius, "m")?,
                height: check::positive(&key("region.height"), height, "m")?,
            },
        };
        let spec = FactorySpec {
            region,
            sizes,
            basis: match f.basis {
                BasisSection::Number => Basis::Number,
                BasisSection::Mass => Basis::Mass,
            },
            material,
            density: materials[material as usize].density,
            rate,
            count: f.count,
            velocity: check::vec3(&key("velocity"), f.velocity)?,
            start_time: check::non_negative(&key("start_time"), f.start_time, "s")?,
            seed: factory_seed(seed, k),
        };
        out.push(Factory::new(spec).with_context(|| format!("factories[{k}]"))?);
    }
    Ok(out)
}
