//! `tilth next --diagnosis DIR --menu MENU.csv --out NEXT`: which measurement would tell
//! apart the candidates an ambiguous diagnosis could not, ranked by the discrimination
//! criteria of [`tilth_tools::diagnose::discriminate`].
//!
//! Every measurement the lab could take (a row of `--menu`: a test and its conditions; every
//! observable of the test unless the file names one per row) is simulated with the
//! diagnosis's own variants and seeds (the model, each free parameter raised by its step,
//! each rival switched on at its step), so the new rows' columns are measured as the old
//! rows' were. Each measurement is added to the diagnosed rows in turn, and the pair of
//! rivals hardest to tell apart on the result sets its separation: the noncentrality of the
//! encompassing test that would reject the wrong one, less its finite-difference noise, and
//! that test's power at the diagnosis's alpha. The ranking is by the expected power of
//! [`tilth_tools::diagnose::discriminate::expected_power`]: each rival's chance of being
//! the truth, from its fit's misfit (Box and Hill 1967), times the power of the test against
//! its hardest rival, so a pair the data already make unlikely does not decide the choice
//! (`--criterion maximin` ranks by the hardest pair alone, the T-optimal design). A new row
//! is standardised by sqrt(lab^2 / specimens + scatter^2 / R): the lab's noise (`--noise`,
//! as `tilth synth` takes it; the runs' own scatter when not given) and the model's runs.
//!
//! Writes `NEXT/next.json` (every measurement, best first, with every pair's separation),
//! `NEXT/next.md` and `NEXT/conditions.csv`, the `--top` best as a conditions file for the
//! lab or for `tilth synth --conditions`.

use super::measurements::{Measurement, check_against_model, observables_of, open_csv};
use super::synth::{Noise, parse_noise, read_conditions};
use crate::lab::model::Model;
use crate::study::lab_runs::{LabRunArgs, Simulate, prefetch, simulate};
use crate::sweep::execute;
use anyhow::{Context, Result, bail};
use clap::Args;
use nalgebra::DMatrix;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use tilth_tools::compare::mean_sd;
use tilth_tools::diagnose::discriminate::{
    Rows, Separation, expected_power, separations, weights, worst,
};
use tilth_tools::diagnose::verdict::Kind;

mod fitted;
mod report;
use report::{report, write_conditions};

#[derive(Debug, Args)]
pub struct NextArgs {
    /// A `tilth diagnose` output directory (diagnosis.json and models/).
    #[arg(long)]
    pub diagnosis: PathBuf,
    /// The measurements the lab could take: a CSV of `test` and its conditions (as `tilth
    /// synth --conditions`), with an `observable` column to offer only some readings.
    #[arg(long)]
    pub menu: PathBuf,
    /// Where next.json, next.md and conditions.csv go (the menu's runs in runs/).
    #[arg(long)]
    pub out: PathBuf,
    /// The rivals to separate (default: the diagnosis's ambiguous set).
    #[arg(long, value_delimiter = ',')]
    pub rivals: Vec<String>,
    /// The lab's noise per observable, `NAME=SD` or `NAME=PCT%` (default: the runs' own
    /// scatter, one specimen's).
    #[arg(long, default_value = "")]
    pub noise: String,
    /// Specimens the lab averages per measurement.
    #[arg(long, default_value_t = 1)]
    pub specimens: usize,
    /// How many of the best measurements go into conditions.csv.
    #[arg(long, default_value_t = 1)]
    pub top: usize,
    /// How measurements are ranked: by the expected power over the rivals weighted by their
    /// fits, or by the hardest pair alone.
    #[arg(long, value_enum, default_value_t = Criterion::ExpectedPower)]
    pub criterion: Criterion,
    #[command(flatten)]
    pub lab: LabRunArgs,
}

use crate::study::diagnose::file::DiagnosisFile as Diagnosis;

/// The ranking of `tilth next`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// sum over rivals a of P(a) x the power against a's hardest rival (Box and Hill 1967).
    ExpectedPower,
    /// The hardest pair's separation (T-optimal, Atkinson and Fedorov 1975).
    Maximin,
}

/// One measurement the lab could take, scored.
#[derive(Debug, Serialize)]
pub struct Suggestion {
    pub test: String,
    pub conditions: BTreeMap<String, f64>,
    pub observables: Vec<String>,
    /// The hardest pair's noncentrality less its noise, with the measurement added.
    pub separation: f64,
    /// That pair's test power at the diagnosis's alpha.
    pub power: f64,
    /// sum over rivals a of weight(a) x the power against a's hardest rival.
    pub expected_power: f64,
    pub pairs: Vec<Separation>,
    /// DEM runs a diagnosis with it added costs for it: variants x replicates.
    pub runs: usize,
}

/// A variant of the diagnosis: its model file, its step and its run directory name.
struct Variant {
    name: String,
    model: PathBuf,
    step: f64,
}

pub fn next(args: &NextArgs) -> Result<String> {
    crate::study::summary(|out| next_into(args, out))
}

/// [`next`], writing its summary to `out`.
fn next_into(args: &NextArgs, out: &mut dyn Write) -> Result<()> {
    let (d, rivals, path) = load(args)?;
    let model = Model::load(&std::path::absolute(&d.model)?)?;
    let menu = read_menu(&args.menu)?;
    check_against_model(&menu, &model, &args.menu)?;
    let noise = parse_noise(&args.noise)?;
    let (strengths, baseline, (mut options, unscored), mode) = match fitted::fitted_rivals(
        &d, &rivals,
    ) {
        Some(models) => {
            let options = fitted::fitted_options(args, &d, &rivals, &models, &menu, &noise)?;
            let strengths = models.iter().map(|m| m.1).collect();
            (strengths, vec![], options, "fitted")
        }
        None if rivals.iter().any(|r| r == fitted::FREE) => bail!(
            "--rivals {}: the free parameters' fit is a rival only of a refitted diagnosis (one made without --no-refit)",
            rivals.join(",")
        ),
        None => {
            let (strengths, baseline, options) =
                linear_options(args, (&d, &path), &model, &rivals, (&menu, &noise))?;
            (strengths, baseline, options, "linear")
        }
    };
    if options.is_empty() {
        bail!(
            "{}: no measurement of the menu could be scored: {}",
            args.menu.display(),
            unscored
                .iter()
                .map(Unscored::describe)
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    let weights = weights(&fitted::misfits(&d, &rivals));
    for o in &mut options {
        o.expected_power = expected_power(&o.pairs, &rivals, &weights);
    }
    options.sort_by(|a, b| match args.criterion {
        Criterion::ExpectedPower => (b.expected_power.total_cmp(&a.expected_power))
            .then(b.separation.total_cmp(&a.separation)),
        Criterion::Maximin => b.separation.total_cmp(&a.separation),
    });
    std::fs::create_dir_all(&args.out)?;
    write_conditions(
        &args.out.join("conditions.csv"),
        &options[..args.top.min(options.len())],
    )?;
    let now = worst(&baseline).cloned();
    let json = serde_json::json!({
        "diagnosis": args.diagnosis.display().to_string(),
        "menu": args.menu.display().to_string(),
        "mode": mode,
        "rivals": rivals,
        "strengths": strengths,
        "weights": weights,
        "criterion": args.criterion,
        "alpha": d.alpha,
        "specimens": args.specimens,
        "noise": args.noise,
        "now": baseline,
        "options": options,
        "unscored": unscored,
    });
    std::fs::write(
        args.out.join("next.json"),
        serde_json::to_vec_pretty(&json)?,
    )?;
    let md = report(
        args,
        (&rivals, &strengths, &weights, mode),
        now.as_ref(),
        (&options, &unscored),
    );
    std::fs::write(args.out.join("next.md"), &md)?;
    out.write_all(md.as_bytes())?;
    writeln!(
        out,
        "\nwritten: {}/next.{{json,md}}, conditions.csv",
        args.out.display()
    )?;
    Ok(())
}

/// The linearised ranking: the menu simulated with the diagnosis's own variants, each
/// measurement scored by [`separations`] with the rivals at their one-step strengths.
/// Returns the strengths, the separations on the diagnosed rows alone, and the options.
fn linear_options(
    args: &NextArgs,
    (d, path): (&Diagnosis, &Path),
    model: &Model,
    rivals: &[String],
    (menu, noise): (&[Measurement], &BTreeMap<String, Noise>),
) -> Result<(Vec<f64>, Vec<Separation>, Scored)> {
    let set = args.lab.set.parse()?;
    let variants = variants_of(d, model, &args.diagnosis, rivals)?;
    // Simulate every menu row with every variant, seeds R+1..2R as the diagnosis's
    // finite differences.
    let r = d.replicates;
    let stop = execute::stop_on_signals()?;
    let outs: Vec<PathBuf> = variants
        .iter()
        .map(|v| args.out.join("runs").join(&v.name))
        .collect();
    let hows: Vec<Simulate> = variants
        .iter()
        .zip(&outs)
        .map(|(v, o)| Simulate {
            model: &v.model,
            data: &args.menu,
            out: o,
            replicates: r,
            first_seed: 1 + r as u64,
            lab: &args.lab,
            set: &set,
        })
        .collect();
    prefetch(menu, &hows)?;
    let mut values: Vec<Vec<Vec<f64>>> = vec![];
    for (k, v) in variants.iter().enumerate() {
        if !args.lab.quiet {
            eprintln!("variant {} of {}: {}", k + 1, variants.len(), v.name);
        }
        values.push(
            simulate(menu, &hows[k], &stop)?
                .into_iter()
                .map(|s| s.0)
                .collect(),
        );
    }
    let old = old_rows(d, rivals, path)?;
    let strengths: Vec<f64> = rivals
        .iter()
        .map(|n| {
            d.candidates
                .iter()
                .find(|c| &c.name == n)
                .map(|c| c.strength)
                .with_context(|| format!("{}: no candidate {n}", path.display()))
        })
        .collect::<Result<_>>()?;
    let p = d.free_parameters.len();
    let baseline = separations(&old, rivals, &strengths, d.alpha);
    let measured = Measured {
        values: &values,
        variants: &variants,
        replicates: r,
        params: p,
        noise,
        specimens: args.specimens,
    };
    let rivals_at = Rivals {
        names: rivals,
        strengths: &strengths,
        alpha: d.alpha,
    };
    let runs = (2 + p + d.candidates.len()) * r;
    let options = score(menu, &measured, &old, &rivals_at, runs);
    Ok((strengths, baseline, options))
}

/// The diagnosis in `path`, checked against the options, and the rivals to separate.
fn load(args: &NextArgs) -> Result<(Diagnosis, Vec<String>, PathBuf)> {
    let (d, path) = crate::study::diagnose::file::read(&args.diagnosis, "--diagnosis")?;
    let path = &path;
    if d.coarse != args.lab.coarse {
        bail!(
            "{} was made {} the coarse preset: run `tilth next` {} --coarse, so the new rows are simulated as the old",
            path.display(),
            if d.coarse { "at" } else { "without" },
            if d.coarse { "with" } else { "without" }
        );
    }
    if args.specimens == 0 || args.top == 0 {
        bail!("--specimens and --top: allowed 1 or more");
    }
    let rivals: Vec<String> = if args.rivals.is_empty() {
        if d.verdict.verdict != Kind::Ambiguous {
            bail!(
                "{}: the verdict is not ambiguous, so there are no rivals to separate; name some with --rivals A,B",
                path.display()
            );
        }
        d.verdict.ambiguous.clone()
    } else {
        args.rivals.clone()
    };
    if rivals.len() < 2 {
        bail!("--rivals: allowed two or more candidates, got {rivals:?}");
    }
    Ok((d, rivals, path.clone()))
}

/// The rivals, each at its estimated strength, and the level of the tests between them.
struct Rivals<'a> {
    names: &'a [String],
    strengths: &'a [f64],
    alpha: f64,
}

/// Every measurement of the menu (its readings grouped by test and conditions), added in
/// turn to the diagnosed rows `old` and scored by the hardest pair's separation; `runs` is
/// what a diagnosis with it costs per measurement.
fn score(
    menu: &[Measurement],
    measured: &Measured,
    old: &Rows,
    rivals: &Rivals,
    runs: usize,
) -> Scored {
    let mut options = vec![];
    let mut unscored = vec![];
    for (test, conditions, members) in group(menu) {
        let (rows, kept) = measured.rows(menu, &members, rivals.names.len());
        if kept.is_empty() {
            unscored.push(Unscored {
                test,
                conditions,
                why: vec![
                    "a run failed, or no reading scatters and --noise gives none".to_string(),
                ],
            });
            continue;
        }
        let pairs = separations(
            &old.stack(&rows),
            rivals.names,
            rivals.strengths,
            rivals.alpha,
        );
        let observables = kept.iter().map(|&i| menu[i].observable.clone()).collect();
        options.push(Suggestion::new(
            (test, conditions, observables),
            pairs,
            runs,
        ));
    }
    (options, unscored)
}

/// A measurement of the menu that could not be ranked, and why (per rival, its runs'
/// first problem): a funnel that jams for one rival and not for another is a difference
/// the ranking cannot weigh, since the reading is missing.
#[derive(Debug, Serialize)]
pub struct Unscored {
    pub test: String,
    pub conditions: BTreeMap<String, f64>,
    pub why: Vec<String>,
}

impl Unscored {
    /// "TEST at C V, ...: WHY; WHY".
    pub fn describe(&self) -> String {
        format!(
            "{} at {}: {}",
            self.test,
            report::conditions_text(&self.conditions),
            self.why.join("; ")
        )
    }
}

/// The ranked measurements and those that could not be scored.
type Scored = (Vec<Suggestion>, Vec<Unscored>);

impl Suggestion {
    /// A measurement scored by its hardest pair.
    fn new(
        (test, conditions, observables): (String, BTreeMap<String, f64>, Vec<String>),
        pairs: Vec<Separation>,
        runs: usize,
    ) -> Suggestion {
        let w = worst(&pairs).expect("two rivals or more").clone();
        Suggestion {
            test,
            conditions,
            observables,
            separation: w.noncentrality - w.noise,
            power: w.power,
            expected_power: 0.0,
            pairs,
            runs,
        }
    }
}

/// The menu's runs, every variant's, and how a new reading is standardised.
struct Measured<'a> {
    /// [variant][menu row] -> the replicates' values.
    values: &'a [Vec<Vec<f64>>],
    variants: &'a [Variant],
    replicates: usize,
    params: usize,
    noise: &'a BTreeMap<String, Noise>,
    specimens: usize,
}

impl Measured<'_> {
    /// The standardised columns of the readings `members` (menu rows) that can be scored:
    /// every variant ran all replicates, and the reading has a standard error. Returns them
    /// with the menu rows kept.
    fn rows(&self, menu: &[Measurement], members: &[usize], rivals: usize) -> (Rows, Vec<usize>) {
        let (r, p) = (self.replicates, self.params);
        let mut kept = vec![];
        let mut free: Vec<Vec<f64>> = vec![];
        let mut riv: Vec<Vec<(f64, f64)>> = vec![];
        for &i in members {
            let fd = &self.values[0][i];
            let complete = self.values.iter().all(|v| v[i].len() == r);
            let (mean_fd, scatter) = mean_sd(fd);
            let s = scatter.unwrap_or(0.0);
            let lab = self
                .noise
                .get(&menu[i].observable)
                .map_or(s, |n| n.sd(mean_fd));
            let se = (lab * lab / self.specimens as f64 + s * s / r as f64).sqrt();
            if !complete || !(se > 0.0) {
                continue;
            }
            let slope = |c: usize| -> (f64, f64) {
                let step = self.variants[c].step;
                let d: Vec<f64> = (self.values[c][i].iter().zip(fd))
                    .map(|(a, b)| (a - b) / step / se)
                    .collect();
                let (mean, sd) = mean_sd(&d);
                (mean, sd.map_or(0.0, |x| x * x / r as f64))
            };
            free.push((1..=p).map(|c| slope(c).0).collect());
            riv.push((0..rivals).map(|k| slope(1 + p + k)).collect());
            kept.push(i);
        }
        let n = kept.len();
        let rows = Rows {
            free: DMatrix::from_fn(n, p, |a, b| free[a][b]),
            rivals: DMatrix::from_fn(n, rivals, |a, b| riv[a][b].0),
            rival_var: DMatrix::from_fn(n, rivals, |a, b| riv[a][b].1),
        };
        (rows, kept)
    }
}

/// base-fd, each free parameter's and each rival's variant, as the diagnosis made them.
fn variants_of(
    d: &Diagnosis,
    model: &Model,
    dir: &Path,
    rivals: &[String],
) -> Result<Vec<Variant>> {
    let models = dir.join("models");
    let file = |name: &str| -> Result<PathBuf> {
        let p = std::path::absolute(models.join(format!("{name}.toml")))?;
        if !p.exists() {
            bail!(
                "{}: missing; diagnose again into {}",
                p.display(),
                dir.display()
            );
        }
        Ok(p)
    };
    let mut out = vec![Variant {
        name: "base-fd".into(),
        model: file("base")?,
        step: 1.0,
    }];
    for f in &d.free_parameters {
        let key = format!("{}.{}", f.pair, f.key);
        let written = d.recalibration.iter().find(|r| r.parameter == key);
        let name = written
            .and_then(|r| r.variant.clone())
            .unwrap_or_else(|| format!("param-{key}"));
        let fraction = written.and_then(|r| r.step).unwrap_or(d.param_step);
        out.push(Variant {
            model: file(&name)?,
            step: fraction * (f.high - f.low),
            name,
        });
    }
    for n in rivals {
        let (name, step) = match n.strip_prefix(super::diagnose::HELD) {
            Some(key) => {
                let probe = d
                    .probes
                    .iter()
                    .find(|p| p.parameter == key)
                    .with_context(|| format!("--rivals: {n} is not a probe of the diagnosis"))?;
                let name = (probe.variant.clone()).unwrap_or_else(|| format!("probe-{key}"));
                (name, probe.step)
            }
            None => {
                let c = model.file.candidates.get(n).with_context(|| {
                    format!("--rivals: {n} is not a candidate of {}", d.model.display())
                })?;
                (format!("candidate-{n}"), c.step)
            }
        };
        out.push(Variant {
            model: file(&name)?,
            step,
            name,
        });
    }
    Ok(out)
}

/// The diagnosed rows' standardised columns, as diagnosis.json holds them.
fn old_rows(d: &Diagnosis, rivals: &[String], path: &Path) -> Result<Rows> {
    let m = d.rows.len();
    let mut rows = Rows {
        free: DMatrix::zeros(m, d.free_parameters.len()),
        rivals: DMatrix::zeros(m, rivals.len()),
        rival_var: DMatrix::zeros(m, rivals.len()),
    };
    for (c, f) in d.free_parameters.iter().enumerate() {
        let key = format!("{}.{}", f.pair, f.key);
        let col = d.columns.free.get(&key).filter(|v| v.len() == m);
        let col = col.with_context(|| format!("{}: no column of {key}", path.display()))?;
        rows.free
            .set_column(c, &nalgebra::DVector::from_column_slice(col));
    }
    for (k, n) in rivals.iter().enumerate() {
        let s = d
            .columns
            .candidates
            .get(n)
            .filter(|s| s.sensitivity.len() == m);
        let s = s.with_context(|| format!("{}: no column of {n}", path.display()))?;
        rows.rivals
            .set_column(k, &nalgebra::DVector::from_column_slice(&s.sensitivity));
        let var: Vec<f64> = (0..m)
            .map(|i| s.variance.get(i).copied().unwrap_or(0.0))
            .collect();
        rows.rival_var
            .set_column(k, &nalgebra::DVector::from_column_slice(&var));
    }
    Ok(rows)
}

/// The menu's rows; without an `observable` column, every observable of each row's test.
fn read_menu(path: &Path) -> Result<Vec<Measurement>> {
    let (_, head) = open_csv(path)?;
    let rows = read_conditions(path)?;
    if head.iter().any(|h| h == "observable") {
        return Ok(rows);
    }
    Ok(rows
        .into_iter()
        .flat_map(|m| {
            observables_of(&m.test)
                .into_iter()
                .map(move |(o, unit)| Measurement {
                    observable: o.to_string(),
                    unit: unit.to_string(),
                    ..m.clone()
                })
        })
        .collect())
}

/// The menu's rows grouped by test and conditions (one specimen gives all its readings).
fn group(menu: &[Measurement]) -> Vec<(String, BTreeMap<String, f64>, Vec<usize>)> {
    let mut out: Vec<(String, BTreeMap<String, f64>, Vec<usize>)> = vec![];
    for (i, m) in menu.iter().enumerate() {
        match out
            .iter_mut()
            .find(|g| g.0 == m.test && g.1 == m.conditions)
        {
            Some(g) => g.2.push(i),
            None => out.push((m.test.clone(), m.conditions.clone(), vec![i])),
        }
    }
    out
}
