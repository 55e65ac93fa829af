//! `tilth fit --model M.toml --data D.csv --param ... --out DIR`: one set of parameters for
//! every measured row at once (all tests, conditions and observables), by weighted least
//! squares on simulations; a candidate effect's strength can be one of them.
//!
//! Where `tilth calibrate` fits each condition on its own (a parameter becomes a table over
//! the condition), `fit` moves each parameter by one amount everywhere, so that the
//! measurements together decide it: what "add the effect and recalibrate" needs after
//! `tilth diagnose`, and the joint calibration EDEM users do by hand.
//!
//! Parameters: `PAIR.KEY=LOW:HIGH` shifts the model's value (a number or every point of its
//! table) by one offset, keeping every point within [LOW, HIGH]; `candidate.NAME=LOW:HIGH`
//! is the strength of the model file's `[candidates.NAME]`, switched on (start 0, or
//! `LOW:HIGH@START`, e.g. diagnose's estimate).
//!
//! Levenberg-Marquardt with finite-difference Jacobians. Each iteration runs the current
//! setting and each parameter moved by a quarter of its range (`JACOBIAN_STEP`), all with
//! seeds 1..R (common random numbers, though the grains' chaos leaves two runs of one seed
//! little alike after the change). Residuals are standardised by
//! each row's standard error sqrt(uncertainty^2 + s^2 / R), s the current setting's scatter:
//! chi^2 = sum z^2. The step solves (J'J + lambda diag J'J) d = J'z, limited to a quarter of
//! each range; a step that raises chi^2 is taken back, lambda raised and the next step at most half as long (Marquardt 1963).
//! Standard errors from (J'J - N)^-1, scaled by chi^2 / dof when that is above 1, where N is
//! the noise the finite-difference Jacobian carries into J'J, measured from the per-seed
//! slopes (`jacobian_noise.rs`); the naive (J'J)^-1 is reported beside them as a lower
//! bound.
//!
//! The fit stops at the first setting at the noise (`stop.rs`): chi^2 <= dof, and the next
//! step's predicted chi^2 gain (the score statistic) under chi^2_P's 95 % quantile. A step
//! from there would follow the runs' scatter and costs 1 + P settings of DEM runs;
//! `--to-minimum` keeps stepping. It also stops when every step is under 1 % of its range,
//! or after `--iterations`.
//!
//! Writes `DIR/fit.json` (estimate, standard errors, correlations, the history),
//! `DIR/fit.md`, and `DIR/model.toml`: the model with the fitted parameters, ready for
//! `tilth compare`. Runs go to `DIR/runs/iter-K/<variant>/` and resume.

mod from_diagnosis;
mod jacobian_noise;
mod stop;

use super::compare::{LabRunArgs, Simulate, TestSetting, mean_sd, prefetch, simulate, std_error};
use super::measurements::{Measurement, check_against_model, read_measurements};
use super::model_edit::{add_to, switch_on, values_of, variant};
use crate::lab::model::Model;
use crate::sweep::execute;
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use jacobian_noise::{covariance, jacobian_noise};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use stop::{Stop, at_noise, noise_gain, predicted_gain};

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Starting model file.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements (CSV): every row is fitted.
    #[arg(long)]
    pub data: PathBuf,
    /// A free parameter: `PAIR.KEY=LOW:HIGH` or `candidate.NAME=LOW:HIGH[@START]`
    /// (repeatable).
    #[arg(long = "param", required_unless_present = "from_diagnosis")]
    pub params: Vec<String>,
    /// Act on `tilth diagnose`'s verdict in DIR/diagnosis.json: its free parameters, and the
    /// strength of each effect it names (from its estimate). Refused unless the verdict is
    /// `effect`. Any --param is added.
    #[arg(long, value_name = "DIR")]
    pub from_diagnosis: Option<PathBuf>,
    /// Runs per row and setting (seeds 1..R, the same at every setting).
    #[arg(long, default_value_t = 3)]
    pub replicates: usize,
    /// Levenberg-Marquardt iterations, at most (each runs 1 + parameters settings).
    #[arg(long, default_value_t = 4)]
    pub iterations: usize,
    /// Keep stepping at the noise (chi^2 <= degrees of freedom and the next step's predicted
    /// chi^2 gain under chi^2_P's 95 % quantile), where the fit stops by default.
    #[arg(long)]
    pub to_minimum: bool,
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub lab: LabRunArgs,
}

/// What a free parameter moves.
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Target {
    /// An offset added to `pairs.PAIR.KEY`.
    Offset { path: String },
    /// The strength of `[candidates.NAME]`.
    Candidate { name: String },
}

/// A free parameter: its value is the offset or the strength.
#[derive(Debug, Clone, Serialize)]
pub struct FreeParam {
    pub label: String,
    pub target: Target,
    /// Bounds of the value (for an offset: what keeps the model's points in range).
    pub low: f64,
    pub high: f64,
    pub start: f64,
}

fn parse(s: &str, model: &Model, doc: &toml_edit::DocumentMut) -> Result<FreeParam> {
    let bad = || {
        anyhow!(
            "--param {s:?}: expected PAIR.KEY=LOW:HIGH or candidate.NAME=LOW:HIGH[@START], e.g. soil-soil.rolling_friction=0.05:0.45"
        )
    };
    let (path, range) = s.split_once('=').ok_or_else(bad)?;
    let (range, start) = match range.split_once('@') {
        Some((r, x)) => (r, Some(x)),
        None => (range, None),
    };
    let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| anyhow!("--param {s:?}: {t:?} is not a number"))
    };
    let (low, high) = (num(lo)?, num(hi)?);
    if high <= low {
        bail!("--param {s:?}: the range must be LOW:HIGH with LOW < HIGH");
    }
    let path = path.trim();
    if let Some(name) = path.strip_prefix("candidate.") {
        super::model_edit::has_candidate(model, name, &format!("--param {s:?}"))?;
        let start = start.map(num).transpose()?.unwrap_or(0.0);
        if !(low..=high).contains(&start) {
            bail!("--param {s:?}: the start {start} is outside [{low}, {high}]");
        }
        return Ok(FreeParam {
            label: path.to_string(),
            target: Target::Candidate {
                name: name.to_string(),
            },
            low,
            high,
            start,
        });
    }
    if start.is_some() {
        bail!("--param {s:?}: @START is for candidates; a PAIR.KEY starts at the model's value");
    }
    if !path.contains('.') {
        return Err(bad());
    }
    let now = values_of(doc, path).with_context(|| format!("--param {s:?}"))?;
    let (min, max) = now
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if min < low || max > high {
        bail!("--param {s:?}: the model's value ({min} to {max}) is outside [{low}, {high}]");
    }
    Ok(FreeParam {
        label: path.to_string(),
        target: Target::Offset {
            path: path.to_string(),
        },
        low: low - min,
        high: high - max,
        start: 0.0,
    })
}

/// The model with the free parameters at `theta`.
fn apply(
    doc: &mut toml_edit::DocumentMut,
    model: &Model,
    params: &[FreeParam],
    theta: &[f64],
) -> Result<()> {
    for (p, &v) in params.iter().zip(theta) {
        match &p.target {
            Target::Offset { path } => add_to(doc, path, v)?,
            Target::Candidate { name } => switch_on(doc, model, name, v)?,
        }
    }
    Ok(())
}

/// One iteration's record.
#[derive(Debug, Clone, Serialize)]
pub struct Step {
    pub iteration: usize,
    pub theta: Vec<f64>,
    pub chi2: f64,
    pub rmse: BTreeMap<String, f64>,
    /// Whether this setting improved on the best before it.
    pub accepted: bool,
    /// For an accepted setting whose Jacobian was run: the chi^2 the Gauss-Newton step from
    /// it is predicted to remove, z'J (J'J)^-1 J'z (`stop.rs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_gain: Option<f64>,
}

/// How far each parameter is moved for the finite-difference Jacobian, as a fraction of its
/// range: as far as a step may go (the trust radius starts at a quarter of each range), so
/// the secant describes the readings over the region a step can reach.
///
/// Not less: the grains' chaos decorrelates the runs of one seed after any change, so each
/// slope carries noise of variance 2 s^2 / (R h^2), s the runs' scatter. At 5 % of the range
/// that noise was larger than the slopes themselves on the discovery proof's draws, so J'J
/// was mostly noise: steps came out short, the estimates stayed near their start, and the
/// standard errors were 2-6x too small (docs/discovery-proof.md, "`fit`'s standard errors"). A
/// simulation of this fit on a model of two parameters
/// whose truth is known (`tools/discovery/fit_steps.py`, 400 draws each): with 5 % steps
/// the estimates fall short of the truth by up to 1.6 of their exact standard deviations
/// and the 95 % interval holds it in 5-77 % of the draws; with 25 %, the bias is under 0.25
/// of them and the interval holds it in 85-95 % of the draws with (J'J)^-1, 95-97 % with
/// the Jacobian's noise taken off.
const JACOBIAN_STEP: f64 = 0.25;

/// The best setting so far.
struct Best {
    theta: Vec<f64>,
    chi2: f64,
    /// The rows' simulated means and their standard errors.
    centre: Vec<f64>,
    se: Vec<f64>,
    /// The Jacobian (standardised by `se`) and the noise it carries into J'J
    /// (`jacobian_noise.rs`).
    jac: DMatrix<f64>,
    noise: DMatrix<f64>,
}

impl Best {
    fn at(
        theta: &[f64],
        chi2: f64,
        centre: Vec<f64>,
        se: Vec<f64>,
        (jac, noise): (DMatrix<f64>, DMatrix<f64>),
    ) -> Best {
        Best {
            theta: theta.to_vec(),
            chi2,
            centre,
            se,
            jac,
            noise,
        }
    }
}

/// The simulated rows at one setting.
struct Sims {
    /// Each row's mean, None where a run failed.
    mean: Vec<Option<f64>>,
    /// Each row's scatter (sample standard deviation).
    scatter: Vec<Option<f64>>,
    /// Each row's values, seed by seed (seeds 1..R in order, all of them where `mean` is
    /// Some).
    seeds: Vec<Vec<f64>>,
}

/// The runs of every row with the model file `model`, in `out`: replicates 1..R.
fn at<'a>(
    model: &'a Path,
    out: &'a Path,
    args: &'a FitArgs,
    set: &'a [TestSetting],
) -> Simulate<'a> {
    Simulate {
        model,
        data: &args.data,
        out,
        replicates: args.replicates,
        first_seed: 1,
        lab: &args.lab,
        set,
    }
}

pub fn fit(args: &FitArgs, out: &mut dyn Write) -> Result<()> {
    let set = args.lab.set.parse()?;
    if args.replicates < 2 {
        bail!(
            "--replicates {}: allowed 2 or more (the rows' standard errors need the runs' scatter)",
            args.replicates
        );
    }
    if args.iterations == 0 {
        bail!("--iterations 0: allowed 1 or more");
    }
    let model_path = std::path::absolute(&args.model)?;
    let model = Model::load(&model_path)?;
    let text = std::fs::read_to_string(&model_path)?;
    let doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", args.model.display()))?;
    let rows = read_measurements(&args.data)?;
    check_against_model(&rows, &model, &args.data)?;
    let mut asked = args.params.clone();
    if let Some(dir) = &args.from_diagnosis {
        let step = |name: &str| model.file.candidates.get(name).map(|c| c.step);
        for p in from_diagnosis::params_from_diagnosis(dir, &step)? {
            let label = p.split('=').next().unwrap_or_default().to_string();
            if !asked
                .iter()
                .any(|a| a.split('=').next() == Some(label.as_str()))
            {
                asked.push(p);
            }
        }
    }
    let params: Vec<FreeParam> = asked
        .iter()
        .map(|s| parse(s, &model, &doc))
        .collect::<Result<_>>()?;
    let n = params.len();
    let stop = execute::stop_on_signals()?;
    let runs = args.out.join("runs");
    let models = args.out.join("models");
    std::fs::create_dir_all(&models)?;

    // The model file and the run directory of variant `name` of iteration `it` (at `theta`).
    let setting = |it: usize, name: &str, theta: &[f64]| -> Result<(PathBuf, PathBuf)> {
        let label = format!("iter-{it}-{name}");
        let path = variant(&model, &text, &models, &label, |d| {
            apply(d, &model, &params, theta)
        })?;
        Ok((path, runs.join(format!("iter-{it}")).join(name)))
    };
    // Simulates every row with the model file `path`, into `out`.
    let run_at = |path: &Path, out: &Path| -> Result<Sims> {
        let sims = simulate(&rows, &at(path, out, args, &set), &stop)?;
        let (mean, scatter) = sims
            .iter()
            .map(|(v, _)| {
                if v.len() == args.replicates {
                    let (m, s) = mean_sd(v);
                    (Some(m), s)
                } else {
                    (None, None)
                }
            })
            .unzip();
        Ok(Sims {
            mean,
            scatter,
            seeds: sims.into_iter().map(|(v, _)| v).collect(),
        })
    };
    // Simulates every row at `theta`, as variant `name` of iteration `it`.
    let run = |it: usize, name: &str, theta: &[f64]| -> Result<Sims> {
        let (path, out) = setting(it, name, theta)?;
        run_at(&path, &out)
    };
    let mut theta: Vec<f64> = params.iter().map(|p| p.start).collect();
    let mut best: Option<Best> = None;
    let mut lambda = 1e-3;
    let mut radius = 0.25;
    // The last step, as a fraction of each range (its largest component).
    let mut last_step = 0.25f64;
    let mut history: Vec<Step> = vec![];
    let dof = rows.len().saturating_sub(n).max(1);
    let mut stopped = Stop::Iterations;
    for it in 0..=args.iterations {
        if !args.lab.quiet {
            eprintln!(
                "fit: iteration {it} of {}: {}",
                args.iterations,
                show(&params, &theta)
            );
        }
        let Sims {
            mean: centre,
            scatter,
            seeds: centre_seeds,
        } = run(it, "centre", &theta)?;
        let failed: Vec<String> = rows
            .iter()
            .zip(&centre)
            .filter(|(_, c)| c.is_none())
            .map(|(m, _)| format!("row {}", m.row))
            .collect();
        if !failed.is_empty() {
            bail!(
                "iteration {it} ({}): runs failed at {}; see {}",
                show(&params, &theta),
                failed.join(", "),
                runs.join(format!("iter-{it}")).display()
            );
        }
        let centre: Vec<f64> = centre.into_iter().map(Option::unwrap).collect();
        let se: Vec<f64> = rows
            .iter()
            .zip(&scatter)
            .map(|(m, s)| {
                std_error(*s, args.replicates, m.uncertainty)
                    .filter(|e| *e > 0.0)
                    .unwrap_or(1.0)
            })
            .collect();
        let z: Vec<f64> = rows
            .iter()
            .zip(&centre)
            .zip(&se)
            .map(|((m, c), s)| (m.value - c) / s)
            .collect();
        let chi2: f64 = z.iter().map(|v| v * v).sum();
        let accepted = best.as_ref().is_none_or(|b| chi2 < b.chi2);
        history.push(Step {
            iteration: it,
            theta: theta.clone(),
            chi2,
            rmse: rmse(&rows, &centre),
            accepted,
            predicted_gain: None,
        });
        if accepted {
            lambda = (lambda / 3.0f64).max(1e-6);
            if it == args.iterations {
                // No step follows: the standard errors use the last Jacobian, one step
                // back (not worth P more settings of runs).
                let (jac, noise) = best
                    .map(|b| (b.jac, b.noise))
                    .unwrap_or_else(|| (DMatrix::zeros(rows.len(), n), DMatrix::zeros(n, n)));
                best = Some(Best::at(&theta, chi2, centre, se, (jac, noise)));
                break;
            }
            // The Jacobian at the new best setting, standardised by its standard errors.
            // Each parameter moved by `JACOBIAN_STEP` of its range (backwards at its upper
            // bound).
            let steps: Vec<f64> = params
                .iter()
                .enumerate()
                .map(|(j, p)| {
                    let h0 = JACOBIAN_STEP * (p.high - p.low);
                    if theta[j] + h0 <= p.high { h0 } else { -h0 }
                })
                .collect();
            let moved_settings = steps
                .iter()
                .enumerate()
                .map(|(j, h)| {
                    let mut t = theta.clone();
                    t[j] += h;
                    setting(it, &format!("param-{j}"), &t)
                })
                .collect::<Result<Vec<_>>>()?;
            // With --slurm the P moved settings go into one job array.
            let hows: Vec<Simulate> = moved_settings
                .iter()
                .map(|(path, out)| at(path, out, args, &set))
                .collect();
            prefetch(&rows, &hows)?;
            let mut jac = DMatrix::zeros(rows.len(), n);
            let mut moved_seeds = Vec::with_capacity(n);
            for (j, p) in params.iter().enumerate() {
                let h = steps[j];
                let (path, out) = &moved_settings[j];
                let Sims {
                    mean: moved, seeds, ..
                } = run_at(path, out)?;
                moved_seeds.push(seeds);
                for i in 0..rows.len() {
                    let m = moved[i].ok_or_else(|| {
                        anyhow!(
                            "iteration {it}: the runs with {} moved failed at row {}",
                            p.label,
                            rows[i].row
                        )
                    })?;
                    jac[(i, j)] = (m - centre[i]) / h / se[i];
                }
            }
            let noise = jacobian_noise(&centre_seeds, &moved_seeds, &steps, &se);
            let gain = predicted_gain(&jac, &z);
            history.last_mut().expect("pushed above").predicted_gain = gain;
            best = Some(Best::at(&theta, chi2, centre, se, (jac, noise)));
            if at_noise(chi2, dof, gain, n) && !args.to_minimum {
                if !args.lab.quiet {
                    eprintln!(
                        "fit: at the noise (chi^2 {chi2:.2} <= {dof} degrees of freedom; the next step's predicted gain {} < {:.2}, chi^2_{n}'s 95 % quantile); --to-minimum steps on",
                        gain.map_or("-".into(), |g| format!("{g:.2}")),
                        noise_gain(n)
                    );
                }
                stopped = Stop::AtNoise;
                break;
            }
        } else {
            lambda *= 4.0;
            // Back to the best setting, with a step half as long as the one that failed
            // (raising lambda alone hardly shortens a step that was small to begin with).
            radius = 0.5 * last_step;
            if it == args.iterations {
                break;
            }
        }
        let b = best.as_ref().unwrap();
        let (b_theta, jac) = (&b.theta, &b.jac);
        let b_z: Vec<f64> = rows
            .iter()
            .zip(&b.centre)
            .zip(&b.se)
            .map(|((m, c), s)| (m.value - c) / s)
            .collect();
        let jtj = jac.transpose() * jac;
        let jtz = jac.transpose() * DVector::from_vec(b_z);
        let mut a = jtj.clone();
        for k in 0..n {
            a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
        }
        let d = a
            .lu()
            .solve(&jtz)
            .ok_or_else(|| anyhow!("iteration {it}: the fit's normal equations are singular"))?;
        let mut next = b_theta.clone();
        let mut small = true;
        last_step = 0.0;
        for (k, p) in params.iter().enumerate() {
            let span = p.high - p.low;
            let step = d[k].clamp(-radius * span, radius * span);
            next[k] = (b_theta[k] + step).clamp(p.low, p.high);
            small &= (next[k] - b_theta[k]).abs() < 0.01 * span;
            last_step = last_step.max((next[k] - b_theta[k]).abs() / span);
        }
        if small {
            stopped = Stop::Converged;
            if !args.lab.quiet {
                eprintln!("fit: converged (every step under 1 % of its range)");
            }
            break;
        }
        theta = next;
    }

    let Best {
        theta: b_theta,
        chi2: b_chi2,
        centre: b_centre,
        se: b_se,
        jac,
        noise,
        ..
    } = best.expect("iteration 0 ran");
    let scale = (b_chi2 / dof as f64).max(1.0);
    let cov = covariance(&jac, &noise, scale);
    let naive = covariance(&jac, &DMatrix::zeros(n, n), scale);
    let sd_of = |cov: &Option<DMatrix<f64>>| -> Vec<Option<f64>> {
        (0..n)
            .map(|k| cov.as_ref().map(|c| c[(k, k)].max(0.0).sqrt()))
            .collect()
    };
    let (sd, sd_naive) = (sd_of(&cov), sd_of(&naive));
    let corr: Option<Vec<Vec<f64>>> = cov.as_ref().map(|c| {
        (0..n)
            .map(|a| {
                (0..n)
                    .map(|b| c[(a, b)] / (c[(a, a)] * c[(b, b)]).sqrt())
                    .collect()
            })
            .collect()
    });
    // The fitted model, comments kept.
    let mut fitted: toml_edit::DocumentMut = text.parse()?;
    apply(&mut fitted, &model, &params, &b_theta)?;
    let header = format!(
        "# Fitted by `tilth fit` to {} ({} rows): {}\n",
        args.data.display(),
        rows.len(),
        show(&params, &b_theta)
    );
    let model_out = args.out.join("model.toml");
    std::fs::write(&model_out, header + &fitted.to_string())?;
    Model::load(&model_out).context("the fitted model")?;

    let first = &history[0];
    let json = serde_json::json!({
        "model": args.model.display().to_string(),
        "data": args.data.display().to_string(),
        "replicates": args.replicates,
        "coarse": args.lab.coarse,
        "set": args.lab.set.set,
        "parameters": params,
        "estimate": b_theta,
        "standard_error": sd,
        "standard_error_uncorrected": sd_naive,
        "jacobian_noise": (0..n).map(|j| (0..n).map(|k| noise[(j, k)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "correlation": corr,
        "chi2": b_chi2,
        // Each row's (measured - simulated) / standard error at the estimate: chi2 is their
        // sum of squares (diagnose's refit compares fits row by row).
        "z": rows.iter().zip(&b_centre).zip(&b_se).map(|((m, c), s)| (m.value - c) / s).collect::<Vec<_>>(),
        "dof": dof,
        "rmse_start": first.rmse,
        "rmse": rmse(&rows, &b_centre),
        "history": history,
        "stopped": stopped,
        "fitted_model": model_out.display().to_string(),
    });
    std::fs::write(args.out.join("fit.json"), serde_json::to_vec_pretty(&json)?)?;
    let mut md = format!(
        "# Fit of {} to {}\n\n{} rows, {} replicates per setting, {} free parameter{}.\n\n| parameter | start | estimate | standard error | uncorrected (a lower bound) | range |\n|---|---|---|---|---|---|\n",
        args.model.display(),
        args.data.display(),
        rows.len(),
        args.replicates,
        n,
        if n == 1 { "" } else { "s" }
    );
    for (k, p) in params.iter().enumerate() {
        md += &format!(
            "| {} | {:.4} | {:.4} | {} | {} | [{:.4}, {:.4}] |\n",
            describe(p),
            p.start,
            b_theta[k],
            sd[k].map_or("not determined".into(), |s| format!("{s:.4}")),
            sd_naive[k].map_or("-".into(), |s| format!("{s:.4}")),
            p.low,
            p.high
        );
    }
    md += "\nThe standard errors take off J'J the noise the finite-difference Jacobian carries (the runs' chaos, measured from the per-seed slopes); the uncorrected ones, (J'J)^-1, understate the uncertainty.";
    if sd.iter().any(Option::is_none) {
        md += " Not determined: once that noise is taken off, the runs do not show how the readings move with the parameters; more replicates (`--replicates`) would.";
    }
    md += "\n";
    md += &format!(
        "\nchi^2 {:.2} on {dof} degrees of freedom (start {:.2}). {}\n\n| observable | RMSE at the start | RMSE fitted |\n|---|---|---|\n",
        b_chi2,
        first.chi2,
        stopped.say(args.iterations)
    );
    let end = rmse(&rows, &b_centre);
    for (k, v) in &end {
        md += &format!("| {k} | {:.4} | {:.4} |\n", first.rmse[k], v);
    }
    md += &format!(
        "\nThe fitted model: `{}` (for `tilth compare`).\n",
        model_out.display()
    );
    std::fs::write(args.out.join("fit.md"), &md)?;
    out.write_all(md.as_bytes())?;
    writeln!(
        out,
        "\nwritten: {}/fit.{{json,md}}, model.toml",
        args.out.display()
    )?;
    Ok(())
}

fn describe(p: &FreeParam) -> String {
    match &p.target {
        Target::Offset { path } => format!("{path} (offset)"),
        Target::Candidate { name } => format!("candidate {name} (strength)"),
    }
}

fn show(params: &[FreeParam], theta: &[f64]) -> String {
    params
        .iter()
        .zip(theta)
        .map(|(p, v)| format!("{} {v:+.4}", p.label))
        .collect::<Vec<_>>()
        .join(", ")
}

/// RMSE of simulated - measured per observable, in its unit.
fn rmse(rows: &[Measurement], sim: &[f64]) -> BTreeMap<String, f64> {
    let mut acc: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    for (m, s) in rows.iter().zip(sim) {
        let e = acc.entry(m.observable.clone()).or_default();
        e.0 += (s - m.value).powi(2);
        e.1 += 1;
    }
    acc.into_iter()
        .map(|(k, (ss, n))| (k, (ss / n as f64).sqrt()))
        .collect()
}
