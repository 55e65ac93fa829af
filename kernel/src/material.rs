//! Bulk materials and the effective (pair) quantities of Hertz-Mindlin contact.
//!
//! docs/physics.md, "Effective quantities":
//! - 1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j
//! - 1/G* = 2(2 - nu_i)(1 + nu_i)/E_i + 2(2 - nu_j)(1 + nu_j)/E_j

use crate::error::{KernelError, Result};

/// A bulk material: Young's modulus E (Pa), Poisson ratio nu (-), density rho (kg/m^3).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub density: f64,
}

impl Material {
    pub fn new(name: &str, youngs_modulus: f64, poisson_ratio: f64, density: f64) -> Result<Self> {
        let m = Material {
            name: name.to_string(),
            youngs_modulus,
            poisson_ratio,
            density,
        };
        m.validate()?;
        Ok(m)
    }

    /// From shear modulus G: E = 2 G (1 + nu) (isotropic elasticity).
    pub fn from_shear_modulus(
        name: &str,
        shear_modulus: f64,
        poisson_ratio: f64,
        density: f64,
    ) -> Result<Self> {
        if !(shear_modulus > 0.0 && shear_modulus.is_finite()) {
            return Err(range_err(
                name,
                "shear_modulus",
                shear_modulus,
                "(0, inf)",
                "Pa",
            ));
        }
        Self::new(
            name,
            2.0 * shear_modulus * (1.0 + poisson_ratio),
            poisson_ratio,
            density,
        )
    }

    pub fn validate(&self) -> Result<()> {
        let n = &self.name;
        if !(self.youngs_modulus > 0.0 && self.youngs_modulus.is_finite()) {
            return Err(range_err(
                n,
                "youngs_modulus",
                self.youngs_modulus,
                "(0, inf)",
                "Pa",
            ));
        }
        // Thermodynamic bounds of isotropic elasticity; 0.5 (incompressible) makes G* singular-free
        // but E* infinite in the limit, so it is excluded.
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(range_err(
                n,
                "poisson_ratio",
                self.poisson_ratio,
                "(-1, 0.5)",
                "-",
            ));
        }
        if !(self.density > 0.0 && self.density.is_finite()) {
            return Err(range_err(n, "density", self.density, "(0, inf)", "kg/m^3"));
        }
        Ok(())
    }

    /// G = E / (2 (1 + nu)), Pa.
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }
}

fn range_err(material: &str, key: &str, value: f64, range: &str, unit: &str) -> KernelError {
    KernelError::OutOfRange {
        key: format!("materials.{material}.{key}"),
        value,
        range: range.to_string(),
        unit: unit.to_string(),
    }
}

/// Effective Young's modulus E* (Pa) of a contact between materials a and b.
pub fn effective_youngs(a: &Material, b: &Material) -> f64 {
    let inv = (1.0 - a.poisson_ratio.powi(2)) / a.youngs_modulus
        + (1.0 - b.poisson_ratio.powi(2)) / b.youngs_modulus;
    1.0 / inv
}

/// Effective shear modulus G* (Pa) of a contact between materials a and b.
pub fn effective_shear(a: &Material, b: &Material) -> f64 {
    let part =
        |m: &Material| 2.0 * (2.0 - m.poisson_ratio) * (1.0 + m.poisson_ratio) / m.youngs_modulus;
    1.0 / (part(a) + part(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn study_soil_effective_moduli() {
        // Same material both sides: E* = E / (2 (1 - nu^2)), G* = E / (4 (2 - nu)(1 + nu)).
        let soil = Material::new("soil", 13.5e6, 0.2, 1380.0).unwrap();
        let e = effective_youngs(&soil, &soil);
        let g = effective_shear(&soil, &soil);
        assert!((e - 13.5e6 / (2.0 * 0.96)).abs() < 1e-6);
        assert!((g - 13.5e6 / (4.0 * 1.8 * 1.2)).abs() < 1e-6);
        assert!((soil.shear_modulus() - 5.625e6).abs() < 1e-6);
    }

    #[test]
    fn bad_material_is_refused_with_key_and_range() {
        let err = Material::new("soil", -1.0, 0.2, 1380.0)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("materials.soil.youngs_modulus") && err.contains("(0, inf)"),
            "{err}"
        );
        let err = Material::new("soil", 1e6, 0.5, 1380.0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("poisson_ratio"), "{err}");
        let steel = Material::from_shear_modulus("steel", 79e9, 0.3, 7865.0).unwrap();
        assert!((steel.youngs_modulus - 205.4e9).abs() < 1e3);
    }
}
