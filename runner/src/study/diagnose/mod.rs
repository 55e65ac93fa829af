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
//! (sqrt(uncertainty^2 + scatter^2 / replicates), the scatter pooled over the variants);
//! from the per-seed slopes, the noise of
//! every finite difference (the candidates' variances, the free parameters' covariances);
//! then the score test of [`tilth_tools::diagnose`]. Writes `DIR/diagnosis.json` (`candidates` best first: `name`,
//! `statistic`, `p_value`, `strength`, `predicted_rmse_drop`, `identifiable`, ...) and
//! `DIR/diagnosis.md`, the ranking in words.

use super::calibrate::{Param, parse_param};
use super::measurements::{Measurement, check_against_model, read_measurements};
use super::model_edit::values_of;
use crate::lab::model::Model;
use crate::study::lab_runs::LabRunArgs;
use anyhow::{Result, bail};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::diagnose::verdict::Verdict;
use tilth_tools::diagnose::{Score, score_tests};

mod asked;
mod exclude;
pub mod file;
mod fit_first;
mod refit;
mod report;
mod runs;
mod sensitivity;
mod steps;

use fit_first::{FitFirst, fit_first, fit_summary};
use runs::Simulations;
use sensitivity::{Differences, Standardised};

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
    /// explains is not blamed on an effect (e.g. soil-soil.surface_energy=0.05). Added to
    /// the model file's `[probes]` (the same PAIR.KEY: this STEP); a free --param is not
    /// probed.
    #[arg(long = "probe")]
    pub probes: Vec<String>,
    /// Leave out the model file's `[probes]` (only --probe's are weighed).
    #[arg(long)]
    pub no_model_probes: bool,
    /// Runs per row and variant, with seeds 1, 2, ... shared by every variant.
    #[arg(long, default_value_t = 3)]
    pub replicates: usize,
    /// Each free parameter's first finite-difference step, as a fraction of its range. It
    /// is doubled, up to --longest-param-step, while noise is more than a tenth of the
    /// parameter's measured effect: a parameter measured as noise leaves its misfit to the
    /// candidate most like it (`steps.rs`; docs/discovery-proof.md, "A free parameter
    /// off"). A longer step measures a secant, and a candidate that mimics the parameter is
    /// then absorbed by it: these readings cannot tell them apart.
    #[arg(long, default_value_t = 0.05)]
    pub param_step: f64,
    /// The longest a free parameter's step is lengthened to, as a fraction of its range
    /// (--param-step keeps every step as given).
    #[arg(long, default_value_t = 0.2)]
    pub longest_param_step: f64,
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
    /// its rivals' fits are worse beyond the noise, ambiguous with those that are not (docs/discovery.md,
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
    /// Its finite-difference step, as a fraction of its range: `--param-step`, lengthened
    /// where the runs' noise hid its effect (`steps.rs`).
    pub step: f64,
    /// The variant its slope was measured with (`DIR/models/<variant>.toml`).
    pub variant: String,
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
    /// The share of its measured column's |x|^2 that is noise (`steps.rs`).
    pub noise_share: f64,
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

/// The options' ranges, checked before anything is read.
fn check_args(args: &DiagnoseArgs) -> Result<()> {
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
    if !(args.longest_param_step >= args.param_step && args.longest_param_step <= 0.5) {
        bail!(
            "--longest-param-step {} is out of range: allowed [--param-step {}, 0.5]",
            args.longest_param_step,
            args.param_step
        );
    }
    Ok(())
}

/// What a diagnosis starts from, read and checked before any variant is written.
struct Inputs {
    /// The model the candidates are scored at: the one given, or with `--fit-first` the
    /// fitted one.
    model: Model,
    /// That model's file, as text.
    text: String,
    /// With `--fit-first`, the fitted model's path.
    fitted: Option<PathBuf>,
    /// The measurements of the tests asked for.
    rows: Vec<Measurement>,
    params: Vec<Param>,
    /// The candidates asked for (without the probes).
    names: Vec<String>,
    probes: Vec<(String, f64)>,
}

/// Reads the model, the measurements, the free parameters, the candidates and the probes,
/// and with `--fit-first` fits the free parameters (which runs simulations).
fn read_inputs(args: &DiagnoseArgs) -> Result<Inputs> {
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
    asked::check_candidates(&names, &model, &args.model)?;
    let probes = asked::probes(args, &model, &params)?;
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
    Ok(Inputs {
        model,
        text,
        fitted,
        rows,
        params,
        names,
        probes,
    })
}

/// The linear recalibration of each free parameter: its values shifted by the
/// least-squares `shift`, whether they stay in its range, and whether its effect stands
/// above its noise (sum of x^2 over its sum of variances).
fn recalibrate(
    params: &[Param],
    doc: &toml_edit::DocumentMut,
    shift: &[f64],
    fd: &Differences,
    steps: &[f64],
) -> Result<Vec<Recalibrated>> {
    params
        .iter()
        .enumerate()
        .map(|(c, p)| {
            let path = format!("{}.{}", p.pair, p.key);
            let now = values_of(doc, &path)?;
            let after: Vec<f64> = now.iter().map(|v| v + shift[c]).collect();
            Ok(Recalibrated {
                within_range: after.iter().all(|v| (p.low..=p.high).contains(v)),
                measurable: tilth_tools::diagnose::measurable(
                    &fd.sensitivity(2 + c),
                    &fd.variance(2 + c),
                ),
                noise_share: tilth_tools::diagnose::noise_share(
                    &fd.sensitivity(2 + c),
                    &fd.variance(2 + c),
                ),
                parameter: path,
                step: steps[c],
                variant: fd.variants[2 + c].name.clone(),
                now,
                shift: shift[c],
                after,
                range: [p.low, p.high],
            })
        })
        .collect()
}

/// Each observable's RMSE, in its unit, of the standardised residuals `z` over the used
/// rows (index, standard error se): sqrt(sum of (z * se)^2 / n) over its n rows.
fn rmse_by_obs(rows: &[Measurement], used: &[(usize, f64)], z: &[f64]) -> BTreeMap<String, f64> {
    let mut acc: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    for (r, &(i, s)) in used.iter().enumerate() {
        let e = acc.entry(rows[i].observable.clone()).or_default();
        e.0 += (z[r] * s).powi(2);
        e.1 += 1;
    }
    acc.into_iter()
        .map(|(k, (ss, n))| (k, (ss / n as f64).sqrt()))
        .collect()
}

/// Each score as written: significant when identifiable with p < `--alpha`, and the RMSE
/// drop per observable it predicts, `before` (after recalibration) less the RMSE of the
/// absorbed residual less the candidate's fitted change.
fn to_diagnosed(
    args: &DiagnoseArgs,
    inputs: &Inputs,
    used: &[(usize, f64)],
    scores: Vec<Score>,
    absorbed: &[f64],
    before: &BTreeMap<String, f64>,
) -> Vec<Diagnosed> {
    scores
        .into_iter()
        .map(|s| {
            let after_z: Vec<f64> = absorbed
                .iter()
                .zip(&s.fitted_change)
                .map(|(a, f)| a - f)
                .collect();
            let after = rmse_by_obs(&inputs.rows, used, &after_z);
            Diagnosed {
                significant: s.identifiable && s.p_value < args.alpha,
                predicted_rmse_drop: before
                    .iter()
                    .map(|(k, b)| (k.clone(), b - after[k]))
                    .collect(),
                description: match s.name.strip_prefix(HELD) {
                    Some(key) => Some(format!("the model's {key}, held fixed")),
                    None => inputs.model.file.candidates[&s.name].description.clone(),
                },
                held_parameter: s.name.starts_with(HELD),
                score: s,
            }
        })
        .collect()
}

/// Fits the contenders on simulations (see [`refit::refit`]), each at its step: a
/// candidate's from the model file, a probe's from `--probe` with the model's values of it.
fn refit_contenders(
    args: &DiagnoseArgs,
    inputs: &Inputs,
    doc: &toml_edit::DocumentMut,
    verdict: &Verdict,
    diagnosed: &[Diagnosed],
) -> Result<Option<(Verdict, refit::Refits)>> {
    let step_of = |d: &Diagnosed| -> Result<(f64, Vec<f64>)> {
        match d.score.name.strip_prefix(HELD) {
            Some(key) => {
                let step = inputs
                    .probes
                    .iter()
                    .find(|(k, _)| k == key)
                    .map_or(0.0, |p| p.1);
                Ok((step, values_of(doc, key)?))
            }
            None => Ok((inputs.model.file.candidates[&d.score.name].step, vec![])),
        }
    };
    refit::refit(args, &inputs.rows, verdict, diagnosed, &step_of)
}

/// What a diagnosis found, as `diagnosis.json` and `diagnosis.md` give it.
struct Outcome {
    fit_first: Option<FitFirst>,
    /// RMSE per observable of the model as it is.
    now: BTreeMap<String, f64>,
    /// RMSE per observable after the linear recalibration of the free parameters.
    before: BTreeMap<String, f64>,
    recalibrated: Vec<Recalibrated>,
    diagnosed: Vec<Diagnosed>,
    /// The refit's verdict, or the linear one with `--no-refit` or without a refit.
    verdict: Verdict,
    /// The linear verdict, when the refit's replaced it.
    linear_verdict: Option<Verdict>,
    refits: Option<refit::Refits>,
    dropped: Vec<String>,
    /// Each probe's variant, as its step was measured.
    probe_variants: Vec<String>,
}

/// Writes `DIR/diagnosis.json`: the settings, the outcome, and the standardised columns and
/// rows that `tilth next` reads.
fn write_json(
    args: &DiagnoseArgs,
    inputs: &Inputs,
    used: &[(usize, f64)],
    sims: &Simulations,
    lin: &Standardised,
    o: &Outcome,
) -> Result<()> {
    let Inputs {
        params,
        probes,
        rows,
        fitted,
        ..
    } = inputs;
    let means = &sims.means;
    let json = serde_json::json!({
        "model": args.model.display().to_string(),
        "data": args.data.display().to_string(),
        "replicates": args.replicates,
        "coarse": args.lab.coarse,
        "set": args.lab.set.set,
        "alpha": args.alpha,
        "free_parameters": params,
        "param_step": args.param_step,
        "longest_param_step": args.longest_param_step,
        "fitted_model": fitted.as_ref().map(|p| p.display().to_string()),
        "fit_first": o.fit_first,
        "rows_used": used.len(),
        "rows_dropped": o.dropped,
        "rmse_now": o.now,
        "rmse_after_recalibration": o.before,
        "recalibration": o.recalibrated,
        "candidates": o.diagnosed,
        "probes": probes.iter().zip(&o.probe_variants).map(|((k, h), v)| serde_json::json!({"parameter": k, "step": h, "variant": v})).collect::<Vec<_>>(),
        "verdict": o.verdict,
        "linear_verdict": o.linear_verdict,
        "refit": o.refits,
        // Standardised, one number per entry of "rows": what `tilth next` extends.
        "columns": {
            "free": params.iter().enumerate().map(|(c, p)| (format!("{}.{}", p.pair, p.key), lin.x.column(c).iter().copied().collect::<Vec<_>>())).collect::<BTreeMap<_, _>>(),
            "candidates": lin.candidates.iter().map(|c| (c.name.clone(), serde_json::json!({"sensitivity": c.sensitivity, "variance": c.sensitivity_var}))).collect::<BTreeMap<_, _>>(),
        },
        "rows": used.iter().enumerate().map(|(r, &(i, se))| serde_json::json!({
            "row": rows[i].row,
            "test": rows[i].test,
            "observable": rows[i].observable,
            "conditions": rows[i].conditions,
            "measured": rows[i].value,
            "simulated": means[0][i],
            "standard_error": se,
            "residual_z": lin.residual[r],
            "residual_dof": Some(lin.residual_dof[r]).filter(|d| d.is_finite()),
        })).collect::<Vec<_>>(),
    });
    std::fs::write(
        args.out.join("diagnosis.json"),
        serde_json::to_vec_pretty(&json)?,
    )?;
    Ok(())
}

/// Writes `DIR/diagnosis.md` and prints it.
fn write_report(
    args: &DiagnoseArgs,
    params: &[Param],
    o: &Outcome,
    out: &mut dyn Write,
) -> Result<()> {
    let md = report::report(
        args,
        &report::Findings {
            params,
            diagnosed: &o.diagnosed,
            now: &o.now,
            before: &o.before,
            recalibrated: &o.recalibrated,
            dropped: &o.dropped,
            verdict: &o.verdict,
            fit_first: o.fit_first.as_ref(),
            refits: o.refits.as_ref(),
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

pub fn diagnose(args: &DiagnoseArgs) -> Result<String> {
    crate::study::summary(|out| diagnose_into(args, out))
}

/// [`diagnose`], writing its summary to `out`.
fn diagnose_into(args: &DiagnoseArgs, out: &mut dyn Write) -> Result<()> {
    let set = args.lab.set.parse()?;
    check_args(args)?;
    let mut inputs = read_inputs(args)?;
    let mut variants = runs::write_variants(args, &inputs)?;
    // The candidates' columns, then the probes'.
    let names: Vec<String> = (inputs.names.iter().cloned())
        .chain(inputs.probes.iter().map(|(k, _)| format!("{HELD}{k}")))
        .collect();
    let mut sims = runs::simulate_variants(args, &set, &inputs.rows, &variants)?;
    let steps = steps::lengthen_steps(args, &set, &inputs, &mut variants, &mut sims)?;
    // The probes' variants come last; their steps as lengthened.
    let probe_variants = &variants[variants.len() - inputs.probes.len()..];
    for (probe, v) in inputs.probes.iter_mut().zip(probe_variants) {
        probe.1 = v.step;
    }
    let runs::Usable { used, dropped } = runs::usable_rows(args, &inputs.rows, &sims)?;
    let fd = Differences {
        variants: &variants,
        sims: &sims,
        used: &used,
    };
    let lin = sensitivity::standardise(&inputs.rows, &fd, inputs.params.len(), &names);
    let fit_first = match &inputs.fitted {
        Some(_) => Some(fit_summary(&args.out)?),
        None => None,
    };
    let Standardised {
        residual,
        residual_dof,
        x,
        noise,
        candidates,
    } = &lin;
    let scores = score_tests(residual, x, noise, candidates);
    let verdict = tilth_tools::diagnose::verdict::verdict(
        residual,
        residual_dof,
        x,
        noise,
        candidates,
        &scores,
        args.alpha,
    );
    let absorbed = tilth_tools::diagnose::absorbed(residual, x);
    let shift = tilth_tools::diagnose::recalibration(residual, x);
    let doc: toml_edit::DocumentMut = inputs.text.parse()?;
    let recalibrated = recalibrate(&inputs.params, &doc, &shift, &fd, &steps)?;
    let before = rmse_by_obs(&inputs.rows, &used, &absorbed);
    let now = rmse_by_obs(&inputs.rows, &used, residual);
    let diagnosed = to_diagnosed(args, &inputs, &used, scores, &absorbed, &before);
    let refitted = refit_contenders(args, &inputs, &doc, &verdict, &diagnosed)?;
    let (verdict, linear_verdict, refits) = match refitted {
        Some((v, refits)) => (v, Some(verdict), Some(refits)),
        None => (verdict, None, None),
    };
    let outcome = Outcome {
        fit_first,
        now,
        before,
        recalibrated,
        diagnosed,
        verdict,
        linear_verdict,
        refits,
        dropped,
        probe_variants: probe_variants.iter().map(|v| v.name.clone()).collect(),
    };
    write_json(args, &inputs, &used, &sims, &lin, &outcome)?;
    write_report(args, &inputs.params, &outcome, out)
}
