//! The variants of the model a diagnosis simulates, their runs, and the rows usable in all
//! of them.

use super::{DiagnoseArgs, Inputs};
use crate::study::calibrate::Param;
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

/// The variant of free parameter `p` raised by `fraction` of its range: `param-PAIR.KEY`
/// at `--param-step`, `param-PAIR.KEY-step-F` at another fraction F (each its own runs).
pub(super) fn param_variant(
    args: &DiagnoseArgs,
    inputs: &Inputs,
    p: &Param,
    fraction: f64,
) -> Result<Variant> {
    let h = fraction * (p.high - p.low);
    let key = format!("{}.{}", p.pair, p.key);
    let name = if fraction == args.param_step {
        format!("param-{key}")
    } else {
        format!("param-{key}-step-{}", crate::sweep::plan::num(fraction))
    };
    let models_dir = args.out.join("models");
    let path = variant(&inputs.model, &inputs.text, &models_dir, &name, |d| {
        add_to(d, &key, h)
    })?;
    Ok(Variant {
        name,
        path,
        step: h,
    })
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
        variants.push(param_variant(args, inputs, p, args.param_step)?);
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
        variants.push(probe_variant(args, inputs, key, *step, false)?);
    }
    Ok(variants)
}

/// The model with held parameter `key` raised by `step`: `probe-KEY`, or once its step was
/// lengthened (`steps.rs`) `probe-KEY-step-STEP`.
pub(super) fn probe_variant(
    args: &DiagnoseArgs,
    inputs: &Inputs,
    key: &str,
    step: f64,
    lengthened: bool,
) -> Result<Variant> {
    let name = if lengthened {
        format!("probe-{key}-step-{}", crate::sweep::plan::num(step))
    } else {
        format!("probe-{key}")
    };
    let models_dir = args.out.join("models");
    let path = variant(&inputs.model, &inputs.text, &models_dir, &name, |d| {
        add_to(d, key, step)
    })?;
    Ok(Variant { name, path, step })
}

/// What the runs of every variant gave, indexed by variant and then by row.
pub(super) struct Simulations {
    /// The mean of a row's replicates; None unless all of them finished.
    pub means: Vec<Vec<Option<f64>>>,
    /// The values of a row's replicates that finished, seed by seed.
    pub values: Vec<Vec<Vec<f64>>>,
    /// Each row's scatter, the standard deviation of its replicates, pooled over the variants
    /// (each a small step from "base", so they share it), with its degrees of freedom.
    pub scatter: Vec<Option<(f64, f64)>>,
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
    let mut sims = Simulations {
        means: vec![],
        values: vec![],
        scatter: vec![],
        problems: BTreeMap::new(),
    };
    for (k, Variant { name, .. }) in variants.iter().enumerate() {
        if !args.lab.quiet {
            eprintln!("variant {} of {}: {name}", k + 1, variants.len());
        }
        let runs = simulate(rows, &hows[k], &stop)?;
        sims.put(k, name, runs, args.replicates);
    }
    sims.pool(args.replicates);
    Ok(sims)
}

/// Runs variant `k` (not "base") again, its model file changed, and puts its runs in place.
pub(super) fn rerun_variant(
    args: &DiagnoseArgs,
    set: &[TestSetting],
    rows: &[Measurement],
    variant: &Variant,
    k: usize,
    sims: &mut Simulations,
) -> Result<()> {
    let stop = execute::stop_on_signals()?;
    let out = args.out.join("runs").join(&variant.name);
    let how = Simulate {
        model: &variant.path,
        data: &args.data,
        out: &out,
        replicates: args.replicates,
        first_seed: 1 + args.replicates as u64,
        lab: &args.lab,
        set,
    };
    let runs = simulate(rows, &how, &stop)?;
    sims.put(k, &variant.name, runs, args.replicates);
    sims.pool(args.replicates);
    Ok(())
}

impl Simulations {
    /// Puts variant `k`'s runs (`simulate`'s: values and problems per row) in place, or
    /// after the others when it is new. A row's mean needs all `replicates` runs; a failed
    /// run is reported and its row dropped by `usable_rows`.
    fn put(&mut self, k: usize, name: &str, runs: Vec<(Vec<f64>, Vec<String>)>, replicates: usize) {
        for (i, (_, why)) in runs.iter().enumerate() {
            if let Some(first) = why.first() {
                self.problems
                    .entry(i)
                    .or_insert_with(|| format!("{name}, {first}"));
            }
        }
        let means = runs
            .iter()
            .map(|(v, _)| (v.len() == replicates).then(|| mean_sd(v).0))
            .collect();
        let values = runs.into_iter().map(|(v, _)| v).collect();
        if k < self.means.len() {
            self.means[k] = means;
            self.values[k] = values;
        } else {
            self.means.push(means);
            self.values.push(values);
        }
    }

    /// Each row's scatter pooled over the variants.
    fn pool(&mut self, replicates: usize) {
        let rows = self.values.first().map_or(0, Vec::len);
        self.scatter = (0..rows)
            .map(|i| pooled_scatter(self.values.iter().map(|v| v[i].as_slice()), replicates))
            .collect();
    }
}

/// The standard deviation of the runs pooled over groups, each group's runs about its own
/// mean: sqrt(sum (x - mean_g)^2 / sum (n_g - 1)), over the groups with all `replicates`
/// runs, and the degrees of freedom it is credited with. With R = 4 one group's scatter has
/// 3, and a residual standardised by it has Student's t tails (variance 3) that inflate
/// every test. The first group ("base", seeds 1..R) is independent of the others, which
/// share seeds R+1..2R (common random numbers), so their scatters are not independent of
/// each other: the credit is that of two groups, 2 (R - 1), a lower bound; the estimate
/// itself averages them all.
fn pooled_scatter<'a>(
    groups: impl Iterator<Item = &'a [f64]>,
    replicates: usize,
) -> Option<(f64, f64)> {
    let (mut squares, mut dof, mut full) = (0.0, 0.0, 0usize);
    for g in groups.filter(|g| g.len() == replicates && g.len() > 1) {
        let mean = g.iter().sum::<f64>() / g.len() as f64;
        squares += g.iter().map(|x| (x - mean).powi(2)).sum::<f64>();
        dof += (g.len() - 1) as f64;
        full += 1;
    }
    let credit = full.min(2) as f64 * replicates.saturating_sub(1) as f64;
    (dof > 0.0).then(|| ((squares / dof).sqrt(), credit))
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
/// sqrt(uncertainty^2 + scatter^2 / replicates), the scatter pooled over the variants.
pub(super) fn usable_rows(
    args: &DiagnoseArgs,
    rows: &[Measurement],
    sims: &Simulations,
) -> Result<Usable> {
    let mut used = vec![];
    let mut dropped = vec![];
    for (i, m) in rows.iter().enumerate() {
        let se = std_error(sims.scatter[i].map(|s| s.0), args.replicates, m.uncertainty);
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

#[cfg(test)]
mod tests {
    use super::pooled_scatter;

    #[test]
    fn the_pooled_scatter_is_each_group_about_its_own_mean() {
        // Groups {1, 3} and {10, 14}: squares 2 + 8 over 1 + 1 degrees of freedom; a group
        // with a run missing is left out.
        let groups: [&[f64]; 3] = [&[1.0, 3.0], &[10.0, 14.0], &[5.0]];
        let (sd, dof) = pooled_scatter(groups.into_iter(), 2).unwrap();
        assert!((sd - 5f64.sqrt()).abs() < 1e-12, "{sd}");
        assert_eq!(dof, 2.0);
        // Ten groups of four are credited with two groups' 6, not 30.
        let four: Vec<Vec<f64>> = (0..10).map(|k| vec![0.0, 1.0, 2.0, f64::from(k)]).collect();
        let (_, dof) = pooled_scatter(four.iter().map(Vec::as_slice), 4).unwrap();
        assert_eq!(dof, 6.0);
        assert!(pooled_scatter([&[2.0][..]].into_iter(), 1).is_none());
    }
}
