//! `[[particles]]`: explicit particles created before the first step (small scenes, tests).

use super::check;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use tilth_kernel::material::Material;
use tilth_kernel::particles::Particles;

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleSection {
    /// Centre, m.
    pub position: [f64; 3],
    /// Initial velocity, m/s (default at rest).
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Diameter, m.
    pub diameter: f64,
    /// Material name.
    pub material: String,
}

/// The particles, in file order (so the kernel's `particles[i]` is the file's i-th).
pub fn resolve(sections: &[ParticleSection], materials: &[Material]) -> Result<Particles> {
    let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
    let mut p = Particles::default();
    for (i, s) in sections.iter().enumerate() {
        let key = |k: &str| format!("particles[{i}].{k}");
        let x = check::vec3(&key("position"), s.position)?;
        let v = check::vec3(&key("velocity"), s.velocity)?;
        let d = check::positive(&key("diameter"), s.diameter, "m")?;
        let m = check::material(&key("material"), &s.material, &names)?;
        p.push(x, v, 0.5 * d, materials[m as usize].density, m);
    }
    Ok(p)
}
