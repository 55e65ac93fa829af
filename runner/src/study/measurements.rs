//! Measurement files: one row per measured value (see data/li2022/README.md).
//!
//! ```text
//! test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source
//! repose,6,,,repose_angle_deg,35.53,deg,0.8,10,table 1
//! ```
//!
//! A file may add setting columns, `TEST.KEY`: a number key of a test's own table (the keys of
//! `sweeps/experiments/*.toml`, as `--set` takes them), which a row of that test sets for its
//! own runs over the preset and any `--set`: the funnel at another drop height
//! (`repose.drop_height`) or on another tray (`repose.tray_diameter`). An empty cell keeps the
//! preset's value. A setting is a condition of its row: it keys the row's runs and seeds.
//!
//! Everything is checked before any simulation starts, and every error names the file, the
//! row (1-based, the header is row 1) and the column, with what is allowed: a missing
//! column, an unknown test or observable, a condition the test needs left empty, a number
//! that is not one, a non-positive uncertainty, uncertainty_dof or replicate count, and
//! (against a model) a condition outside the model's range.
//!
//! `uncertainty_dof` (optional) is the degrees of freedom of `uncertainty` when it is itself
//! estimated (GUM's effective degrees of freedom; `synth` writes it for the scatter of its
//! truth runs). Empty: the uncertainty is taken as exact. The chi^2 tests allow for it
//! ([`tilth_tools::compare::welch`]).

use crate::lab::model::Model;
use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The tests tilth simulates, each with the observables it measures and their units; the
/// first is the test's own (the one the study reports).
///
/// A repose run also gives the funnel test's other readings: the angle of the heap on the
/// fixed base (atan(H / R), H the heap's height over the tray of radius R: the fixed-base
/// cone method, USP <1174>), the mass the tray holds, the funnel's mass flow rate
/// (`lab::discharge`: the Hall-flowmeter reading) and the soil left in the funnel (weighed
/// after the test). They respond to different physics: the flow rate to wall friction and
/// cohesion much more than to rolling resistance, the residue to adhesion to the steel.
///
/// The tilting plate (`lab::tilt`) reads the angle at which a bonded sample slides on steel
/// and its tangent, the static friction coefficient of the study's table 1: it responds to
/// the soil-steel friction and to adhesion between soil and steel, hardly to the soil's
/// own cohesion, which the sample's bonds hold.
pub const OBSERVABLES: [(&str, &str, &str); 9] = [
    ("repose", "repose_angle_deg", "deg"),
    ("repose", "heap_cone_angle_deg", "deg"),
    ("repose", "tray_mass_g", "g"),
    ("repose", "funnel_flow_rate_g_s", "g/s"),
    ("repose", "funnel_residue_g", "g"),
    ("direct_shear", "peak_shear_force_n", "N"),
    ("ucs", "ucs_kpa", "kPa"),
    ("tilt", "static_friction", "-"),
    ("tilt", "slide_angle_deg", "deg"),
];

/// The tests, in order.
pub const TESTS: [&str; 4] = ["repose", "direct_shear", "ucs", "tilt"];

/// The observables a test measures, with their units; the first is the test's own.
pub fn observables_of(test: &str) -> Vec<(&'static str, &'static str)> {
    OBSERVABLES
        .iter()
        .filter(|(t, _, _)| *t == test)
        .map(|(_, o, u)| (*o, *u))
        .collect()
}

/// The test's own observable and its unit, or None for an unknown test.
pub fn observable_of(test: &str) -> Option<(&'static str, &'static str)> {
    observables_of(test).first().copied()
}

/// Condition columns, in file order.
pub const CONDITIONS: [&str; 3] = ["moisture_pct", "firmness_mpa", "normal_pressure_pa"];

/// A setting column's test and key (`repose.drop_height` -> `("repose", "drop_height")`), or
/// None for a column that is not one.
pub fn setting_of(column: &str) -> Option<(&str, &str)> {
    let (test, key) = column.split_once('.')?;
    TESTS.contains(&test).then_some((test, key))
}

/// The columns a conditions (or measurement) file may have: a measurement file's, and
/// settings, each a number key of its test's table.
pub fn check_conditions_columns(file: &str, head: &[String]) -> Result<()> {
    let allowed: Vec<&str> = REQUIRED
        .iter()
        .chain(CONDITIONS.iter())
        .chain(OPTIONAL.iter())
        .copied()
        .collect();
    for h in head.iter().filter(|h| !allowed.contains(&h.as_str())) {
        let Some((test, key)) = setting_of(h) else {
            bail!(
                "{file}: unknown column `{h}`; allowed: {}, and settings TEST.KEY (e.g. repose.drop_height)",
                allowed.join(", ")
            );
        };
        if let Some((_, condition)) = KEYS_OF_CONDITIONS.iter().find(|(k, _)| k == h) {
            bail!(
                "{file}: column `{h}`: the test's key of the condition `{condition}`; give it there"
            );
        }
        crate::lab::experiment::check_test_key(test, key, &toml::Value::Float(1.0)).map_err(
            |e| {
                anyhow!(
                    "{file}: column `{h}`: {e}; a setting column is TEST.KEY with a number key of the test's table (see sweeps/experiments/{test}.toml)"
                )
            },
        )?;
    }
    Ok(())
}

/// Test keys a condition column sets (`lab_runs::condition_factors`), not to be set twice.
const KEYS_OF_CONDITIONS: [(&str, &str); 1] =
    [("direct_shear.normal_pressure", "normal_pressure_pa")];

/// Columns every file must have.
const REQUIRED: [&str; 4] = ["test", "observable", "value", "unit"];

/// Columns a file may have besides the required ones, conditions and settings.
const OPTIONAL: [&str; 4] = ["uncertainty", "uncertainty_dof", "replicates", "source"];

/// One measurement row.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Measurement {
    /// Row in the file (the header is row 1).
    pub row: usize,
    pub test: String,
    pub conditions: BTreeMap<String, f64>,
    pub observable: String,
    pub value: f64,
    pub unit: String,
    /// One standard deviation of the measured value, when known.
    pub uncertainty: Option<f64>,
    /// Degrees of freedom of `uncertainty` when it is estimated; None: exact.
    pub uncertainty_dof: Option<f64>,
    /// Tests the value averages, when known.
    pub replicates: Option<u32>,
    pub source: String,
}

/// The conditions a test needs.
pub fn conditions_of(test: &str) -> &'static [&'static str] {
    match test {
        "repose" => &CONDITIONS[..1],
        "ucs" | "tilt" => &CONDITIONS[..2],
        _ => &CONDITIONS[..],
    }
}

/// Opens a CSV file (cells trimmed) and reads its header.
pub fn open_csv(path: &Path) -> Result<(csv::Reader<std::fs::File>, Vec<String>)> {
    let file = path.display();
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(false)
        .from_path(path)
        .with_context(|| format!("{file}: cannot read"))?;
    let head: Vec<String> = reader
        .headers()
        .with_context(|| format!("{file}: cannot read the header"))?
        .iter()
        .map(str::to_string)
        .collect();
    Ok((reader, head))
}

/// The rows of an open CSV that are not blank, each with its row number (the header is 1).
pub fn rows_of<'a>(
    reader: &'a mut csv::Reader<std::fs::File>,
    head: &'a [String],
    file: &'a str,
) -> impl Iterator<Item = Result<Cells<'a>>> + 'a {
    reader.records().enumerate().filter_map(move |(k, record)| {
        let row = k + 2;
        match record {
            Err(e) => Some(Err(anyhow!("{file}: row {row}: {e}"))),
            Ok(r) if r.iter().all(str::is_empty) => None,
            Ok(record) => Some(Ok(Cells {
                file,
                row,
                head,
                record,
            })),
        }
    })
}

/// One row of a CSV file, for reading cells with errors that name the file, row and column.
pub struct Cells<'a> {
    file: &'a str,
    pub row: usize,
    head: &'a [String],
    record: csv::StringRecord,
}

impl Cells<'_> {
    pub fn has(&self, name: &str) -> bool {
        self.head.iter().any(|h| h == name)
    }

    /// The cell under `name` ("" when the column is missing).
    pub fn cell(&self, name: &str) -> &str {
        self.head
            .iter()
            .position(|h| h == name)
            .and_then(|c| self.record.get(c))
            .unwrap_or("")
    }

    /// "FILE: row R, column NAME".
    pub fn at(&self, name: &str) -> String {
        format!("{}: row {}, column {name}", self.file, self.row)
    }

    /// A finite number, or `None` for an empty cell.
    pub fn number(&self, name: &str) -> Result<Option<f64>> {
        let s = self.cell(name);
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => bail!("{}: `{s}` is not a finite number", self.at(name)),
        }
    }

    /// The row's test, with its own observable and that observable's unit.
    pub fn test(&self) -> Result<(String, &'static str, &'static str)> {
        let test = self.cell("test").to_string();
        let (observable, unit) = observable_of(&test).ok_or_else(|| {
            anyhow!(
                "{}: test `{test}` is unknown; allowed: {}",
                self.at("test"),
                TESTS.join(", ")
            )
        })?;
        Ok((test, observable, unit))
    }

    /// The row's observable, one that `test` measures, and its unit.
    pub fn observable(&self, test: &str) -> Result<(&'static str, &'static str)> {
        let name = self.cell("observable");
        let all = observables_of(test);
        all.iter()
            .find(|(o, _)| *o == name)
            .copied()
            .ok_or_else(|| {
                anyhow!(
                    "{}: a {test} test measures {}, not `{name}`",
                    self.at("observable"),
                    all.iter()
                        .map(|(o, _)| format!("`{o}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }

    /// The conditions `test` needs, each present and a number.
    pub fn conditions(&self, test: &str) -> Result<BTreeMap<String, f64>> {
        let mut conditions = BTreeMap::new();
        for name in conditions_of(test) {
            if !self.has(name) {
                bail!(
                    "{}: no column `{name}`, which a {test} row (row {}) needs",
                    self.file,
                    self.row
                );
            }
            let v = self
                .number(name)?
                .ok_or_else(|| anyhow!("{}: empty, but a {test} test needs it", self.at(name)))?;
            conditions.insert(name.to_string(), v);
        }
        for column in self.head.iter().filter(|h| setting_of(h).is_some()) {
            let Some(v) = self.number(column)? else {
                continue;
            };
            let (owner, _) = setting_of(column).expect("a setting");
            if owner != test {
                bail!(
                    "{}: a {test} row cannot set a {owner} test's key; leave it empty",
                    self.at(column)
                );
            }
            conditions.insert(column.to_string(), v);
        }
        Ok(conditions)
    }
}

/// Reads and checks a measurement file.
pub fn read_measurements(path: &Path) -> Result<Vec<Measurement>> {
    let (mut reader, head) = open_csv(path)?;
    let file = path.display().to_string();
    let missing: Vec<&str> = REQUIRED
        .iter()
        .copied()
        .filter(|c| !head.iter().any(|h| h == c))
        .collect();
    if !missing.is_empty() {
        bail!(
            "{file}: missing column{} {}; a measurement file needs {} (conditions: {}; optional: {}, and settings TEST.KEY)",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", "),
            REQUIRED.join(", "),
            CONDITIONS.join(", "),
            OPTIONAL.join(", ")
        );
    }
    check_conditions_columns(&file, &head)?;
    let mut out = vec![];
    for cells in rows_of(&mut reader, &head, &file) {
        let c = cells?;
        let (test, _, _) = c.test()?;
        let (observable, unit) = c.observable(&test)?;
        if c.cell("unit") != unit {
            bail!(
                "{}: {observable} is in {unit}, not `{}`",
                c.at("unit"),
                c.cell("unit")
            );
        }
        let value = c
            .number("value")?
            .ok_or_else(|| anyhow!("{}: empty", c.at("value")))?;
        let conditions = c.conditions(&test)?;
        let uncertainty = c.number("uncertainty")?;
        if let Some(u) = uncertainty {
            if u <= 0.0 {
                bail!(
                    "{}: {u} is not a standard deviation: allowed > 0, or empty when unknown",
                    c.at("uncertainty")
                );
            }
        }
        let uncertainty_dof = c.number("uncertainty_dof")?;
        if let Some(d) = uncertainty_dof {
            if !(d > 0.0) || uncertainty.is_none() {
                bail!(
                    "{}: `{d}` is not a count of degrees of freedom of an uncertainty: allowed > 0 beside an uncertainty, or empty when it is exact",
                    c.at("uncertainty_dof")
                );
            }
        }
        let replicates = match c.cell("replicates") {
            "" => None,
            s => match s.parse::<u32>() {
                Ok(n) if n >= 1 => Some(n),
                _ => bail!(
                    "{}: `{s}` is not a count: allowed a whole number >= 1, or empty",
                    c.at("replicates")
                ),
            },
        };
        out.push(Measurement {
            row: c.row,
            test,
            conditions,
            observable: observable.to_string(),
            value,
            unit: unit.to_string(),
            uncertainty,
            uncertainty_dof,
            replicates,
            source: c.cell("source").to_string(),
        });
    }
    if out.is_empty() {
        bail!("{file}: no measurement rows");
    }
    Ok(out)
}

/// Checks every row's conditions against the model's ranges (conditions the model does not
/// declare, such as a test's normal pressure, are the experiment's to check).
pub fn check_against_model(rows: &[Measurement], model: &Model, path: &Path) -> Result<()> {
    for m in rows {
        for (name, v) in &m.conditions {
            if let Some([lo, hi]) = model.file.conditions.get(name) {
                if !(lo..=hi).contains(&v) {
                    bail!(
                        "{}: row {}, column {name}: {v} is outside the model's range [{lo}, {hi}] ({})",
                        path.display(),
                        m.row,
                        model.path.display()
                    );
                }
            }
        }
    }
    Ok(())
}

/// Writes rows in the same format (the header of data/li2022/measurements.csv, with
/// `uncertainty_dof` after `uncertainty` when a row has one).
pub fn write_measurements(path: &Path, rows: &[Measurement]) -> Result<()> {
    let mut w = csv::Writer::from_path(path)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    let settings = setting_columns(rows);
    let with_dof = rows.iter().any(|m| m.uncertainty_dof.is_some());
    let mut head: Vec<&str> = vec!["test"];
    head.extend(CONDITIONS);
    head.extend(settings.iter().map(String::as_str));
    head.extend(["observable", "value", "unit", "uncertainty"]);
    if with_dof {
        head.push("uncertainty_dof");
    }
    head.extend(["replicates", "source"]);
    w.write_record(&head)?;
    for m in rows {
        let mut rec = vec![m.test.clone()];
        for c in CONDITIONS
            .iter()
            .copied()
            .chain(settings.iter().map(String::as_str))
        {
            rec.push(
                m.conditions
                    .get(c)
                    .map(|v| v.to_string())
                    .unwrap_or_default(),
            );
        }
        rec.push(m.observable.clone());
        rec.push(format!("{}", m.value));
        rec.push(m.unit.clone());
        rec.push(m.uncertainty.map(|u| u.to_string()).unwrap_or_default());
        if with_dof {
            rec.push(m.uncertainty_dof.map(|d| d.to_string()).unwrap_or_default());
        }
        rec.push(m.replicates.map(|n| n.to_string()).unwrap_or_default());
        rec.push(m.source.clone());
        w.write_record(&rec)?;
    }
    w.flush()?;
    Ok(())
}

/// The setting columns the rows use, in name order.
pub fn setting_columns(rows: &[Measurement]) -> Vec<String> {
    let set: std::collections::BTreeSet<&String> = rows
        .iter()
        .flat_map(|m| m.conditions.keys())
        .filter(|k| setting_of(k).is_some())
        .collect();
    set.into_iter().cloned().collect()
}
