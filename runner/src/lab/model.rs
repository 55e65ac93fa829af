//! Model files: test conditions (moisture, firmness, ...) -> materials and contact parameters.
//!
//! ```toml
//! format_version = 1
//! name = "li2022"
//! conditions = { moisture_pct = [3, 12], firmness_mpa = [0.34, 2.76] }   # allowed ranges
//! [materials.soil]
//! youngs_modulus = 13.5e6
//! [contact]
//! normal = "jkr"
//! [pairs.soil-soil]
//! restitution = 0.45                                                          # a constant
//! rolling_friction = { interpolate = "moisture_pct", x = [3, 6], y = [0.19, 0.15] }
//! surface_energy = { polynomial = "moisture_pct", coefficients = [0.35, 0.001] }
//! shear_stiffness_per_area = { cases = [
//!   { when = { moisture_pct = 6 }, value = { interpolate = "firmness_mpa", x = [...], y = [...] } },
//!   { when = { firmness_mpa = 1.55 }, value = { interpolate = "moisture_pct", ... } } ] }
//! ```
//!
//! A value is a number, a linear interpolation in one condition (no extrapolation: a
//! condition outside the table is refused with the table's range), a polynomial
//! c0 + c1 x + c2 x^2 + ... in one condition, or `cases`: the first case whose `when`
//! conditions all equal the given ones. A `when` may also name the test, `test = "ucs"`:
//! that case holds for that test's specimens only (the study calibrated its bonds per test,
//! tables 2 and 3, and tables 12 and 13 cannot both come from one material; see
//! docs/li2022-statistics.md). Materials and the contact section pass through to the scene
//! unchanged.

use super::experiment::KINDS;
use crate::config::{ContactSection, MaterialSection, PairSection};
use anyhow::{Context, Result, anyhow, bail};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Value;

/// A model file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    pub format_version: i64,
    pub name: String,
    pub description: Option<String>,
    /// Condition name -> [min, max] allowed.
    pub conditions: BTreeMap<String, [f64; 2]>,
    /// Scene `[materials]`, passed through.
    pub materials: toml::Table,
    /// Scene `[contact]`, passed through.
    pub contact: toml::Table,
    /// "a-b" -> parameter -> value form.
    pub pairs: BTreeMap<String, BTreeMap<String, Value>>,
    /// Bonds, used only by experiments that form them (direct shear, UCS).
    pub bond: Option<BondModel>,
    /// Effects the model lacks, for `tilth diagnose`; the lab ignores them.
    #[serde(default)]
    pub candidates: BTreeMap<String, CandidateModel>,
    /// `[probes]`: parameters the model holds fixed but is unsure of, `"PAIR.KEY" = STEP`,
    /// which `tilth diagnose` weighs against the candidates (the model with each raised by
    /// STEP); the lab ignores them.
    #[serde(default)]
    pub probes: BTreeMap<String, f64>,
    /// The soil's size mix beyond the test's one diameter ([`super::sizes::SizeMix`]).
    pub particles: Option<ParticlesModel>,
}

/// `[particles]`: a fine fraction beside the test's particle diameter.
///
/// ```toml
/// [particles]
/// fine_fraction = 0.1          # mass fraction, [0, 0.5]; a value form (may follow a condition)
/// fine_diameter_ratio = 0.5    # fine diameter / the test's diameter, [0.3, 1)
/// ```
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticlesModel {
    pub fine_fraction: Option<Value>,
    pub fine_diameter_ratio: Option<f64>,
}

/// `[candidates.NAME]`: a physical effect the model might be missing, with a strength
/// where 0 is the model as it is. Switching it on at strength s adds `extra` (a law of the
/// extra slot) to the contact model, sets `pairs` (that law's fixed parameters), and adds s
/// to every parameter in `strength` (`PAIR.KEY`; a missing one counts as 0).
///
/// ```toml
/// [candidates.capillary]
/// extra = "capillary"
/// strength = ["soil-soil.surface_tension"]   # N/m; 0 = no liquid bridges
/// step = 0.02
/// pairs.soil-soil = { bridge_volume = 5e-13 }
/// pairs.soil-steel = { bridge_volume = 5e-13, surface_tension = 0.0 }
/// ```
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CandidateModel {
    pub description: Option<String>,
    pub extra: Option<String>,
    pub strength: Vec<String>,
    /// A condition (e.g. `moisture_pct`): the strength is then a slope along it, each
    /// strength parameter changing by strength x (condition - the middle of its range), so
    /// that 0 is still the model as it is.
    pub along: Option<String>,
    /// Finite-difference step of the strength (its unit is the strength parameters').
    pub step: f64,
    #[serde(default)]
    pub pairs: BTreeMap<String, BTreeMap<String, Value>>,
}

/// `[bond]`: the bond law and its parameters per material pair.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondModel {
    /// The law for the contact model's `bond` slot (e.g. "bond").
    pub law: String,
    /// "a-b" -> parameter -> value form.
    pub pairs: BTreeMap<String, BTreeMap<String, Value>>,
}

/// A model file with where it came from.
#[derive(Debug, Clone)]
pub struct Model {
    pub file: ModelFile,
    pub path: PathBuf,
}

/// Test conditions: name -> value.
pub type Conditions = BTreeMap<String, f64>;

/// Where a value is evaluated: the test conditions and, when known, the test, which a
/// `cases` entry may name (`when = { test = "ucs" }`). A case that names a test does not
/// match where the test is unknown.
#[derive(Debug, Clone, Copy)]
pub struct At<'a> {
    pub conditions: &'a Conditions,
    pub test: Option<&'a str>,
}

impl<'a> At<'a> {
    /// Conditions only (no test named).
    pub fn conditions(conditions: &'a Conditions) -> At<'a> {
        At {
            conditions,
            test: None,
        }
    }

    /// Conditions in one test.
    pub fn test(conditions: &'a Conditions, test: &'a str) -> At<'a> {
        At {
            conditions,
            test: Some(test),
        }
    }
}

impl Model {
    pub fn load(path: &Path) -> Result<Model> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let file: ModelFile = toml::from_str(&text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start].matches('\n').count() + 1)
                .map(|l| format!(":{l}"))
                .unwrap_or_default();
            anyhow!("{}{line}: {}", path.display(), e.message())
        })?;
        if file.format_version != 1 {
            bail!(
                "{}: format_version = {} is not supported; this tilth reads model format_version = 1",
                path.display(),
                file.format_version
            );
        }
        Ok(Model {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Checks the given conditions against the model's declared ones and their ranges
    /// (a condition an experiment does not need may be left out).
    pub fn check_conditions(&self, conds: &Conditions) -> Result<()> {
        let p = self.path.display();
        for (name, v) in conds {
            let [lo, hi] = self.file.conditions.get(name).ok_or_else(|| {
                let known: Vec<&str> = self.file.conditions.keys().map(String::as_str).collect();
                anyhow!(
                    "{p}: unknown condition `{name}`; the model's conditions are {}",
                    known.join(", ")
                )
            })?;
            if !(lo..=hi).contains(&v) {
                bail!("{p}: condition {name} = {v} is out of range: allowed [{lo}, {hi}]");
            }
        }
        Ok(())
    }

    /// The scene sections the model gives at `at` (materials, contact laws and the pairs'
    /// coefficients), with the bond law and its parameters when `bonds`.
    pub fn scene_parts(&self, at: At, bonds: bool) -> Result<SceneParts> {
        self.check_conditions(at.conditions)?;
        let path = self.path.display();
        let mut by_pair: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
        let mut add =
            |section: &str, pairs: &BTreeMap<String, BTreeMap<String, Value>>| -> Result<()> {
                for (pair, params) in pairs {
                    let t = by_pair.entry(pair.clone()).or_default();
                    for (key, form) in params {
                        let v = evaluate_at(form, at)
                            .map_err(|e| anyhow!("{path}: {section}.{pair}.{key}: {e}"))?;
                        t.insert(key.clone(), v);
                    }
                }
                Ok(())
            };
        add("pairs", &self.file.pairs)?;
        let mut contact: ContactSection = self.section("contact", &self.file.contact)?;
        if bonds {
            let b = self.file.bond.as_ref().ok_or_else(|| {
                anyhow!("{path}: this experiment forms bonds, but the model has no [bond] section")
            })?;
            add("bond.pairs", &b.pairs)?;
            // The bond law goes with the additive laws (`extra`); the kernel gives it its slot.
            contact.extra.push(b.law.clone());
        }
        let mut pairs = vec![];
        for (pair, params) in by_pair {
            let (a, b) = pair.split_once('-').ok_or_else(|| {
                anyhow!("{path}: [pairs.{pair}]: name a pair as material-material")
            })?;
            pairs.push(PairSection {
                materials: [a.into(), b.into()],
                params,
            });
        }
        Ok(SceneParts {
            materials: self.section("materials", &self.file.materials)?,
            contact,
            pairs,
        })
    }

    /// A table the model passes through to the scene, read as the scene reads it, so that
    /// a key the scene does not take is refused with the model's name.
    fn section<T: serde::de::DeserializeOwned>(
        &self,
        name: &str,
        table: &toml::Table,
    ) -> Result<T> {
        Value::Table(table.clone())
            .try_into()
            .map_err(|e: toml::de::Error| {
                let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
                anyhow!("{}: [{name}]: {message}", self.path.display())
            })
    }
}

/// The scene sections a model gives at some conditions.
#[derive(Debug)]
pub struct SceneParts {
    /// `[materials]`, as the model has them.
    pub materials: BTreeMap<String, MaterialSection>,
    /// `[contact]`, with the bond law among the additive laws when the test forms bonds.
    pub contact: ContactSection,
    /// `[[pairs]]`, in the order of the pairs' names, each value evaluated at the conditions.
    pub pairs: Vec<PairSection>,
}

fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn numbers(v: Option<&Value>, key: &str) -> Result<Vec<f64>> {
    let list = v
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("`{key}` must be a list of numbers"))?;
    list.iter()
        .map(|x| number(x).ok_or_else(|| anyhow!("`{key}` must be a list of numbers")))
        .collect()
}

fn condition<'a>(t: &toml::Table, key: &str, conds: &'a Conditions) -> Result<(&'a str, f64)> {
    let name = t
        .get(key)
        .and_then(Value::as_str)
        .ok_or_else(|| anyhow!("`{key}` must name a condition"))?;
    conds
        .get_key_value(name)
        .map(|(k, v)| (k.as_str(), *v))
        .ok_or_else(|| anyhow!("condition `{name}` is not given"))
}

/// The value of one parameter form at `conds`, in no test in particular.
pub fn evaluate(form: &Value, conds: &Conditions) -> Result<f64> {
    evaluate_at(form, At::conditions(conds))
}

/// The value of one parameter form at `at`.
pub fn evaluate_at(form: &Value, at: At) -> Result<f64> {
    let conds = at.conditions;
    if let Some(x) = number(form) {
        return Ok(x);
    }
    let t = form.as_table().ok_or_else(|| {
        anyhow!("a value is a number or a table (interpolate, polynomial, cases)")
    })?;
    if t.contains_key("interpolate") {
        let (name, c) = condition(t, "interpolate", conds)?;
        let x = numbers(t.get("x"), "x")?;
        let y = numbers(t.get("y"), "y")?;
        if x.len() != y.len() || x.is_empty() || x.windows(2).any(|w| w[0] >= w[1]) {
            bail!("x and y must have the same length and x must increase");
        }
        let (lo, hi) = (x[0], x[x.len() - 1]);
        if c < lo || c > hi {
            bail!("{name} = {c} is outside the table: allowed [{lo}, {hi}]");
        }
        let k = x.iter().position(|&xi| xi >= c).unwrap_or(x.len() - 1);
        if k == 0 || x[k] == c {
            return Ok(y[k]);
        }
        let f = (c - x[k - 1]) / (x[k] - x[k - 1]);
        return Ok(y[k - 1] + f * (y[k] - y[k - 1]));
    }
    if t.contains_key("polynomial") {
        let (_, c) = condition(t, "polynomial", conds)?;
        let coef = numbers(t.get("coefficients"), "coefficients")?;
        return Ok(coef.iter().rev().fold(0.0, |acc, k| acc * c + k));
    }
    if let Some(cases) = t.get("cases").and_then(Value::as_array) {
        for case in cases {
            let when = case
                .get("when")
                .and_then(Value::as_table)
                .ok_or_else(|| anyhow!("each case needs `when = {{ condition = value }}`"))?;
            let mut hit = true;
            for (k, v) in when {
                hit &= if k == "test" {
                    let name = v.as_str().filter(|n| KINDS.contains(n)).ok_or_else(|| {
                        anyhow!(
                            "`when = {{ test = {v} }}`: the tests are {}",
                            KINDS.join(", ")
                        )
                    })?;
                    at.test == Some(name)
                } else {
                    let v = number(v).ok_or_else(|| {
                        anyhow!("`when = {{ {k} = {v} }}`: a condition's value is a number")
                    })?;
                    conds.get(k).is_some_and(|c| (c - v).abs() < 1e-9)
                };
            }
            if hit {
                let value = case
                    .get("value")
                    .ok_or_else(|| anyhow!("a case needs `value`"))?;
                return evaluate_at(value, at);
            }
        }
        let mut given: Vec<String> = conds.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        if let Some(t) = at.test {
            given.push(format!("test = \"{t}\""));
        }
        bail!("no case matches {}", given.join(", "));
    }
    bail!("unknown value form: use a number, {{ interpolate }}, {{ polynomial }} or {{ cases }}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn conds(m: f64, f: f64) -> Conditions {
        [
            ("moisture_pct".to_string(), m),
            ("firmness_mpa".to_string(), f),
        ]
        .into()
    }

    #[test]
    fn forms_evaluate_by_their_formulas() {
        let v: Value = toml::from_str(
            "a = { interpolate = \"moisture_pct\", x = [3, 6, 9], y = [1.0, 2.0, 4.0] }\n\
             b = { polynomial = \"firmness_mpa\", coefficients = [1.0, 2.0, 3.0] }\n\
             c = { cases = [ { when = { moisture_pct = 6 }, value = 7.0 }, { when = { firmness_mpa = 1.55 }, value = { interpolate = \"moisture_pct\", x = [3, 12], y = [0.0, 9.0] } } ] }",
        )
        .unwrap();
        assert_eq!(evaluate(&v["a"], &conds(4.5, 1.0)).unwrap(), 1.5);
        assert_eq!(evaluate(&v["a"], &conds(9.0, 1.0)).unwrap(), 4.0);
        assert_eq!(
            evaluate(&v["b"], &conds(3.0, 2.0)).unwrap(),
            1.0 + 4.0 + 12.0
        );
        assert_eq!(evaluate(&v["c"], &conds(6.0, 0.34)).unwrap(), 7.0);
        assert_eq!(evaluate(&v["c"], &conds(9.0, 1.55)).unwrap(), 6.0);
        let e = evaluate(&v["a"], &conds(12.0, 1.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("allowed [3, 9]"), "{e}");
        let e = evaluate(&v["c"], &conds(9.0, 0.34))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no case matches"), "{e}");
    }

    #[test]
    fn a_case_may_name_the_test_and_holds_for_that_test_only() {
        let v: Value = toml::from_str(
            "s = { cases = [ { when = { test = \"ucs\", moisture_pct = 6 }, value = 5.0 }, \
                             { when = { test = \"direct_shear\" }, value = 3.0 }, \
                             { when = {}, value = 1.0 } ] }\n\
             typo = { cases = [ { when = { test = \"shear\" }, value = 2.0 } ] }\n\
             word = { cases = [ { when = { moisture_pct = \"six\" }, value = 2.0 } ] }",
        )
        .unwrap();
        let c = conds(6.0, 1.55);
        assert_eq!(evaluate_at(&v["s"], At::test(&c, "ucs")).unwrap(), 5.0);
        assert_eq!(
            evaluate_at(&v["s"], At::test(&c, "direct_shear")).unwrap(),
            3.0
        );
        assert_eq!(evaluate_at(&v["s"], At::test(&c, "repose")).unwrap(), 1.0);
        // Another moisture skips the UCS case; no test named skips both test cases.
        let c9 = conds(9.0, 1.55);
        assert_eq!(evaluate_at(&v["s"], At::test(&c9, "ucs")).unwrap(), 1.0);
        assert_eq!(evaluate(&v["s"], &c).unwrap(), 1.0);
        let e = evaluate_at(&v["typo"], At::test(&c, "ucs"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("repose, direct_shear, ucs, tilt"), "{e}");
        let e = evaluate(&v["word"], &c).unwrap_err().to_string();
        assert!(e.contains("a condition's value is a number"), "{e}");
    }
}
