//! Step 3 of a per-condition calibration: direct runs at each condition's chosen setting,
//! and a step towards the measurement while their mean misses it, plus the running and
//! reading of plans that every step shares.

use super::surface::Solved;
use super::{CalibrateArgs, Iteration, Setup, describe};
use crate::study::lab_runs::{Dispatch, run_generated};
use crate::sweep::job::{Status, read_summary, run_dir};
use crate::sweep::plan::{Plan, PlannedRun};
use anyhow::{Result, bail};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use tilth_tools::calibrate::{Check, next_from_checks};
use tilth_tools::compare::mean_sd;

/// Checks every condition at its setting, all conditions together per iteration, and moves
/// each that misses by more than `--tolerance` %, up to `--refine` times. Returns each
/// condition's iterations (one at least).
pub(super) fn refine(setup: &Setup, report: &[Solved]) -> Result<Vec<Vec<Iteration>>> {
    let args = setup.args;
    let mut settings: Vec<Vec<f64>> = report.iter().map(|r| r.chosen.clone()).collect();
    let mut iterations: Vec<Vec<Iteration>> = vec![vec![]; report.len()];
    let mut active: Vec<bool> = vec![true; report.len()];
    let targets: Vec<f64> = report.iter().map(|r| r.m.value).collect();
    for it in 0..=args.refine {
        if !active.iter().any(|a| *a) {
            break;
        }
        let conditions = report.iter().map(|r| r.conds.clone()).collect::<Vec<_>>();
        let mut all = check(it, &active, &settings, &conditions, &targets, setup)?;
        for c in 0..report.len() {
            if !active[c] {
                continue;
            }
            let got = std::mem::take(&mut all[c]);
            if got.is_empty() {
                bail!(
                    "{}: every run at the chosen setting failed (see {})",
                    describe(&report[c].conds),
                    args.out.join(format!("check-{it}")).display()
                );
            }
            let (mean, sd) = mean_sd(&got);
            let target = report[c].m.value;
            let fit = &report[c].fit;
            let err = 100.0 * (mean - target) / target;
            iterations[c].push(Iteration {
                setting: settings[c].clone(),
                predicted: fit.predict(&settings[c]),
                values: got,
                mean,
                sd,
                error_pct: err,
            });
            if err.abs() <= args.tolerance || it == args.refine {
                active[c] = false;
                continue;
            }
            match next_setting(setup, &report[c], &settings[c], &iterations[c], mean) {
                Some(next) => settings[c] = next,
                None => active[c] = false,
            }
        }
    }
    Ok(iterations)
}

/// Where the next check of a condition goes, from `setting` whose checks' mean is `mean`;
/// None when the surface is flat there (no step can be taken).
///
/// A Newton step along the surface's gradient g (real units): d = -(mean - target) g / |g|^2.
/// With one parameter and checks at two settings or more, the step follows the line through
/// the checks themselves (measured where the calibration is, on the same seeds) rather than
/// the surface's slope there; see `next_from_checks`.
fn next_setting(
    setup: &Setup,
    cond: &Solved,
    setting: &[f64],
    iterations: &[Iteration],
    mean: f64,
) -> Option<Vec<f64>> {
    let params = &setup.params;
    let (fit, target) = (&cond.fit, cond.m.value);
    let z = fit.coding.code(setting);
    let g: Vec<f64> = fit
        .gradient_coded(&z)
        .iter()
        .enumerate()
        .map(|(i, d)| d / fit.coding.half(i))
        .collect();
    let g2: f64 = g.iter().map(|v| v * v).sum();
    if g2 == 0.0 {
        return None;
    }
    let miss = mean - target;
    let from_checks = if params.len() == 1 {
        let checks: Vec<Check> = iterations
            .iter()
            .map(|i| Check {
                setting: i.setting[0],
                mean: i.mean,
                runs: i.values.len(),
            })
            .collect();
        next_from_checks(&checks, target, g[0])
    } else {
        None
    };
    let step: Vec<f64> = match from_checks {
        Some((x, slope)) => {
            if !setup.args.quiet {
                eprintln!(
                    "{}: the checks' line ({slope:.4} per unit) puts the target at {x:.6}",
                    describe(&cond.conds)
                );
            }
            vec![x - setting[0]]
        }
        None => g.iter().map(|gi| -miss * gi / g2).collect(),
    };
    // A trust region: the surface is a fit to noisy runs, so no step goes further than
    // a quarter of any parameter's range (half a coded unit).
    let worst = step
        .iter()
        .zip(params)
        .map(|(d, p)| d.abs() / (0.25 * (p.high - p.low)))
        .fold(1.0, f64::max);
    Some(
        setting
            .iter()
            .zip(&step)
            .zip(params)
            .map(|((x, d), p)| (x + d / worst).clamp(p.low, p.high))
            .collect(),
    )
}

/// One direct check of every active condition at its setting: `--check-seeds` seeds (1001
/// on), in `DIR/check-IT`; with `--check-se`, more batches of as many seeds (in
/// `DIR/check-IT-K`) for each condition whose mean is not yet precise enough
/// ([`wants_more_seeds`]). Returns every condition's values (empty for inactive ones).
fn check(
    it: usize,
    active: &[bool],
    settings: &[Vec<f64>],
    conditions: &[BTreeMap<String, f64>],
    targets: &[f64],
    setup: &Setup,
) -> Result<Vec<Vec<f64>>> {
    let (args, params) = (setup.args, &setup.params);
    let batch = args.check_seeds.unwrap_or(args.seeds);
    let most = match args.check_se {
        Some(_) => args.max_check_seeds.unwrap_or(4 * batch),
        None => batch,
    };
    let mut got: Vec<Vec<f64>> = vec![vec![]; active.len()];
    let mut planned = vec![0usize; active.len()];
    let mut want = active.to_vec();
    for k in 0.. {
        let mut runs = vec![];
        for c in (0..active.len()).filter(|c| want[*c]) {
            for s in planned[c]..(planned[c] + batch).min(most) {
                let mut values = conditions[c].clone();
                for (p, v) in params.iter().zip(&settings[c]) {
                    values.insert(p.name.clone(), *v);
                }
                runs.push(PlannedRun {
                    id: runs.len() + 1,
                    std: c,
                    replicate: s + 1,
                    coded: BTreeMap::new(),
                    values,
                    seed: 1001 + s as u64,
                });
            }
        }
        if runs.is_empty() {
            break;
        }
        // The first batch keeps the name and place a check always had, so that an earlier
        // calibration's runs are reused.
        let name = match k {
            0 => format!("check-{it}"),
            k => format!("check-{it}-{k}"),
        };
        let plan = Plan::generated(
            &format!("{}-{name}", args.test),
            setup.text.clone(),
            Path::new("."),
            setup.factors.clone(),
            runs,
        )?;
        let values = run_plan(&plan, &args.out.join(&name), args, &setup.stop)?;
        let ran: Vec<usize> = (0..active.len()).filter(|c| want[*c]).collect();
        for c in ran {
            got[c].extend(
                plan.runs
                    .iter()
                    .zip(&values)
                    .filter(|(r, _)| r.std == c)
                    .filter_map(|(_, v)| *v),
            );
            planned[c] = (planned[c] + batch).min(most);
            want[c] = planned[c] < most && wants_more_seeds(&got[c], targets[c], args);
        }
    }
    Ok(got)
}

/// Whether a check's mean needs more seeds under `--check-se PCT`: its standard error is
/// above PCT % of the measurement (or unknown, with one run), and it does not already miss
/// by more than the tolerance plus two standard errors.
pub fn wants_more_seeds(values: &[f64], target: f64, args: &CalibrateArgs) -> bool {
    let Some(pct) = args.check_se else {
        return false;
    };
    let (mean, sd) = mean_sd(values);
    let Some(sd) = sd else {
        return true;
    };
    let se = 100.0 * sd / (values.len() as f64).sqrt() / target.abs();
    let err = 100.0 * (mean - target) / target;
    se > pct && err.abs() - 2.0 * se <= args.tolerance
}

/// Runs `plan` into `dir`; each run's value of the test's own observable (None when it
/// failed).
pub(super) fn run_plan(
    plan: &Plan,
    dir: &Path,
    args: &CalibrateArgs,
    stop: &Arc<AtomicBool>,
) -> Result<Vec<Option<f64>>> {
    let observable = crate::study::measurements::observable_of(&args.test)
        .map(|(o, _)| o)
        .ok_or_else(|| anyhow::anyhow!("--test {}: not a test", args.test))?;
    run_and_read(plan, dir, args, stop, |_| Some(observable))
}

/// Runs `plan` into `dir`; each run's value of `observable(run.std)` (None when the run
/// failed or has no such reading).
pub fn run_and_read<'a>(
    plan: &Plan,
    dir: &Path,
    args: &CalibrateArgs,
    stop: &Arc<AtomicBool>,
    observable: impl Fn(usize) -> Option<&'a str>,
) -> Result<Vec<Option<f64>>> {
    run_generated(plan, dir, &Dispatch::Local(args.cores), args.quiet, stop)?;
    Ok(plan
        .runs
        .iter()
        .map(|r| {
            let observable = observable(r.std)?;
            let s = read_summary(&run_dir(dir, r.id))?;
            if s.status != Status::Done {
                return None;
            }
            s.reduced.as_ref()?.get(observable)?.as_f64()
        })
        .collect())
}
