//! Typed law parameters: each law declares its parameters with units and allowed ranges,
//! and the model builder checks every value against them before a run starts.

use crate::error::{KernelError, Result};
use std::collections::BTreeMap;

/// One bound of an allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    Open(f64),
    Closed(f64),
    Unbounded,
}

/// A parameter a law takes: its key, unit, allowed range, optional default and meaning.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    pub key: &'static str,
    pub unit: &'static str,
    pub min: Bound,
    pub max: Bound,
    /// `None` means required.
    pub default: Option<f64>,
    pub doc: &'static str,
}

impl ParamSpec {
    /// The range as a mathematician writes it, e.g. `(0, 1]`.
    pub fn range_text(&self) -> String {
        let lo = match self.min {
            Bound::Open(v) => format!("({v}"),
            Bound::Closed(v) => format!("[{v}"),
            Bound::Unbounded => "(-inf".to_string(),
        };
        let hi = match self.max {
            Bound::Open(v) => format!("{v})"),
            Bound::Closed(v) => format!("{v}]"),
            Bound::Unbounded => "inf)".to_string(),
        };
        format!("{lo}, {hi}")
    }

    pub fn contains(&self, v: f64) -> bool {
        if !v.is_finite() {
            return false;
        }
        let lo = match self.min {
            Bound::Open(b) => v > b,
            Bound::Closed(b) => v >= b,
            Bound::Unbounded => true,
        };
        let hi = match self.max {
            Bound::Open(b) => v < b,
            Bound::Closed(b) => v <= b,
            Bound::Unbounded => true,
        };
        lo && hi
    }

    /// Checks `v`, naming `key_path` (e.g. `pairs[soil-soil].restitution`) in the error.
    pub fn check(&self, key_path: &str, v: f64) -> Result<()> {
        if self.contains(v) {
            Ok(())
        } else {
            Err(KernelError::OutOfRange {
                key: key_path.to_string(),
                value: v,
                range: self.range_text(),
                unit: self.unit.to_string(),
            })
        }
    }
}

/// Checks that every key of `given` is declared in `specs`, that every required key is present
/// and that every value lies in its range. `context` names where the values came from.
pub fn validate(
    context: &str,
    given: &BTreeMap<String, f64>,
    specs: &[(&'static str, ParamSpec)],
) -> Result<()> {
    for key in given.keys() {
        if !specs.iter().any(|(_, s)| s.key == key) {
            let mut allowed: Vec<&str> = specs.iter().map(|(_, s)| s.key).collect();
            allowed.sort();
            allowed.dedup();
            return Err(KernelError::UnknownKey {
                context: context.to_string(),
                key: key.clone(),
                allowed: if allowed.is_empty() {
                    "(nothing)".into()
                } else {
                    allowed.join(", ")
                },
            });
        }
    }
    for (law, spec) in specs {
        match given.get(spec.key) {
            Some(&v) => spec.check(&format!("{context}.{}", spec.key), v)?,
            None if spec.default.is_none() => {
                return Err(KernelError::MissingKey {
                    context: context.to_string(),
                    key: spec.key.to_string(),
                    law: law.to_string(),
                    doc: format!("{}, {} {}", spec.doc, spec.range_text(), spec.unit),
                });
            }
            None => {}
        }
    }
    Ok(())
}

/// Validated parameter values handed to a law's constructor.
#[derive(Debug, Clone, Copy)]
pub struct Params<'a> {
    pub(crate) values: &'a BTreeMap<String, f64>,
}

impl<'a> Params<'a> {
    pub fn new(values: &'a BTreeMap<String, f64>) -> Self {
        Params { values }
    }

    /// The value of `spec`, or its default. The builder has validated presence and range.
    pub fn get(&self, spec: &ParamSpec) -> f64 {
        self.values
            .get(spec.key)
            .copied()
            .or(spec.default)
            .unwrap_or(f64::NAN)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const E: ParamSpec = ParamSpec {
        key: "restitution",
        unit: "-",
        min: Bound::Open(0.0),
        max: Bound::Closed(1.0),
        default: None,
        doc: "coefficient of restitution",
    };

    #[test]
    fn range_text_and_membership() {
        assert_eq!(E.range_text(), "(0, 1]");
        assert!(E.contains(1.0));
        assert!(!E.contains(0.0));
        assert!(!E.contains(f64::NAN));
    }

    #[test]
    fn validate_names_key_and_range() {
        let mut m = BTreeMap::new();
        m.insert("restitution".to_string(), 1.5);
        let err = validate("pairs[soil-soil]", &m, &[("hertz", E)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("pairs[soil-soil].restitution"), "{err}");
        assert!(err.contains("(0, 1]"), "{err}");
        m.clear();
        m.insert("restitutoin".to_string(), 0.5);
        let err = validate("pairs[soil-soil]", &m, &[("hertz", E)])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("unknown key 'restitutoin'") && err.contains("restitution"),
            "{err}"
        );
        m.clear();
        let err = validate("pairs[soil-soil]", &m, &[("restitution", E)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing key 'restitution'"), "{err}");
    }
}
