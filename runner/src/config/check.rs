//! Small value checks shared by the sections; errors read like the kernel's
//! (`walls[2].radius = -0.01 is out of range: allowed (0, inf) m`).

use anyhow::{Result, bail};
use tilth_kernel::{DVec3, KernelError};

fn out_of_range(key: &str, value: f64, range: &str, unit: &str) -> anyhow::Error {
    KernelError::OutOfRange {
        key: key.to_string(),
        value,
        range: range.to_string(),
        unit: unit.to_string(),
    }
    .into()
}

/// A value in (0, inf).
pub fn positive(key: &str, value: f64, unit: &str) -> Result<f64> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(out_of_range(key, value, "(0, inf)", unit))
    }
}

/// A value in [0, inf).
pub fn non_negative(key: &str, value: f64, unit: &str) -> Result<f64> {
    if value >= 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(out_of_range(key, value, "[0, inf)", unit))
    }
}

/// Any finite value.
pub fn finite(key: &str, value: f64, unit: &str) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(out_of_range(key, value, "(-inf, inf)", unit))
    }
}

/// A vector with finite components.
pub fn vec3(key: &str, v: [f64; 3]) -> Result<DVec3> {
    let d = DVec3::from_array(v);
    if !d.is_finite() {
        bail!("{key} = {v:?} must have finite components");
    }
    Ok(d)
}

/// A finite, non-zero direction (not normalised; the kernel does that).
pub fn direction(key: &str, v: [f64; 3]) -> Result<DVec3> {
    let d = vec3(key, v)?;
    if d.length_squared() == 0.0 {
        bail!("{key} = {v:?} must be a non-zero direction");
    }
    Ok(d)
}

/// The index of material `name`, or an error listing the defined ones.
pub fn material(key: &str, name: &str, defined: &[String]) -> Result<u16> {
    match defined.iter().position(|m| m == name) {
        Some(i) => Ok(i as u16),
        None => bail!(
            "{key} = \"{name}\" is not a defined material; defined: {} (add a [materials.{name}] table or fix the name)",
            defined.join(", ")
        ),
    }
}
