//! `tilth diagnose --model M.toml --data D.csv --out DIR`: which of the model's candidate
//! effects (`[candidates.NAME]` in the model file) explains where it fails.
//!
//! Runs, all with the same seeds (common random numbers) and `--replicates` of them:
//! the model as it is; the model with each free parameter (`--param PAIR.KEY=LOW:HIGH`)
//! raised by `--param-step` (default 5 %) of its range; the model with each candidate
//! switched on at its `step`.
//! Each variant is a model file in `DIR/models/` and a resumable sweep per test in
//! `DIR/runs/<variant>/`. From the row means: residuals, the free parameters' Jacobian and
//! each candidate's sensitivity, standardised by each row's standard error
//! (sqrt(uncertainty^2 + scatter^2 / replicates)); from the per-seed slopes, the noise of
//! every finite difference (the candidates' variances, the free parameters' covariances);
//! then the score test of [`tilth_tools::diagnose`]. Writes `DIR/diagnosis.json` (`candidates` best first: `name`,
//! `statistic`, `p_value`, `strength`, `predicted_rmse_drop`, `identifiable`, ...) and
//! `DIR/diagnosis.md`, the ranking in words.

use super::calibrate::{Param, parse_param};
use super::compare::{LabRunArgs, Simulate, mean_sd, prefetch, simulate, std_error};
use super::measurements::{Measurement, check_against_model, read_measurements};
use super::model_edit::{add_to, switch_on, values_of, variant};
use crate::lab::model::Model;
use crate::sweep::execute;
use anyhow::{Result, bail};
use clap::Args;
use nalgebra::DMatrix;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::diagnose::{Candidate, JacobianNoise, Score, score_tests};

pub mod file;
mod fit_first;
mod refit;
mod report;

use fit_first::{fit_first, fit_summary};

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Model file with `[candidates.NAME]` sections.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements (CSV).
    #[arg(long)]
    pub data: PathBuf,
    #[arg(long)]
    pub out: PathBuf,
    /// A free parameter the calibration may move, PAIR.KEY=LOW:HIGH (repeatable): what it
    /// can absorb is removed before the candidates are tested.
    #[arg(long = "param")]
    pub params: Vec<String>,
    /// Only these candidates (default: all in the model file).
    #[arg(long, value_delimiter = ',')]
    pub candidates: Vec<String>,
    /// A model parameter the diagnosis holds fixed, weighed against the candidates,
    /// PAIR.KEY=STEP (repeatable): its sensitivity (the model with it raised by STEP) takes
    /// part in the verdict as a candidate would, so a misfit that a miscalibrated parameter
    /// explains is not blamed on an effect (e.g. soil-soil.surface_energy=0.05).
    #[arg(long = "probe")]
    pub probes: Vec<String>,
    /// Runs per row and variant, with seeds 1, 2, ... shared by every variant.
    #[arg(long, default_value_t = 3)]
    pub replicates: usize,
    /// Each free parameter's finite-difference step, as a fraction of its range. Longer
    /// steps lift the parameter's effect above the runs' chaos, but measure a secant: on the
    /// discovery proof's draws, 25 % let rolling friction absorb hidden plastic adhesion (found
    /// in 1 draw of 8, against 7 at 5 %), and 2 % left it within its noise in 19 diagnoses of
    /// 24 (docs/discovery-proof.md, "The free parameters' step in `diagnose`"). A step that leaves
    /// a parameter within its noise cannot take out a misfit of that parameter: with rolling
    /// friction 0.05 off and no effect hidden, 5 % called a candidate significant in 8 seeds
    /// of 20, 10 % in none ("A free parameter off"). Use 10 % when the free parameters have
    /// not been fitted to the data, or --fit-first.
    #[arg(long, default_value_t = 0.05)]
    pub param_step: f64,
    /// Fit the free parameters to the data first (`tilth fit`, into DIR/fit/) and score the
    /// candidates at the fitted model: the restricted estimate of the score test. A
    /// miscalibrated free parameter is then not blamed on a candidate, but an effect it can
    /// partly mimic is absorbed too (docs/discovery-proof.md, "A free parameter off").
    #[arg(long)]
    pub fit_first: bool,
    /// Give the linear verdict only. By default the free parameters alone and then each
    /// contender with them (a candidate or probe the linear verdict kept or scored at a
    /// corrected p under 0.1) are fitted on simulations (`tilth fit`, into DIR/refit/), and
    /// the verdict is the fits': the best needed contender within the noise is named when
    /// its rivals fit worse row by row, ambiguous with those that do not (docs/discovery.md,
    /// "Refitting the contenders"). That costs one fit per contender.
    #[arg(long)]
    pub no_refit: bool,
    /// Levenberg-Marquardt iterations, at most, of each fit (--fit-first and the refit; see
    /// `tilth fit`).
    #[arg(long, default_value_t = 3)]
    pub fit_iterations: usize,
    /// Corrected p-value below which a candidate is called significant.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Only these tests (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub tests: Vec<String>,
    #[command(flatten)]
    pub lab: LabRunArgs,
}

/// The linear recalibration of one free parameter that the "after recalibration" numbers
/// assume, as written.
#[derive(Debug, Clone, Serialize)]
pub struct Recalibrated {
    /// `PAIR.KEY`.
    pub parameter: String,
    /// The numbers the model holds for it (one per interpolation point or case).
    pub now: Vec<f64>,
    /// The least-squares shift, in the parameter's unit, added to each.
    pub shift: f64,
    pub after: Vec<f64>,
    /// The range given with `--param`, over which its sensitivity was measured.
    pub range: [f64; 2],
    pub within_range: bool,
    /// Whether its effect on the measurements stands above the noise of its estimate.
    pub measurable: bool,
}

/// A candidate's result, as written.
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosed {
    #[serde(flatten)]
    pub score: Score,
    pub significant: bool,
    /// Predicted RMSE drop per observable, in its unit, after adding the candidate at its
    /// estimated strength and recalibrating the free parameters.
    pub predicted_rmse_drop: BTreeMap<String, f64>,
    pub description: Option<String>,
    /// A parameter held fixed (`--probe`), not an effect.
    pub held_parameter: bool,
}

/// The name a `--probe PAIR.KEY` goes by among the candidates.
pub const HELD: &str = "held:";

/// `PAIR.KEY=STEP` of `--probe`.
fn parse_probe(s: &str) -> Result<(String, f64)> {
    let (path, step) = s.split_once('=').unwrap_or((s, ""));
    let step: f64 = step.trim().parse().map_err(|_| {
        anyhow::anyhow!("--probe {s:?}: expected PAIR.KEY=STEP, e.g. soil-soil.surface_energy=0.05")
    })?;
    if !(step.is_finite() && step != 0.0 && path.contains('.')) {
        bail!(
            "--probe {s:?}: STEP {step} is out of range: allowed a non-zero number, with PAIR.KEY before it"
        );
    }
    Ok((path.trim().to_string(), step))
}

/// Every candidate asked for exists in the model file with a usable step and strength.
fn check_candidates(names: &[String], model: &Model, path: &std::path::Path) -> Result<()> {
    if names.is_empty() {
        bail!(
            "{}: no [candidates.NAME] sections: nothing to diagnose (see docs/discovery.md)",
            path.display()
        );
    }
    for n in names {
        let Some(c) = model.file.candidates.get(n) else {
            bail!(
                "--candidates: `{n}` is not in {}; it has {}",
                path.display(),
                model
                    .file
                    .candidates
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        };
        if !(c.step.is_finite() && c.step != 0.0) {
            bail!(
                "{}: candidates.{n}.step = {} is out of range: allowed a non-zero number",
                path.display(),
                c.step
            );
        }
        if c.strength.is_empty() {
            bail!(
                "{}: candidates.{n}.strength is empty: name at least one PAIR.KEY",
                path.display()
            );
        }
    }
    Ok(())
}

pub fn diagnose(args: &DiagnoseArgs, out: &mut dyn Write) -> Result<()> {
    let set = args.lab.set.parse()?;
    if args.replicates < 2 {
        bail!(
            "--replicates {} is out of range: allowed 2 or more (the noise of every finite difference is estimated from the replicates; without it any candidate could look significant)",
            args.replicates
        );
    }
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        bail!("--alpha {} is out of range: allowed (0, 1)", args.alpha);
    }
    if args.fit_iterations == 0 {
        bail!("--fit-iterations 0 is out of range: allowed 1 or more (with --fit-first)");
    }
    if !(args.param_step > 0.0 && args.param_step <= 0.5) {
        bail!(
            "--param-step {} is out of range: allowed (0, 0.5], a fraction of each --param's range",
            args.param_step
        );
    }
    let model_path = std::path::absolute(&args.model)?;
    let model = Model::load(&model_path)?;
    let text = std::fs::read_to_string(&model_path)?;
    let rows: Vec<Measurement> = read_measurements(&args.data)?
        .into_iter()
        .filter(|m| args.tests.is_empty() || args.tests.contains(&m.test))
        .collect();
    if rows.is_empty() {
        bail!("{}: no rows of the tests asked for", args.data.display());
    }
    check_against_model(&rows, &model, &args.data)?;
    let params: Vec<Param> = args
        .params
        .iter()
        .map(|p| parse_param(p))
        .collect::<Result<_>>()?;
    let names: Vec<String> = if args.candidates.is_empty() {
        model.file.candidates.keys().cloned().collect()
    } else {
        args.candidates.clone()
    };
    check_candidates(&names, &model, &args.model)?;
    let probes: Vec<(String, f64)> = args
        .probes
        .iter()
        .map(|p| parse_probe(p))
        .collect::<Result<_>>()?;
    // With --fit-first, the restricted estimate: the candidates are scored where the model
    // without them fits the data best.
    let (model, text, fitted) = match fit_first(args, &rows)? {
        Some(path) => (
            Model::load(&path)?,
            std::fs::read_to_string(&path)?,
            Some(path),
        ),
        None => (model, text, None),
    };

    // The variants, written and checked before any run.
    let models_dir = args.out.join("models");
    std::fs::create_dir_all(&models_dir)?;
    // "base" (seeds 1..R) gives the residuals; "base-fd" (seeds R+1..2R) is the other end
    // of every finite difference, so that the sensitivities' noise is independent of the
    // residuals' (sharing runs would correlate them and fake a signal for every candidate).
    let base = variant(&model, &text, &models_dir, "base", |_| Ok(()))?;
    let mut variants: Vec<(String, PathBuf, f64)> = vec![
        ("base".into(), base.clone(), 1.0),
        ("base-fd".into(), base, 1.0),
    ];
    for p in &params {
        let h = args.param_step * (p.high - p.low);
        let name = format!("param-{}.{}", p.pair, p.key);
        let path = variant(&model, &text, &models_dir, &name, |d| {
            add_to(d, &format!("{}.{}", p.pair, p.key), h)
        })?;
        variants.push((name, path, h));
    }
    for n in &names {
        let step = model.file.candidates[n].step;
        let name = format!("candidate-{n}");
        let path = variant(&model, &text, &models_dir, &name, |d| {
            switch_on(d, &model, n, step)
        })?;
        variants.push((name, path, step));
    }
    for (key, step) in &probes {
        let name = format!("probe-{key}");
        let path = variant(&model, &text, &models_dir, &name, |d| add_to(d, key, *step))?;
        variants.push((name, path, *step));
    }
    // The candidates' columns, then the probes'.
    let names: Vec<String> = names
        .into_iter()
        .chain(probes.iter().map(|(k, _)| format!("{HELD}{k}")))
        .collect();

    let stop = execute::stop_on_signals()?;
    let outs: Vec<std::path::PathBuf> = variants
        .iter()
        .map(|(name, _, _)| args.out.join("runs").join(name))
        .collect();
    // With --slurm every variant's runs go into one job array.
    let hows: Vec<Simulate> = variants
        .iter()
        .zip(&outs)
        .enumerate()
        .map(|(k, ((_, path, _), out))| Simulate {
            model: path,
            data: &args.data,
            out,
            replicates: args.replicates,
            first_seed: if k == 0 {
                1
            } else {
                1 + args.replicates as u64
            },
            lab: &args.lab,
            set: &set,
        })
        .collect();
    prefetch(&rows, &hows)?;
    let mut means: Vec<Vec<Option<f64>>> = vec![];
    let mut values: Vec<Vec<Vec<f64>>> = vec![];
    // The first reason a row has no value in some variant.
    let mut problems: BTreeMap<usize, String> = BTreeMap::new();
    let mut base_scatter: Vec<Option<f64>> = vec![];
    for (k, (name, _, _)) in variants.iter().enumerate() {
        if !args.lab.quiet {
            eprintln!("variant {} of {}: {name}", k + 1, variants.len());
        }
        let sims = simulate(&rows, &hows[k], &stop)?;
        if k == 0 {
            base_scatter = sims.iter().map(|(v, _)| mean_sd(v).1).collect();
        }
        // Only replicates that finished in every variant would be fairer; a failed run
        // is reported and its row dropped below.
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

    // Rows usable in every variant, with a standard error.
    let mut used = vec![];
    let mut dropped = vec![];
    for (i, m) in rows.iter().enumerate() {
        let se = std_error(base_scatter[i], args.replicates, m.uncertainty);
        if means.iter().any(|v| v[i].is_none()) {
            dropped.push(format!(
                "row {}: a run failed ({})",
                m.row,
                problems.get(&i).map_or("no value", String::as_str)
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
    let m = used.len();
    let residual: Vec<f64> = used
        .iter()
        .map(|&(i, s)| (rows[i].value - means[0][i].unwrap()) / s)
        .collect();
    // Finite differences against base-fd (variant 1), paired by seed.
    let sens = |v: usize| -> Vec<f64> {
        let h = variants[v].2;
        used.iter()
            .map(|&(i, s)| (means[v][i].unwrap() - means[1][i].unwrap()) / h / s)
            .collect()
    };
    // Each row's slopes seed by seed (all are differences against base-fd): their scatter
    // is the noise of the finite differences.
    let seed_slopes = |v: usize| -> Vec<Vec<f64>> {
        let h = variants[v].2;
        used.iter()
            .map(|&(i, s)| {
                (values[v][i].iter().zip(&values[1][i]))
                    .map(|(a, b)| (a - b) / h / s)
                    .collect()
            })
            .collect()
    };
    // Variance of each row's mean difference.
    let sens_var = |v: usize| -> Vec<f64> {
        seed_slopes(v)
            .iter()
            .map(|d| mean_sd(d).1.map_or(0.0, |sd| sd * sd / d.len() as f64))
            .collect()
    };
    // The free parameters' slopes' covariances, and the candidates' with them.
    let jacobian_noise = JacobianNoise::from_seeds(
        &(0..params.len())
            .map(|c| seed_slopes(2 + c))
            .collect::<Vec<_>>(),
        &(0..names.len())
            .map(|k| seed_slopes(2 + params.len() + k))
            .collect::<Vec<_>>(),
    );
    // Column by column (each sensitivity once, not once per element).
    let columns: Vec<f64> = (0..params.len()).flat_map(|c| sens(2 + c)).collect();
    let x = DMatrix::from_column_slice(m, params.len(), &columns);
    let candidates: Vec<Candidate> = names
        .iter()
        .enumerate()
        .map(|(k, n)| Candidate {
            name: n.clone(),
            sensitivity: sens(2 + params.len() + k),
            sensitivity_var: sens_var(2 + params.len() + k),
        })
        .collect();
    let fit_first = match &fitted {
        Some(_) => Some(fit_summary(&args.out)?),
        None => None,
    };
    let scores = score_tests(&residual, &x, &jacobian_noise, &candidates);
    let verdict = tilth_tools::diagnose::verdict::verdict(
        &residual,
        &x,
        &jacobian_noise,
        &candidates,
        &scores,
        args.alpha,
    );
    let absorbed = tilth_tools::diagnose::absorbed(&residual, &x);
    let shift = tilth_tools::diagnose::recalibration(&residual, &x);
    let doc: toml_edit::DocumentMut = text.parse()?;
    let recalibrated: Vec<Recalibrated> = params
        .iter()
        .enumerate()
        .map(|(c, p)| {
            let path = format!("{}.{}", p.pair, p.key);
            let now = values_of(&doc, &path)?;
            let after: Vec<f64> = now.iter().map(|v| v + shift[c]).collect();
            Ok(Recalibrated {
                within_range: after.iter().all(|v| (p.low..=p.high).contains(v)),
                measurable: tilth_tools::diagnose::measurable(&sens(2 + c), &sens_var(2 + c)),
                parameter: path,
                now,
                shift: shift[c],
                after,
                range: [p.low, p.high],
            })
        })
        .collect::<Result<_>>()?;

    // Per observable RMSE after recalibration, and after adding each candidate.
    let rmse_by_obs = |z: &[f64]| -> BTreeMap<String, f64> {
        let mut acc: BTreeMap<String, (f64, usize)> = BTreeMap::new();
        for (r, &(i, s)) in used.iter().enumerate() {
            let e = acc.entry(rows[i].observable.clone()).or_default();
            e.0 += (z[r] * s).powi(2);
            e.1 += 1;
        }
        acc.into_iter()
            .map(|(k, (ss, n))| (k, (ss / n as f64).sqrt()))
            .collect()
    };
    let before = rmse_by_obs(&absorbed);
    let now = rmse_by_obs(&residual);
    let diagnosed: Vec<Diagnosed> = scores
        .into_iter()
        .map(|s| {
            let after_z: Vec<f64> = absorbed
                .iter()
                .zip(&s.fitted_change)
                .map(|(a, f)| a - f)
                .collect();
            let after = rmse_by_obs(&after_z);
            Diagnosed {
                significant: s.identifiable && s.p_value < args.alpha,
                predicted_rmse_drop: before
                    .iter()
                    .map(|(k, b)| (k.clone(), b - after[k]))
                    .collect(),
                description: match s.name.strip_prefix(HELD) {
                    Some(key) => Some(format!("the model's {key}, held fixed")),
                    None => model.file.candidates[&s.name].description.clone(),
                },
                held_parameter: s.name.starts_with(HELD),
                score: s,
            }
        })
        .collect();
    let refitted = {
        let step_of = |d: &Diagnosed| -> Result<(f64, Vec<f64>)> {
            match d.score.name.strip_prefix(HELD) {
                Some(key) => {
                    let step = probes.iter().find(|(k, _)| k == key).map_or(0.0, |p| p.1);
                    Ok((step, values_of(&doc, key)?))
                }
                None => Ok((model.file.candidates[&d.score.name].step, vec![])),
            }
        };
        refit::refit(args, &rows, &verdict, &diagnosed, &step_of)?
    };
    let (verdict, linear_verdict, refits) = match refitted {
        Some((v, refits)) => (v, Some(verdict), Some(refits)),
        None => (verdict, None, None),
    };
    let json = serde_json::json!({
        "model": args.model.display().to_string(),
        "data": args.data.display().to_string(),
        "replicates": args.replicates,
        "coarse": args.lab.coarse,
        "set": args.lab.set.set,
        "alpha": args.alpha,
        "free_parameters": params,
        "param_step": args.param_step,
        "fitted_model": fitted.as_ref().map(|p| p.display().to_string()),
        "fit_first": fit_first,
        "rows_used": m,
        "rows_dropped": dropped,
        "rmse_now": now,
        "rmse_after_recalibration": before,
        "recalibration": recalibrated,
        "candidates": diagnosed,
        "probes": probes.iter().map(|(k, h)| serde_json::json!({"parameter": k, "step": h})).collect::<Vec<_>>(),
        "verdict": verdict,
        "linear_verdict": linear_verdict,
        "refit": refits,
        // Standardised, one number per entry of "rows": what `tilth next` extends.
        "columns": {
            "free": params.iter().enumerate().map(|(c, p)| (format!("{}.{}", p.pair, p.key), x.column(c).iter().copied().collect::<Vec<_>>())).collect::<BTreeMap<_, _>>(),
            "candidates": candidates.iter().map(|c| (c.name.clone(), serde_json::json!({"sensitivity": c.sensitivity, "variance": c.sensitivity_var}))).collect::<BTreeMap<_, _>>(),
        },
        "rows": used.iter().enumerate().map(|(r, &(i, se))| serde_json::json!({
            "row": rows[i].row,
            "test": rows[i].test,
            "observable": rows[i].observable,
            "conditions": rows[i].conditions,
            "measured": rows[i].value,
            "simulated": means[0][i],
            "standard_error": se,
            "residual_z": residual[r],
        })).collect::<Vec<_>>(),
    });
    std::fs::write(
        args.out.join("diagnosis.json"),
        serde_json::to_vec_pretty(&json)?,
    )?;
    let md = report::report(
        args,
        &report::Findings {
            params: &params,
            diagnosed: &diagnosed,
            now: &now,
            before: &before,
            recalibrated: &recalibrated,
            dropped: &dropped,
            verdict: &verdict,
            fit_first: fit_first.as_ref(),
            refits: refits.as_ref(),
        },
    );
    std::fs::write(args.out.join("diagnosis.md"), &md)?;
    out.write_all(md.as_bytes())?;
    writeln!(
        out,
        "\nwritten: {}/diagnosis.{{json,md}}",
        args.out.display()
    )?;
    Ok(())
}
