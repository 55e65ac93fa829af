//! The variants of the model a diagnosis simulates, their runs, and the rows usable in all
//! of them.

use super::{DiagnoseArgs, Inputs};
use crate::study::lab_runs::{Simulate, TestSetting, prefetch, simulate};
use crate::study::measurements::Measurement;
use crate::study::model_edit::{add_to, switch_on, variant};
use crate::sweep::execute;
use anyhow::{Result, bail};
use std::collections::BTreeMap;
use std::path::PathBuf;
use tilth_tools::compare::{mean_sd, std_error};

/// One variant of the model: its name (its runs go to `DIR/runs/<name>/`), its model file in
/// `DIR/models/`, and the step it is raised by from the base, the `h` of its finite
/// difference (1 for the base itself).
pub(super) struct Variant {
    pub name: String,
    pub path: PathBuf,
    pub step: f64,
}

/// Writes every variant's model file, all checked before any run: "base", "base-fd", each
/// free parameter raised by `--param-step` of its range, each candidate switched on at its
/// step, each probe raised by its step, in that order (the order of the columns).
pub(super) fn write_variants(args: &DiagnoseArgs, inputs: &Inputs) -> Result<Vec<Variant>> {
    let Inputs {
        model,
        text,
        params,
        names,
        probes,
        ..
    } = inputs;
    let models_dir = args.out.join("models");
    std::fs::create_dir_all(&models_dir)?;
    // "base" (seeds 1..R) gives the residuals; "base-fd" (seeds R+1..2R) is the other end
    // of every finite difference, so that the sensitivities' noise is independent of the
    // residuals' (sharing runs would correlate them and fake a signal for every candidate).
    let base = variant(model, text, &models_dir, "base", |_| Ok(()))?;
    let mut variants = vec![
        Variant {
            name: "base".into(),
            path: base.clone(),
            step: 1.0,
        },
        Variant {
            name: "base-fd".into(),
            path: base,
            step: 1.0,
        },
    ];
    for p in params {
        let h = args.param_step * (p.high - p.low);
        let name = format!("param-{}.{}", p.pair, p.key);
        let path = variant(model, text, &models_dir, &name, |d| {
            add_to(d, &format!("{}.{}", p.pair, p.key), h)
        })?;
        variants.push(Variant {
            name,
            path,
            step: h,
        });
    }
    for n in names {
        let step = model.file.candidates[n].step;
        let name = format!("candidate-{n}");
        let path = variant(model, text, &models_dir, &name, |d| {
            switch_on(d, model, n, step)
        })?;
        variants.push(Variant { name, path, step });
    }
    for (key, step) in probes {
        let name = format!("probe-{key}");
        let path = variant(model, text, &models_dir, &name, |d| add_to(d, key, *step))?;
        variants.push(Variant {
            name,
            path,
            step: *step,
        });
    }
    Ok(variants)
}

/// What the runs of every variant gave, indexed by variant and then by row.
pub(super) struct Simulations {
    /// The mean of a row's replicates; None unless all of them finished.
    pub means: Vec<Vec<Option<f64>>>,
    /// The values of a row's replicates that finished, seed by seed.
    pub values: Vec<Vec<Vec<f64>>>,
    /// The standard deviation of each row's replicates in "base", the simulation's scatter.
    pub base_scatter: Vec<Option<f64>>,
    /// The first reason a row has no value in some variant.
    pub problems: BTreeMap<usize, String>,
}

/// Simulates every row in every variant, `--replicates` seeds each: "base" with seeds
/// 1..R, every other variant with R+1..2R, so that each finite difference pairs runs of the
/// same seed (common random numbers).
pub(super) fn simulate_variants(
    args: &DiagnoseArgs,
    set: &[TestSetting],
    rows: &[Measurement],
    variants: &[Variant],
) -> Result<Simulations> {
    let stop = execute::stop_on_signals()?;
    let outs: Vec<PathBuf> = variants
        .iter()
        .map(|v| args.out.join("runs").join(&v.name))
        .collect();
    // With --slurm every variant's runs go into one job array.
    let hows: Vec<Simulate> = variants
        .iter()
        .zip(&outs)
        .enumerate()
        .map(|(k, (v, out))| Simulate {
            model: &v.path,
            data: &args.data,
            out,
            replicates: args.replicates,
            first_seed: if k == 0 {
                1
            } else {
                1 + args.replicates as u64
            },
            lab: &args.lab,
            set,
        })
        .collect();
    prefetch(rows, &hows)?;
    let mut means: Vec<Vec<Option<f64>>> = vec![];
    let mut values: Vec<Vec<Vec<f64>>> = vec![];
    let mut problems: BTreeMap<usize, String> = BTreeMap::new();
    let mut base_scatter: Vec<Option<f64>> = vec![];
    for (k, Variant { name, .. }) in variants.iter().enumerate() {
        if !args.lab.quiet {
            eprintln!("variant {} of {}: {name}", k + 1, variants.len());
        }
        let sims = simulate(rows, &hows[k], &stop)?;
        if k == 0 {
            base_scatter = sims.iter().map(|(v, _)| mean_sd(v).1).collect();
        }
        // Only replicates that finished in every variant would be fairer; a failed run
        // is reported and its row dropped by `usable_rows`.
        means.push(
            sims.iter()
                .map(|(v, _)| {
                    if v.len() == args.replicates {
                        Some(mean_sd(v).0)
                    } else {
                        None
                    }
                })
                .collect(),
        );
        for (i, (_, why)) in sims.iter().enumerate() {
            if let Some(first) = why.first() {
                problems
                    .entry(i)
                    .or_insert_with(|| format!("{name}, {first}"));
            }
        }
        values.push(sims.into_iter().map(|(v, _)| v).collect());
    }
    Ok(Simulations {
        means,
        values,
        base_scatter,
        problems,
    })
}

/// The rows a diagnosis uses and those it drops.
pub(super) struct Usable {
    /// The rows with a value in every variant and a standard error, as (index in `rows`,
    /// standard error).
    pub used: Vec<(usize, f64)>,
    /// Why each other row was dropped.
    pub dropped: Vec<String>,
}

/// Sorts the rows into used and dropped. The standard error is
/// sqrt(uncertainty^2 + scatter^2 / replicates), the scatter that of "base".
pub(super) fn usable_rows(
    args: &DiagnoseArgs,
    rows: &[Measurement],
    sims: &Simulations,
) -> Result<Usable> {
    let mut used = vec![];
    let mut dropped = vec![];
    for (i, m) in rows.iter().enumerate() {
        let se = std_error(sims.base_scatter[i], args.replicates, m.uncertainty);
        if sims.means.iter().any(|v| v[i].is_none()) {
            dropped.push(format!(
                "row {}: a run failed ({})",
                m.row,
                sims.problems.get(&i).map_or("no value", String::as_str)
            ));
        } else if se.is_none() {
            dropped.push(format!(
                "row {}: no uncertainty and no replicate scatter",
                m.row
            ));
        } else {
            used.push((i, se.unwrap()));
        }
    }
    if used.is_empty() {
        bail!(
            "no row is usable: {} (give uncertainties or --replicates 2 or more)",
            dropped.join("; ")
        );
    }
    Ok(Usable { used, dropped })
}
