//! `tilth check DATA`: reads a measurement file with every check the other commands make
//! (optionally against a model's ranges), then asks of the measurements themselves what no
//! simulation can change: can the direct-shear peaks and the unconfined compressive
//! strengths measured at the same conditions come from one material? (`tilth_tools::
//! consistency`, a Mohr-circle bound.) `compare` and `calibrate --joint` print the same
//! check, so that a user does not spend hours calibrating towards two numbers no single
//! material gives.

use super::measurements::{Measurement, check_against_model, read_measurements};
use crate::lab::model::Model;
use crate::lab::shear::default_shear_area;
use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::consistency::ShearUcsCheck;

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Measurements (CSV), e.g. data/li2022/measurements.csv.
    pub data: PathBuf,
    /// Also check every row's conditions against this model's ranges.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Error bands (%) to test the pairs against, shear then UCS, e.g. the study's 6.53,8.07.
    #[arg(long, value_delimiter = ',')]
    pub bands: Option<Vec<f64>>,
    /// Print JSON instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Write the Mohr diagram of the pairs (each UCS's failure circle and the shear box's
    /// point) to DIR/mohr.svg.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// A direct-shear row and a UCS row at the same moisture and firmness, checked.
#[derive(Debug, Clone, Serialize)]
pub struct PairCheck {
    pub conditions: BTreeMap<String, f64>,
    pub shear_row: usize,
    pub ucs_row: usize,
    #[serde(flatten)]
    pub check: ShearUcsCheck,
    /// With `--bands`: whether values within the bands can come from one material.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compatible_within_bands: Option<bool>,
}

/// Conditions two tests must share to be of the same soil.
const SAME_SOIL: [&str; 2] = ["moisture_pct", "firmness_mpa"];

/// Every (direct shear, UCS) pair of rows at the same moisture and firmness, in file order,
/// checked on the lab's shear box (61.8 mm).
pub fn shear_ucs_pairs(rows: &[Measurement]) -> Vec<PairCheck> {
    let area = default_shear_area();
    let mut out = vec![];
    for s in rows.iter().filter(|m| m.observable == "peak_shear_force_n") {
        let Some(&sigma) = s.conditions.get("normal_pressure_pa") else {
            continue;
        };
        for u in rows.iter().filter(|m| m.observable == "ucs_kpa") {
            if SAME_SOIL
                .iter()
                .all(|k| s.conditions.get(*k) == u.conditions.get(*k))
            {
                let conditions = SAME_SOIL
                    .iter()
                    .filter_map(|k| Some((k.to_string(), *s.conditions.get(*k)?)))
                    .collect();
                out.push(PairCheck {
                    conditions,
                    shear_row: s.row,
                    ucs_row: u.row,
                    check: ShearUcsCheck::new(area, sigma, s.value, 1e3 * u.value),
                    compatible_within_bands: None,
                });
            }
        }
    }
    out
}

/// The pairs as a markdown table with a verdict in words; empty when there are none.
pub fn describe(pairs: &[PairCheck]) -> String {
    if pairs.is_empty() {
        return String::new();
    }
    let area_mm2 = 1e6 * pairs[0].check.area_m2;
    let mut s = format!(
        "Direct shear against unconfined compression of the same soil. A material whose \
         unconfined strength is q has a failure envelope on or above the circle through 0 and q, \
         so its shear plane of A = {area_mm2:.0} mm^2 under sigma_n carries at least \
         F = A sqrt(sigma_n (q - sigma_n)) (tilth_tools::consistency):\n\n\
         | moisture % | firmness MPa | rows | peak shear N | sigma_n kPa | UCS kPa | least shear N for this UCS | largest UCS kPa for this shear | one material? | equal band needed |\n\
         |---|---|---|---|---|---|---|---|---|---|\n"
    );
    for p in pairs {
        let k = &p.check;
        let c = |n: &str| {
            p.conditions
                .get(n)
                .map_or_else(|| "-".into(), |v| format!("{v}"))
        };
        let verdict = match (k.compatible, p.compatible_within_bands) {
            (true, _) => "yes".to_string(),
            (false, Some(true)) => "no (yes within the bands)".to_string(),
            (false, _) => "**no**".to_string(),
        };
        s += &format!(
            "| {} | {} | {}, {} | {:.1} | {:.0} | {:.2} | {:.1} | {:.1} | {} | {} |\n",
            c("moisture_pct"),
            c("firmness_mpa"),
            p.shear_row,
            p.ucs_row,
            k.shear_force_n,
            1e-3 * k.normal_stress_pa,
            1e-3 * k.ucs_pa,
            k.min_shear_force_n,
            1e-3 * k.max_ucs_pa,
            verdict,
            if k.compatible {
                "-".to_string()
            } else {
                format!("{:.0} %", 100.0 * k.band_needed)
            }
        );
    }
    let bad: Vec<&PairCheck> = pairs.iter().filter(|p| !p.check.compatible).collect();
    s += "\n";
    if bad.is_empty() {
        s += "Every pair can come from one material.\n";
    } else {
        s += &format!(
            "{} of {} pairs cannot come from one material: no model whose shear and compression \
             specimens are the same homogeneous soil meets both of them, whatever its \
             parameters; a calibration to both finds a compromise, or needs something that \
             differs between the two tests (end friction on the compression platens, \
             progressive failure in the box, the normal stress or area of the shear test as \
             recorded), or specimens prepared differently per test: `tilth calibrate \
             --per-test` gives each test its own values (`when = {{ test = ... }}` in the \
             model).\n",
            bad.len(),
            pairs.len()
        );
        if pairs.iter().any(|p| p.compatible_within_bands.is_some()) {
            let still = bad
                .iter()
                .filter(|p| p.compatible_within_bands == Some(false))
                .count();
            s += &format!("Within the error bands given, {still} of them still cannot.\n");
        }
    }
    s
}

pub fn check(args: &CheckArgs) -> Result<String> {
    crate::study::summary(|out| check_into(args, out))
}

/// [`check`], writing its summary to `out`.
fn check_into(args: &CheckArgs, out: &mut dyn Write) -> Result<()> {
    let rows = read_measurements(&args.data)?;
    if let Some(m) = &args.model {
        let model = Model::load(m)?;
        check_against_model(&rows, &model, &args.data)?;
    }
    let mut pairs = shear_ucs_pairs(&rows);
    if let Some(b) = &args.bands {
        if b.len() != 2 || b.iter().any(|v| !(0.0..100.0).contains(v)) {
            anyhow::bail!(
                "--bands {b:?}: two bands in %, shear then UCS, each in [0, 100), e.g. 6.53,8.07"
            );
        }
        for p in &mut pairs {
            p.compatible_within_bands = Some(p.check.compatible_within(b[0] / 100.0, b[1] / 100.0));
        }
    }
    let mut per_test: BTreeMap<&str, usize> = BTreeMap::new();
    for r in &rows {
        *per_test.entry(r.test.as_str()).or_default() += 1;
    }
    let incompatible = pairs.iter().filter(|p| !p.check.compatible).count();
    let plotted = match (&args.plot, pairs.is_empty()) {
        (Some(dir), false) => {
            let labelled: Vec<(String, &ShearUcsCheck)> = pairs
                .iter()
                .map(|p| {
                    let c = |k: &str| p.conditions.get(k).map_or("-".into(), |v| v.to_string());
                    (
                        format!("{} %, {} MPa", c("moisture_pct"), c("firmness_mpa")),
                        &p.check,
                    )
                })
                .collect();
            let svg = tilth_tools::consistency::mohr_svg(&labelled).map_err(anyhow::Error::msg)?;
            std::fs::create_dir_all(dir)
                .with_context(|| format!("--plot {}: cannot create", dir.display()))?;
            let path = dir.join("mohr.svg");
            std::fs::write(&path, svg)
                .with_context(|| format!("{}: cannot write", path.display()))?;
            Some(path)
        }
        _ => None,
    };
    if args.json {
        let json = serde_json::json!({
            "data": args.data.display().to_string(),
            "rows": rows.len(),
            "tests": per_test,
            "shear_ucs": pairs,
            "shear_ucs_incompatible": incompatible,
            "plot": plotted.as_ref().map(|p| p.display().to_string()),
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&json)?)?;
        return Ok(());
    }
    let tests: Vec<String> = per_test.iter().map(|(t, n)| format!("{t} {n}")).collect();
    writeln!(
        out,
        "{}: {} rows ({}), every row valid{}.\n",
        args.data.display(),
        rows.len(),
        tests.join(", "),
        if args.model.is_some() {
            " and inside the model's ranges"
        } else {
            ""
        }
    )?;
    let words = describe(&pairs);
    if words.is_empty() {
        writeln!(
            out,
            "No direct shear and UCS rows at the same conditions to check against each other."
        )?;
    } else {
        write!(out, "{words}")?;
    }
    if let Some(p) = plotted {
        writeln!(out, "\nwritten: {}", p.display())?;
    }
    Ok(())
}
