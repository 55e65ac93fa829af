//! Experiment files (`sweeps/experiments/*.toml`): a virtual lab test at given conditions.
//!
//! ```toml
//! format_version = 1
//! experiment = "repose"                 # repose | direct_shear | ucs | tilt
//! model = "../../models/li2022.toml"    # conditions -> materials and contact parameters
//! [conditions]
//! moisture_pct = 6
//! [simulation]                          # all optional
//! seed = 1
//! skin_fraction = 0.6                 # Verlet skin, particle diameters (speed only)
//! [repose]                              # the test's own parameters, all with defaults
//! drop_height = 0.03
//! ```
//!
//! The experiment builds a scene (walls, factory, materials and contact from the model) that
//! goes through the same checks as a scene file, plus a [`Protocol`] that runs its phases.
//! `coarse = true` (or `tilth run --coarse`) switches to each test's coarse preset, which
//! finishes in under a minute for tests and smoke runs.

use super::model::{At, Conditions, Model};
use super::protocol::Protocol;
use super::{repose, shear, tilt, ucs};
use crate::config;
use crate::config::target;
use anyhow::{Context, Result, anyhow, bail};
use serde::Deserialize;
use std::path::Path;
use toml::Value;

/// An experiment file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentFile {
    pub format_version: i64,
    /// `repose`, `direct_shear`, `ucs` or `tilt`.
    pub experiment: String,
    /// Model file, relative to this file.
    pub model: String,
    #[serde(default)]
    pub conditions: Conditions,
    /// Use the test's coarse preset (bigger particles, less material).
    #[serde(default)]
    pub coarse: bool,
    #[serde(default)]
    pub simulation: SimulationSettings,
    pub repose: Option<repose::ReposeParams>,
    pub direct_shear: Option<shear::ShearParams>,
    pub ucs: Option<ucs::UcsParams>,
    pub tilt: Option<tilt::TiltParams>,
}

/// `[simulation]` of an experiment.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSettings {
    /// Time step, s (default: `dt_fraction` of the Rayleigh time of the particles).
    pub dt: Option<f64>,
    /// Fraction of the Rayleigh time used when `dt` is not given (EDEM practice 0.2-0.4).
    #[serde(default = "default_dt_fraction")]
    pub dt_fraction: f64,
    /// Verlet skin as a fraction of the smallest particle diameter (default: the test's own,
    /// [`repose::SKIN_FRACTION`] for the funnel, 0.2 for the specimens). A speed setting
    /// only: the pair list holds every pair within reach plus the skin, and a pair out of
    /// contact adds nothing, so the results are the same to the bit for every skin.
    pub skin_fraction: Option<f64>,
    #[serde(default = "one_u64")]
    pub seed: u64,
    #[serde(default = "one_usize")]
    pub threads: usize,
}

fn default_dt_fraction() -> f64 {
    0.35
}
fn one_u64() -> u64 {
    1
}
fn one_usize() -> usize {
    1
}

impl Default for SimulationSettings {
    fn default() -> Self {
        SimulationSettings {
            dt: None,
            dt_fraction: default_dt_fraction(),
            skin_fraction: None,
            seed: 1,
            threads: 1,
        }
    }
}

/// What a test needs from the common part of the file.
pub struct Common<'a> {
    pub model: &'a Model,
    pub conditions: &'a Conditions,
    /// The test (one of [`KINDS`]): model values may differ per test.
    pub test: &'a str,
    pub sim: &'a SimulationSettings,
    pub coarse: bool,
}

impl Common<'_> {
    /// Where the model's values are evaluated: these conditions, in this test.
    pub fn at(&self) -> At<'_> {
        At::test(self.conditions, self.test)
    }
}

/// A built experiment: the scene (TOML, checked like any scene) and its protocol.
pub struct Built {
    pub scene: Value,
    /// The time step the protocol switches to when it forms bonds (the scene's `dt` is the
    /// preparation's), s; `None` for a test without bonds.
    pub bonded_dt: Option<f64>,
    pub protocol: Box<dyn Protocol>,
}

/// Which tests exist.
pub const KINDS: [&str; 4] = ["repose", "direct_shear", "ucs", "tilt"];

/// Whether a TOML document is an experiment file (it has `experiment = "..."`).
pub fn is_experiment(v: &Value) -> bool {
    v.get("experiment").is_some()
}

/// Builds the experiment in `value` (read from `origin`, relative paths from `dir`); scene
/// overrides (`scene:` factor targets) are applied to the generated scene.
pub fn build(
    value: Value,
    origin: &str,
    dir: &Path,
    scene_overrides: &[(String, Value)],
) -> Result<Built> {
    let file: ExperimentFile = value
        .try_into()
        .map_err(|e: toml::de::Error| anyhow!("{origin}: {}", one_line(&e)))?;
    if file.format_version != 1 {
        bail!(
            "{origin}: format_version = {} is not supported; this tilth reads experiment format_version = 1",
            file.format_version
        );
    }
    let mut model = Model::load(&dir.join(&file.model))
        .with_context(|| format!("{origin}: model = \"{}\"", file.model))?;
    bond_overrides_into_model(&mut model, scene_overrides);
    let s = &file.simulation;
    if !(s.dt_fraction > 0.0 && s.dt_fraction <= 1.0) {
        bail!(
            "{origin}: simulation.dt_fraction = {} is out of range: allowed (0, 1]",
            s.dt_fraction
        );
    }
    if let Some(k) = s.skin_fraction {
        if !(k > 0.0 && k <= 2.0) {
            bail!(
                "{origin}: simulation.skin_fraction = {k} is out of range: allowed (0, 2] particle diameters"
            );
        }
    }
    if s.threads == 0 {
        bail!("{origin}: simulation.threads = 0 is out of range: allowed [1, cores]");
    }
    let common = Common {
        model: &model,
        conditions: &file.conditions,
        test: &file.experiment,
        sim: &file.simulation,
        coarse: file.coarse,
    };
    let wrong = |name: &str| -> anyhow::Error {
        anyhow!(
            "{origin}: [{name}] is for experiment = \"{name}\"; this file is \"{}\"",
            file.experiment
        )
    };
    let tables = [
        ("repose", file.repose.is_some()),
        ("direct_shear", file.direct_shear.is_some()),
        ("ucs", file.ucs.is_some()),
        ("tilt", file.tilt.is_some()),
    ];
    if let Some((name, _)) = tables.iter().find(|&&(name, given)| {
        given && KINDS.contains(&file.experiment.as_str()) && name != file.experiment
    }) {
        return Err(wrong(name));
    }
    let mut built = match file.experiment.as_str() {
        "repose" => repose::build(&common, &file.repose.clone().unwrap_or_default()),
        "direct_shear" => shear::build(&common, &file.direct_shear.clone().unwrap_or_default()),
        "ucs" => ucs::build(&common, &file.ucs.clone().unwrap_or_default()),
        "tilt" => tilt::build(&common, &file.tilt.clone().unwrap_or_default()),
        other => bail!(
            "{origin}: experiment = \"{other}\" is unknown: allowed {}",
            KINDS.join(", ")
        ),
    }
    .with_context(|| origin.to_string())?;
    for (path, v) in scene_overrides {
        target::set(&mut built.scene, path, v.clone())
            .with_context(|| format!("{origin}: scene:{path}"))?;
    }
    Ok(built)
}

/// Scene overrides of bond parameters (`pairs[P].K` where the model has K in
/// `[bond.pairs.P]` and not in `[pairs.P]`) written into the model as well, so that what the
/// lab derives from the bonds before the overrides reach the scene (the time step from the
/// stiffest bond) sees the values the run will have: a sweep or calibration over bond
/// stiffness otherwise runs stiff bonds at the time step of the model's soft ones.
fn bond_overrides_into_model(model: &mut Model, scene_overrides: &[(String, Value)]) {
    let Some(bond) = model.file.bond.as_mut() else {
        return;
    };
    for (path, v) in scene_overrides {
        let Some((pair, key)) = path
            .strip_prefix("pairs[")
            .and_then(|rest| rest.split_once("]."))
        else {
            continue;
        };
        let in_contact = model
            .file
            .pairs
            .get(pair)
            .is_some_and(|t| t.contains_key(key));
        if let Some(slot) = bond.pairs.get_mut(pair).and_then(|t| t.get_mut(key))
            && !in_contact
        {
            *slot = v.clone();
        }
    }
}

/// Whether `key = value` can stand in the test's own table (`[repose]`, `[direct_shear]` or
/// `[ucs]`): a key it has, a value of the right type (ranges are checked when a run is built).
/// Errs with serde's sentence, which lists the keys the table has.
pub fn check_test_key(test: &str, key: &str, value: &Value) -> Result<(), String> {
    let mut t = toml::Table::new();
    t.insert(key.to_string(), value.clone());
    let v = Value::Table(t);
    let r = match test {
        "repose" => v.try_into::<repose::ReposeParams>().map(|_| ()),
        "direct_shear" => v.try_into::<shear::ShearParams>().map(|_| ()),
        "ucs" => v.try_into::<ucs::UcsParams>().map(|_| ()),
        "tilt" => v.try_into::<tilt::TiltParams>().map(|_| ()),
        other => return Err(format!("`{other}` is not a test")),
    };
    r.map_err(|e| one_line(&e))
}

fn one_line(e: &toml::de::Error) -> String {
    e.message().split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Prepares the scene of a built experiment like any scene file.
pub fn prepare(
    built: &Built,
    origin: &str,
    dir: &Path,
    threads: Option<usize>,
) -> Result<config::Prepared> {
    config::prepare_value(built.scene.clone(), origin, dir, threads)
}

/// The Rayleigh time (s) of a particle of diameter `d` of the model's material `soil`.
pub fn rayleigh_time(model: &Model, d: f64) -> Result<f64> {
    let soil = model
        .file
        .materials
        .get("soil")
        .and_then(Value::as_table)
        .ok_or_else(|| {
            anyhow!(
                "{}: the model needs a material `soil`",
                model.path.display()
            )
        })?;
    let num = |k: &str| {
        soil.get(k)
            .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
    };
    let nu = num("poisson_ratio").unwrap_or(0.2);
    let rho = num("density").ok_or_else(|| anyhow!("materials.soil.density is missing"))?;
    let g = match (num("shear_modulus"), num("youngs_modulus")) {
        (Some(g), _) => g,
        (None, Some(e)) => e / (2.0 * (1.0 + nu)),
        _ => bail!("materials.soil needs youngs_modulus or shear_modulus"),
    };
    Ok(std::f64::consts::PI * 0.5 * d * (rho / g).sqrt() / (0.1631 * nu + 0.8766))
}

/// The particle diameter of a test: `given`, else 2 mm (the study's class), or 4 mm in the
/// coarse preset.
pub fn particle_diameter(c: &Common, given: Option<f64>) -> f64 {
    given.unwrap_or(if c.coarse { 0.004 } else { 0.002 })
}

/// The number `key` of the model's material `soil`, if given (integers read as floats).
fn soil_number(model: &Model, key: &str) -> Option<f64> {
    model
        .file
        .materials
        .get("soil")
        .and_then(|m| m.get(key))
        .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
}

/// Young's modulus of the model's soil, Pa.
pub fn soil_modulus(model: &Model) -> Result<f64> {
    let num = |k: &str| soil_number(model, k);
    match (num("youngs_modulus"), num("shear_modulus")) {
        (Some(e), _) => Ok(e),
        (None, Some(g)) => Ok(2.0 * g * (1.0 + soil_poisson_ratio(model))),
        _ => bail!(
            "{}: materials.soil needs youngs_modulus or shear_modulus",
            model.path.display()
        ),
    }
}

/// Poisson ratio of the model's soil (0.2 when not given, as in the Rayleigh time).
pub fn soil_poisson_ratio(model: &Model) -> f64 {
    soil_number(model, "poisson_ratio").unwrap_or(0.2)
}

/// Density of the model's soil, kg/m^3.
pub fn soil_density(model: &Model) -> Result<f64> {
    soil_number(model, "density").ok_or_else(|| {
        anyhow!(
            "{}: materials.soil.density is missing",
            model.path.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ucs_dt(overrides: &[(String, Value)]) -> f64 {
        let text = "format_version = 1\nexperiment = \"ucs\"\nmodel = \"models/li2022.toml\"\ncoarse = true\n[conditions]\nmoisture_pct = 6\nfirmness_mpa = 1.55\n";
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let built = build(toml::from_str(text).unwrap(), "test", &root, overrides).unwrap();
        built.bonded_dt.unwrap()
    }

    /// A model value in a case that names the test reaches that test's scene only.
    #[test]
    fn a_value_for_one_test_reaches_that_tests_scene_only() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let model = std::fs::read_to_string(root.join("models/li2022.toml")).unwrap();
        let per_test = "critical_shear_stress = { cases = [ \
            { when = { test = \"ucs\", moisture_pct = 6, firmness_mpa = 1.55 }, value = 4.5e5 }, \
            { when = { test = \"direct_shear\" }, value = 1.5e5 }, { when = {}, value = 6e4 } ] }";
        let start = model.find("critical_shear_stress = { cases").unwrap();
        let end = start + model[start..].find("] }\n").unwrap() + 3;
        let dir = std::env::temp_dir().join(format!("tilth-per-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("model.toml");
        std::fs::write(
            &path,
            format!("{}{per_test}{}", &model[..start], &model[end..]),
        )
        .unwrap();
        let value_in = |test: &str, moisture: f64| -> f64 {
            let text = format!(
                "format_version = 1\nexperiment = \"{test}\"\nmodel = \"{}\"\ncoarse = true\n\
                 [conditions]\nmoisture_pct = {moisture}\nfirmness_mpa = 1.55\n",
                path.display()
            );
            let built = build(toml::from_str(&text).unwrap(), "test", &dir, &[]).unwrap();
            let pairs = built.scene["pairs"].as_array().unwrap();
            let soil = pairs
                .iter()
                .find(|p| {
                    p["materials"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .all(|m| m.as_str() == Some("soil"))
                })
                .unwrap();
            soil["critical_shear_stress"].as_float().unwrap()
        };
        assert_eq!(value_in("ucs", 6.0), 4.5e5);
        assert_eq!(value_in("direct_shear", 6.0), 1.5e5);
        assert_eq!(value_in("ucs", 9.0), 6e4);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A sweep that stiffens the bonds through the scene gets the time step of the stiffer
    /// bonds once they form: BOND_DT_FRACTION sqrt(m / (S pi r^2)) for the coarse preset's
    /// 4 mm grains.
    #[test]
    fn a_stiffer_bond_set_through_the_scene_shortens_the_time_step() {
        let soft = ucs_dt(&[]);
        for key in ["normal_stiffness_per_area", "shear_stiffness_per_area"] {
            let stiff = ucs_dt(&[(format!("pairs[soil-soil].{key}"), Value::Float(1e10))]);
            let (d, rho) = (0.004, 1380.0);
            let m = rho * std::f64::consts::PI * d * d * d / 6.0;
            let k = 1e10 * std::f64::consts::PI * (0.5 * d) * (0.5 * d);
            let expected = super::super::specimen::BOND_DT_FRACTION * (m / k).sqrt();
            assert!(
                (stiff - expected).abs() < 1e-12 * expected,
                "{key}: dt {stiff} against {expected}"
            );
            assert!(stiff < soft, "{key}: {stiff} against {soft}");
        }
        // A contact parameter (in [pairs]) leaves the time step alone.
        let friction = ucs_dt(&[("pairs[soil-soil].friction".into(), Value::Float(0.3))]);
        assert_eq!(friction, soft);
    }
}
