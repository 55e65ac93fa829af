//! `tilth synth --truth T.toml --conditions C.csv --noise SPEC --seed S --out D.csv`:
//! measurements made by a model instead of a laboratory.
//!
//! Every row of C.csv (`test` plus the conditions that test needs, as in a measurement file)
//! is simulated with the truth model, and Gaussian noise of the given standard deviation is
//! added to the reduced observable. The output has the format of a real measurement file
//! (data/li2022/README.md), with the noise's standard deviation as `uncertainty`, so that a
//! model that lacks an effect the truth has can be compared, diagnosed and calibrated
//! against it exactly as against lab data.
//!
//! SPEC gives one standard deviation per observable: `repose_angle_deg=0.5` (absolute, in
//! the observable's unit) or `peak_shear_force_n=4%` (relative to the simulated value);
//! `0` adds no noise. With `--replicates N` each value is the mean of N truth runs (a lab
//! reports the mean of repeated tests) and `uncertainty` is sqrt(SD^2 + s^2 / N), s the runs'
//! scatter, with its Welch-Satterthwaite degrees of freedom as `uncertainty_dof` (s^2 has
//! N - 1 of them, SD is exact). Several observables of one test at the same conditions (a
//! conditions file with an `observable` column) share their runs. The DEM runs use seeds
//! derived from S, and the noise its own stream, so the same S gives the same file. The runs are kept next to the output
//! (`D.runs/<test>/`, resumable) unless `--work` says where.

use super::measurements::{
    CONDITIONS, Measurement, check_against_model, check_conditions_columns, open_csv, rows_of,
    write_measurements,
};
use crate::lab::model::Model;
use crate::study::lab_runs::{LabRunArgs, Simulate, simulate};
use crate::sweep::execute;
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use tilth_tools::compare::mean_sd;

#[derive(Debug, Args)]
pub struct SynthArgs {
    /// The truth: a model file with every effect the data should carry.
    #[arg(long)]
    pub truth: PathBuf,
    /// Conditions to "measure" (CSV: test, moisture_pct, firmness_mpa, normal_pressure_pa,
    /// and optionally observable, else the test's own; other columns, e.g. a measurement
    /// file's value, are ignored).
    #[arg(long)]
    pub conditions: PathBuf,
    /// Noise per observable: NAME=SD or NAME=PCT% (comma-separated), e.g.
    /// repose_angle_deg=0.5,peak_shear_force_n=4%,ucs_kpa=5%.
    #[arg(long)]
    pub noise: String,
    /// Hide an effect in the truth: switch the truth model's `[candidates.NAME]` on at this
    /// strength, NAME=STRENGTH (repeatable). The truth used is written next to --out
    /// (`<name>.truth.toml`).
    #[arg(long = "with")]
    pub with: Vec<String>,
    /// Move a parameter of the truth: PAIR.KEY=DELTA adds DELTA to every number of its value
    /// (as `diagnose --param` and `fit` move it), repeatable. Data from a truth whose
    /// calibrated parameter is off, with no effect hidden, test whether `diagnose` lets the
    /// free parameters absorb the misfit or blames a candidate (docs/discovery-proof.md, "A
    /// free parameter off"). Written into the truth next to --out, as --with.
    #[arg(long = "shift")]
    pub shift: Vec<String>,
    /// Tests averaged per measurement, as a lab reports the mean of repeated tests: the value
    /// is the mean of this many truth runs (different seeds) plus the noise.
    #[arg(long, default_value_t = 1)]
    pub replicates: usize,
    /// Seed of the simulations and of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The measurement file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Where the truth's runs go (default: next to --out, `<name>.runs/`).
    #[arg(long)]
    pub work: Option<PathBuf>,
    #[command(flatten)]
    pub lab: LabRunArgs,
}

/// Noise of one observable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Noise {
    /// Standard deviation in the observable's unit.
    Absolute(f64),
    /// Standard deviation as a fraction of the value.
    Relative(f64),
}

impl Noise {
    pub fn sd(self, value: f64) -> f64 {
        match self {
            Noise::Absolute(s) => s,
            Noise::Relative(f) => f * value.abs(),
        }
    }
}

/// Parses `NAME=SD,NAME=PCT%,...`.
pub fn parse_noise(spec: &str) -> Result<BTreeMap<String, Noise>> {
    let mut out = BTreeMap::new();
    for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, v) = part
            .split_once('=')
            .ok_or_else(|| anyhow!("--noise `{part}`: expected NAME=SD or NAME=PCT%"))?;
        let (name, v) = (name.trim(), v.trim());
        let all = super::measurements::OBSERVABLES;
        if !all.iter().any(|t| t.1 == name) {
            bail!(
                "--noise `{part}`: unknown observable `{name}`; allowed: {}",
                all.map(|t| t.1).join(", ")
            );
        }
        let (num, relative) = match v.strip_suffix('%') {
            Some(p) => (p.trim(), true),
            None => (v, false),
        };
        let x: f64 = num
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite() && *x >= 0.0)
            .ok_or_else(|| {
                anyhow!("--noise `{part}`: `{v}` is not a standard deviation: allowed a number >= 0, or a percentage")
            })?;
        let noise = if relative {
            Noise::Relative(x / 100.0)
        } else {
            Noise::Absolute(x)
        };
        if out.insert(name.to_string(), noise).is_some() {
            bail!("--noise: `{name}` is given twice");
        }
    }
    Ok(out)
}

/// Writes the truth with the `--with` candidates switched on and the `--shift` parameters
/// moved, next to `out`; returns its path.
fn hide_effects(model: &Model, with: &[String], shift: &[String], out: &Path) -> Result<PathBuf> {
    let text = std::fs::read_to_string(&model.path)?;
    let mut moved = vec![];
    for w in shift {
        let (path, delta) = name_and_number("shift", w, "PAIR.KEY=DELTA")?;
        if path.split_once('.').is_none() {
            bail!("--shift `{w}`: expected PAIR.KEY=DELTA, e.g. soil-soil.rolling_friction=0.05");
        }
        moved.push((path.to_string(), delta));
    }
    let mut on = vec![];
    for w in with {
        let (name, s) = name_and_number("with", w, "NAME=STRENGTH")?;
        super::model_edit::has_candidate(model, name, &format!("--with `{w}`"))?;
        on.push((name.to_string(), s));
    }
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "synth".into());
    let name = format!("{stem}.truth");
    let path = super::model_edit::variant(model, &text, dir, &name, |d| {
        for (n, s) in &on {
            super::model_edit::switch_on(d, model, n, *s)?;
        }
        for (path, delta) in &moved {
            super::model_edit::add_to(d, path, *delta)
                .with_context(|| format!("--shift {path}={delta}"))?;
        }
        Ok(())
    })?;
    Ok(std::path::absolute(path)?)
}

/// The name and the finite number of `w`, the value `NAME=NUMBER` of `--option` (`form`:
/// the shape expected, for the message).
fn name_and_number<'a>(option: &str, w: &'a str, form: &str) -> Result<(&'a str, f64)> {
    let (name, v) = w
        .split_once('=')
        .ok_or_else(|| anyhow!("--{option} `{w}`: expected {form}"))?;
    let x: f64 = v
        .trim()
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite())
        .ok_or_else(|| anyhow!("--{option} `{w}`: `{v}` is not a finite number"))?;
    Ok((name.trim(), x))
}

/// Reads the conditions file: rows of `test` and its conditions (and settings, `TEST.KEY`).
pub fn read_conditions(path: &Path) -> Result<Vec<Measurement>> {
    let (mut reader, head) = open_csv(path)?;
    let file = path.display().to_string();
    if !head.iter().any(|h| h == "test") {
        bail!(
            "{file}: no column `test`; a conditions file needs test and the conditions it uses ({})",
            CONDITIONS.join(", ")
        );
    }
    check_conditions_columns(&file, &head)?;
    let mut rows = vec![];
    for cells in rows_of(&mut reader, &head, &file) {
        let c = cells?;
        let (test, mut observable, mut unit) = c.test()?;
        if c.has("observable") && !c.cell("observable").is_empty() {
            (observable, unit) = c.observable(&test)?;
        }
        rows.push(Measurement {
            row: c.row,
            conditions: c.conditions(&test)?,
            test,
            observable: observable.to_string(),
            value: f64::NAN,
            unit: unit.to_string(),
            uncertainty: None,
            uncertainty_dof: None,
            replicates: Some(1),
            source: String::new(),
        });
    }
    if rows.is_empty() {
        bail!("{file}: no rows");
    }
    Ok(rows)
}

pub fn synth(args: &SynthArgs) -> Result<String> {
    crate::study::summary(|out| synth_into(args, out))
}

/// [`synth`], writing its summary to `out`.
fn synth_into(args: &SynthArgs, out: &mut dyn Write) -> Result<()> {
    let set = args.lab.set.parse()?;
    let mut truth = std::path::absolute(&args.truth)?;
    let mut model = Model::load(&truth)?;
    if !args.with.is_empty() || !args.shift.is_empty() {
        truth = hide_effects(&model, &args.with, &args.shift, &args.out)?;
        model = Model::load(&truth)?;
    }
    let mut rows = read_conditions(&args.conditions)?;
    check_against_model(&rows, &model, &args.conditions)?;
    let noise = parse_noise(&args.noise)?;
    if !(1..=100).contains(&args.replicates) {
        bail!(
            "--replicates {}: allowed 1 to 100 truth runs per measurement",
            args.replicates
        );
    }
    for m in &rows {
        if !noise.contains_key(&m.observable) {
            bail!(
                "--noise gives no standard deviation for {} ({}: row {} is a {} test); add {}=SD",
                m.observable,
                args.conditions.display(),
                m.row,
                m.test,
                m.observable
            );
        }
    }
    let work = args.work.clone().unwrap_or_else(|| {
        let stem = args
            .out
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "synth".into());
        args.out.with_file_name(format!("{stem}.runs"))
    });
    let stop = execute::stop_on_signals()?;
    // Seeds of the truth's runs: a block of its own per --seed.
    let first_seed = 1 + 1000 * args.seed;
    let sims = simulate(
        &rows,
        &Simulate {
            model: &truth,
            data: &args.conditions,
            out: &work,
            replicates: args.replicates,
            first_seed,
            lab: &args.lab,
            set: &set,
        },
        &stop,
    )?;
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let source = format!(
        "synth: truth {}{}{}, seed {}, noise {}{}",
        args.truth.display(),
        if args.with.is_empty() {
            String::new()
        } else {
            format!(" with {}", args.with.join(" and "))
        },
        if args.shift.is_empty() {
            String::new()
        } else {
            format!(" shifted {}", args.shift.join(" and "))
        },
        args.seed,
        args.noise,
        if args.lab.coarse { ", coarse" } else { "" }
    );
    for (m, (values, problems)) in rows.iter_mut().zip(sims) {
        if values.len() < args.replicates {
            bail!(
                "{}: row {}: {} of the truth's {} {} runs gave no {}: {}",
                args.conditions.display(),
                m.row,
                args.replicates - values.len(),
                args.replicates,
                m.test,
                m.observable,
                problems.join("; ")
            );
        }
        let (v, scatter) = mean_sd(&values);
        let sd = noise[&m.observable].sd(v);
        let e = if sd > 0.0 {
            Normal::new(0.0, sd)?.sample(&mut rng)
        } else {
            0.0
        };
        m.value = v + e;
        // What the value is uncertain by: the noise and the standard error of the mean of
        // the truth's runs (their scatter is part of what a lab's repeated tests show).
        let se = scatter.map_or(0.0, |s| s / (values.len() as f64).sqrt());
        let u = sd.hypot(se);
        m.uncertainty = (u > 0.0).then_some(u);
        let dof = tilth_tools::compare::welch::residual_dof(
            scatter,
            values.len(),
            Some(sd).filter(|s| *s > 0.0),
            None,
        );
        m.uncertainty_dof = (u > 0.0 && dof.is_finite()).then_some(dof);
        m.replicates = Some(args.replicates as u32);
        m.source = source.replace(',', ";");
    }
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    write_measurements(&args.out, &rows)?;
    writeln!(
        out,
        "wrote {} synthetic measurements to {} (truth runs in {})",
        rows.len(),
        args.out.display(),
        args.lab.cache.as_ref().unwrap_or(&work).display()
    )?;
    Ok(())
}
