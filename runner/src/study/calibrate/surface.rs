//! Steps 1 and 2 of a per-condition calibration: the surface runs at every measured
//! condition, a quadratic response surface per condition, and the setting on it that hits
//! the measurement closest to the starting model.

use super::refine::run_plan;
use super::{Param, Setup, describe, param_form, push_surface_runs, surface_grid};
use crate::lab::model::{At, evaluate_at};
use crate::study::measurements::Measurement;
use crate::sweep::plan::{Plan, PlannedRun};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::Path;
use tilth_tools::rsm::{self, Anova, Data, FitOptions, Order, Table};

/// One condition after the surface step: what the refinement starts from and the report
/// shows.
pub(super) struct Solved {
    pub m: Measurement,
    pub conds: BTreeMap<String, f64>,
    pub fit: Anova,
    pub solution: rsm::Solution,
    /// The starting model's values at the condition.
    pub start: Vec<f64>,
    /// The setting the refinement checks first.
    pub chosen: Vec<f64>,
    /// Surface runs that failed, of `total`.
    pub failed: usize,
    pub total: usize,
}

/// Runs every condition's surface design as one plan in `DIR/surface`: the plan and each
/// run's value (None when it failed).
pub(super) fn run_surfaces(setup: &Setup) -> Result<(Plan, Vec<Option<f64>>)> {
    let args = setup.args;
    let grid = surface_grid(setup.params.len());
    let mut runs = vec![];
    for m in &setup.rows {
        push_surface_runs(&mut runs, &args.test, m, &grid, &setup.params, args)?;
    }
    let surface_plan = Plan::generated(
        &format!("{}-surface", args.test),
        setup.text.clone(),
        Path::new("."),
        setup.factors.clone(),
        runs,
    )?;
    let results = run_plan(&surface_plan, &args.out.join("surface"), args, &setup.stop)?;
    Ok((surface_plan, results))
}

/// Fits `m`'s surface from its runs in `plan` (`results`: their values) and solves it for
/// the measured value.
pub(super) fn solve_condition(
    setup: &Setup,
    m: &Measurement,
    plan: &Plan,
    results: &[Option<f64>],
) -> Result<Solved> {
    let (args, params) = (setup.args, &setup.params);
    let conds = super::cond_values(&args.test, m, &args.data)?;
    let mine: Vec<(&PlannedRun, Option<f64>)> = plan
        .runs
        .iter()
        .zip(results)
        .filter(|(r, _)| r.std == m.row)
        .map(|(r, v)| (r, *v))
        .collect();
    let ok: Vec<(&PlannedRun, f64)> = mine
        .iter()
        .filter_map(|(r, v)| v.map(|v| (*r, v)))
        .collect();
    let pts: Vec<(Vec<f64>, f64)> = ok
        .iter()
        .map(|(r, v)| (params.iter().map(|p| r.values[&p.name]).collect(), *v))
        .collect();
    let fit = surface(params, m, &pts, mine.len())?;
    let start: Vec<f64> = params
        .iter()
        .map(|p| {
            let form = param_form(&setup.model, p).expect("checked above");
            evaluate_at(form, At::test(&conds, &args.test))
        })
        .collect::<Result<_>>()?;
    let solution = rsm::solve(&fit, &describe(&conds), m.value, &[])?;
    let chosen = closest_to(&fit, &solution, &start);
    if !args.quiet {
        eprintln!("{}: {}", describe(&conds), solution.statement);
    }
    Ok(Solved {
        m: m.clone(),
        conds,
        fit,
        solution,
        start,
        chosen,
        failed: mine.len() - ok.len(),
        total: mine.len(),
    })
}

/// The setting that hits the target nearest `start` in coded units, sum_j (z_j - z0_j)^2
/// least: one measurement cannot separate parameters along a ridge, and the least change
/// that fits is the choice it can defend. Without one, the surface's closest approach, then
/// `start` itself.
fn closest_to(fit: &Anova, solution: &rsm::Solution, start: &[f64]) -> Vec<f64> {
    let zs = fit.coding.code(start);
    solution
        .settings
        .iter()
        .min_by(|a, b| {
            let d = |s: &rsm::Setting| {
                fit.coding
                    .code(&s.values)
                    .iter()
                    .zip(&zs)
                    .map(|(x, y)| (x - y).powi(2))
                    .sum::<f64>()
            };
            d(a).total_cmp(&d(b))
        })
        .or(solution.closest.as_ref())
        .map(|s| s.values.clone())
        .unwrap_or_else(|| start.to_vec())
}

/// A quadratic surface of one measurement's observable over the parameters, from the runs
/// that finished (`pts`: parameter values, value) out of `total`.
pub fn surface(
    params: &[Param],
    m: &Measurement,
    pts: &[(Vec<f64>, f64)],
    total: usize,
) -> Result<Anova> {
    let mut columns: Vec<(&str, Vec<f64>)> = params
        .iter()
        .enumerate()
        .map(|(j, p)| (p.name.as_str(), pts.iter().map(|(x, _)| x[j]).collect()))
        .collect();
    columns.push((m.observable.as_str(), pts.iter().map(|(_, v)| *v).collect()));
    let origin = format!("{} surface at {}", m.test, describe(&m.conditions));
    let table = Table::from_columns(&origin, &columns);
    let names: Vec<String> = params.iter().map(|p| p.name.clone()).collect();
    let ranges: Vec<(f64, f64)> = params.iter().map(|p| (p.low, p.high)).collect();
    let data = Data::from_table(&table, &names, &m.observable, Some(&ranges))?;
    rsm::fit(
        &data,
        FitOptions {
            order: Order::Quadratic,
            curvature: false,
            backward: None,
        },
    )
    .with_context(|| format!("{origin}: {} of {total} runs finished", pts.len()))
}
