//! What a calibration starts from, shared by the per-condition and the joint calibration:
//! the option checks, the free parameters in the model, the measurements kept, the surface
//! design and the factors and conditions of a test's runs.

use super::{CalibrateArgs, Param, param_form, parse_param};
use crate::lab::model::Model;
use crate::study::lab_runs::{condition_factors, factor};
use crate::study::measurements::{Measurement, read_measurements};
use crate::sweep::plan::{Factor, PlannedRun};
use anyhow::{Result, anyhow, bail};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The one-test options a per-condition calibration needs: a single known test, and the
/// seed and tolerance options in range.
pub(super) fn check_single_test(args: &CalibrateArgs) -> Result<()> {
    if args.test.contains(',') {
        bail!(
            "--test {}: several tests are calibrated together only with --joint (one value per parameter across them)",
            args.test
        );
    }
    if !crate::study::measurements::TESTS.contains(&args.test.as_str()) {
        bail!(
            "--test {}: unknown, allowed {}",
            args.test,
            crate::study::measurements::TESTS.join(", ")
        );
    }
    check_counts(args)
}

/// The seed counts, the check precision and its cap, and the tolerance: each in range, the
/// cap given only with the precision it caps.
pub(super) fn check_counts(args: &CalibrateArgs) -> Result<()> {
    if args.check_seeds == Some(0) {
        bail!("--check-seeds 0 is out of range: allowed 1 or more");
    }
    if args.seeds == 0 {
        bail!("--seeds 0 is out of range: allowed 1 or more");
    }
    if let Some(se) = args.check_se {
        if !(se > 0.0 && se.is_finite()) {
            bail!("--check-se {se} is out of range: allowed > 0 (percent of the measurement)");
        }
    }
    let batch = args.check_seeds.unwrap_or(args.seeds);
    match args.max_check_seeds {
        Some(_) if args.check_se.is_none() => {
            bail!("--max-check-seeds is the cap of --check-se; give --check-se PCT too")
        }
        Some(max) if max < batch => bail!(
            "--max-check-seeds {max} is out of range: allowed at least --check-seeds ({batch})"
        ),
        _ => {}
    }
    if !(args.tolerance > 0.0) {
        bail!(
            "--tolerance {} is out of range: allowed > 0 (percent)",
            args.tolerance
        );
    }
    Ok(())
}

/// The free parameters, the model file (absolute) and the model, each parameter checked to
/// be in it.
pub fn load_params(args: &CalibrateArgs) -> Result<(Vec<Param>, PathBuf, Model)> {
    let params: Vec<Param> = args
        .params
        .iter()
        .map(|p| parse_param(p))
        .collect::<Result<_>>()?;
    let model_path = std::path::absolute(&args.model)?;
    let model = Model::load(&model_path)?;
    for p in &params {
        if param_form(&model, p).is_none() {
            bail!(
                "--param {}.{}: the model {} has no pairs.{}.{} (nor bond.pairs.{}.{})",
                p.pair,
                p.key,
                args.model.display(),
                p.pair,
                p.key,
                p.pair,
                p.key
            );
        }
    }
    Ok((params, model_path, model))
}

/// The measurements of `tests` that every `--where` keeps, checked against the model.
pub fn select_rows(
    args: &CalibrateArgs,
    model: &Model,
    tests: &[&str],
) -> Result<Vec<Measurement>> {
    let all = read_measurements(&args.data)?;
    crate::study::measurements::check_against_model(&all, model, &args.data)?;
    let mut rows: Vec<Measurement> = all
        .into_iter()
        .filter(|m| tests.contains(&m.test.as_str()))
        .collect();
    // The surface's runs take only the tests' conditions as factors; a row's setting would
    // be dropped unseen.
    if let Some((m, k)) = rows.iter().find_map(|m| {
        m.conditions
            .keys()
            .find(|k| crate::study::measurements::setting_of(k).is_some())
            .map(|k| (m, k))
    }) {
        bail!(
            "{}: row {}, column {k}: calibrate takes no per-row settings; give one setting to every run with --set {k}=VALUE",
            args.data.display(),
            m.row
        );
    }
    for f in &args.filters {
        let (k, v) = f
            .split_once('=')
            .ok_or_else(|| anyhow!("--where {f:?}: expected NAME=VALUE"))?;
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| anyhow!("--where {f:?}: {v:?} is not a number"))?;
        rows.retain(|m| m.conditions.get(k.trim()) == Some(&v));
    }
    if rows.is_empty() {
        bail!(
            "{}: no {} measurement to calibrate against",
            args.data.display(),
            args.test
        );
    }
    Ok(rows)
}

/// The surface design in coded units: the 3^k factorial, then two more centre points.
pub fn surface_grid(k: usize) -> Vec<Vec<f64>> {
    let mut grid: Vec<Vec<f64>> = (0..3usize.pow(k as u32))
        .map(|mut g| {
            (0..k)
                .map(|_| {
                    let v = (g % 3) as f64 - 1.0;
                    g /= 3;
                    v
                })
                .collect()
        })
        .collect();
    grid.push(vec![0.0; k]);
    grid.push(vec![0.0; k]);
    grid
}

/// A coded value in real units: x = (low + high) / 2 + z (high - low) / 2, so that -1, 0
/// and 1 are the range's low end, middle and high end.
fn real(p: &Param, z: f64) -> f64 {
    0.5 * (p.low + p.high) + z * 0.5 * (p.high - p.low)
}

/// Appends `m`'s surface runs to `runs`: each point of `grid` (coded) with `--seeds` seeds,
/// at `m`'s conditions of `test`.
pub(crate) fn push_surface_runs(
    runs: &mut Vec<PlannedRun>,
    test: &str,
    m: &Measurement,
    grid: &[Vec<f64>],
    params: &[Param],
    args: &CalibrateArgs,
) -> Result<()> {
    for (g, z) in grid.iter().enumerate() {
        // The factorial shares its seeds (common random numbers: differences between
        // settings are not blurred by the packing); the two extra centre points take
        // fresh seeds, so that they measure the scatter between seeds.
        let first_seed = 1 + g.saturating_sub(grid.len() - 3) * args.seeds;
        for s in 0..args.seeds {
            let mut values = cond_values(test, m, &args.data)?;
            for (p, zi) in params.iter().zip(z) {
                values.insert(p.name.clone(), real(p, *zi));
            }
            runs.push(PlannedRun {
                id: runs.len() + 1,
                std: m.row,
                replicate: s + 1,
                coded: params
                    .iter()
                    .zip(z)
                    .map(|(p, v)| (p.name.clone(), *v))
                    .collect(),
                values,
                seed: (first_seed + s) as u64,
            });
        }
    }
    Ok(())
}

/// The factors of a test's runs: its conditions, then the free parameters in the scene.
pub fn run_factors(test: &str, params: &[Param]) -> Vec<Factor> {
    let mut f = condition_factors(test);
    for p in params {
        let mut x = factor(&p.name, &format!("scene:pairs[{}].{}", p.pair, p.key));
        x.low = p.low;
        x.high = p.high;
        f.push(x);
    }
    f
}

/// A measurement's conditions, as the test's condition factors take them.
pub fn cond_values(test: &str, m: &Measurement, data: &Path) -> Result<BTreeMap<String, f64>> {
    condition_factors(test)
        .iter()
        .map(|f| {
            m.conditions
                .get(&f.name)
                .map(|v| (f.name.clone(), *v))
                .ok_or_else(|| {
                    anyhow!(
                        "{}:{}: a {test} row needs `{}`",
                        data.display(),
                        m.row,
                        f.name
                    )
                })
        })
        .collect()
}

/// Conditions as `name=value,...`: a condition's label in messages and file names.
pub fn describe(c: &BTreeMap<String, f64>) -> String {
    c.iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(",")
}
