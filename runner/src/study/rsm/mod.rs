//! `tilth rsm fit|solve|path|next`: response surfaces on tables of runs. The maths is in
//! `tilth_tools::rsm`; here the table of runs is read and filtered ([`runs`]), the pictures
//! written ([`plot`]) and the results put in Design-Expert's layout ([`print`]).

pub mod plot;
pub mod print;
pub mod runs;

use anyhow::{Context, Result, bail};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::rsm::{self, Anova, Data, FitOptions, Order, Table};

use runs::labelled;

#[derive(Debug, Args)]
pub struct PathArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Factors on the path (default: those whose first-order p-value is below 0.05).
    #[arg(long, value_delimiter = ',')]
    pub on: Vec<String>,
    /// Coded step of the leading factor per point.
    #[arg(long, default_value_t = 1.0)]
    pub step: f64,
    /// Points on the path, the centre included.
    #[arg(long, default_value_t = 6)]
    pub steps: usize,
    /// Descend instead (to minimise the response).
    #[arg(long)]
    pub descent: bool,
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct NextArgs {
    /// The path's results (CSV), rows in path order.
    pub csv: PathBuf,
    #[arg(long)]
    pub response: String,
    #[arg(long, value_delimiter = ',', required = true)]
    pub factors: Vec<String>,
    /// Targets (VALUE or LABEL=VALUE): the best run minimises the sum of squared relative
    /// misses over them; without targets, the largest response is best.
    #[arg(long = "target", value_delimiter = ',')]
    pub targets: Vec<String>,
    /// Rows on each side of the best one that set the next ranges (the study used 2).
    #[arg(long, default_value_t = 1)]
    pub neighbours: usize,
    #[arg(long)]
    pub json: bool,
}

/// Which runs and which model.
#[derive(Debug, Args)]
pub struct ModelArgs {
    /// Table of runs (CSV with a header): a sweep's results.csv or a study's table.
    pub csv: PathBuf,
    /// Response column.
    #[arg(long)]
    pub response: String,
    /// Factor columns, comma-separated (names are kept in the output).
    #[arg(long, value_delimiter = ',', required = true)]
    pub factors: Vec<String>,
    /// linear, 2fi or quadratic.
    #[arg(long, default_value = "linear")]
    pub model: String,
    /// Real levels coded -1 and +1, e.g. `x4=0.25:0.65,x6=0.15:0.35` (default: each factor's
    /// smallest and largest value in the table).
    #[arg(long, value_delimiter = ',')]
    pub ranges: Vec<String>,
    /// The factor columns hold coded values (-1..+1) whose real levels are these, e.g.
    /// `x4=0.25:0.65,...`: the equation in real units uses them.
    #[arg(long, value_delimiter = ',', conflicts_with = "ranges")]
    pub levels: Vec<String>,
    /// Names for the factors in the output, in the order of --factors (default: the
    /// column names).
    #[arg(long, value_delimiter = ',')]
    pub names: Vec<String>,
    /// Only rows where a column has a value, `moisture_pct=6`, or lies in a closed range,
    /// `tau_c=200000:400000` (either end may be left out: `tau_c=:400000`); repeatable, all
    /// must hold.
    #[arg(long = "where")]
    pub filters: Vec<String>,
    /// Add the centre points' curvature term (screening designs).
    #[arg(long = "centre-curvature", alias = "center-curvature")]
    pub curvature: bool,
    /// Backward elimination of terms with p above ALPHA (default 0.1), keeping hierarchy.
    #[arg(long, num_args = 0..=1, default_missing_value = "0.1")]
    pub backward: Option<f64>,
}

#[derive(Debug, Args)]
pub struct FitArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// A published ANOVA table to check against (CSV with a `source` column).
    #[arg(long)]
    pub reported: Option<PathBuf>,
    /// The column of `--reported` that holds this response's p-values (one column per
    /// response, as in a per-moisture table).
    #[arg(long = "reported-column")]
    pub reported_column: Option<String>,
    /// Write Pareto, main-effects and predicted-vs-actual SVGs here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// One JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct SolveArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Targets, as VALUE or LABEL=VALUE, comma-separated or repeated (e.g. `3%=32.76,6%=35.53`).
    #[arg(long = "target", value_delimiter = ',', required = true)]
    pub targets: Vec<String>,
    /// Hold factors at real values, e.g. `x4=0.45` (repeatable or comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub fix: Vec<String>,
    /// Settings to print per target (evenly spaced along the solutions; JSON has them all).
    #[arg(long, default_value_t = 11)]
    pub show: usize,
    /// Draw each target's contour plot here (two free factors), or the response against the
    /// one free factor with every target on it (`solve-RESPONSE.svg`).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

fn write_path(a: &PathArgs, out: &mut dyn Write) -> Result<()> {
    let (_, anova) = load_and_fit(&a.model)?;
    let on: Vec<usize> = if a.on.is_empty() {
        anova
            .terms
            .iter()
            .filter(|t| t.p.is_some_and(|p| p < 0.05))
            .filter_map(|t| anova.factors.iter().position(|f| *f == t.name))
            .collect()
    } else {
        a.on.iter()
            .map(|n| {
                anova.factors.iter().position(|f| f == n).with_context(|| {
                    format!(
                        "--on {n}: not a factor (factors: {})",
                        anova.factors.join(", ")
                    )
                })
            })
            .collect::<Result<_>>()?
    };
    if on.is_empty() {
        bail!("no first-order term has p < 0.05: name the factors of the path with --on");
    }
    let p = rsm::steepest_path(&anova, &on, a.step, a.steps, a.descent)?;
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&p)?)?;
        return Ok(());
    }
    writeln!(
        out,
        "path of steepest {} along {} (coded direction {}), step {} coded units of the leading factor",
        if a.descent { "descent" } else { "ascent" },
        p.factors.join(", "),
        p.direction
            .iter()
            .map(|d| format!("{d:.4}"))
            .collect::<Vec<_>>()
            .join(", "),
        p.step
    )?;
    write!(out, "{:>5}", "point")?;
    for f in &anova.factors {
        write!(out, "{f:>12}")?;
    }
    writeln!(out, "{:>14}", "predicted")?;
    for (k, (x, y)) in p.real.iter().zip(&p.predicted).enumerate() {
        write!(out, "{:>5}", k + 1)?;
        for v in x {
            write!(out, "{v:>12.5}")?;
        }
        writeln!(out, "{y:>14.4}")?;
    }
    writeln!(
        out,
        "\n# the same path as a sweep design (factors keep their low/high of the fit):"
    )?;
    writeln!(out, "[design]\ntype = \"steepest_ascent\"")?;
    let table = |v: &[f64]| {
        p.factors
            .iter()
            .zip(v)
            .map(|(f, d)| format!("{f} = {d}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    writeln!(out, "direction = {{ {} }}", table(&p.direction))?;
    writeln!(out, "origin = {{ {} }}", table(&vec![0.0; p.factors.len()]))?;
    writeln!(out, "step = {}\nsteps = {}", p.step, a.steps)?;
    writeln!(
        out,
        "\nnote: predictions along the path leave the fitted region; run the path, then `tilth rsm next` on its results"
    )?;
    Ok(())
}

fn write_next(a: &NextArgs, out: &mut dyn Write) -> Result<()> {
    let table = Table::read(&a.csv)?;
    let targets: Vec<f64> = a
        .targets
        .iter()
        .map(|t| labelled(t, "--target").map(|x| x.1))
        .collect::<Result<_>>()?;
    let r = rsm::next_region(&table, &a.factors, &a.response, &targets, a.neighbours)?;
    if a.json {
        writeln!(out, "{}", serde_json::to_string_pretty(&r)?)?;
    } else {
        writeln!(out, "{}", r.statement)?;
    }
    Ok(())
}

fn write_solve(a: &SolveArgs, out: &mut dyn Write) -> Result<()> {
    let (_, anova) = load_and_fit(&a.model)?;
    let mut fixed = Vec::new();
    for f in &a.fix {
        let (name, v) = labelled(f, "--fix")?;
        let k = anova
            .factors
            .iter()
            .position(|n| *n == name)
            .with_context(|| {
                format!(
                    "--fix {f:?}: {name} is not a factor (factors: {})",
                    anova.factors.join(", ")
                )
            })?;
        let (lo, hi) = (anova.coding.low[k], anova.coding.high[k]);
        if !(lo.min(hi)..=lo.max(hi)).contains(&v) {
            bail!("--fix {f:?}: {v} is outside the design's range of {name}, allowed [{lo}, {hi}]");
        }
        fixed.push((k, v));
    }
    let mut solutions = Vec::new();
    for t in &a.targets {
        let (label, value) = labelled(t, "--target")?;
        solutions.push(rsm::solve(&anova, &label, value, &fixed)?);
    }
    if let Some(dir) = &a.plot {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        for s in &solutions {
            if let Some(path) = plot::contour(&anova, s, &fixed, dir)? {
                eprintln!("plot {}", path.display());
            }
        }
        if let Some(path) = plot::curve(&anova, &solutions, &fixed, dir)? {
            eprintln!("plot {}", path.display());
        }
    }
    if a.json {
        let v = serde_json::json!({
            "response": anova.response,
            "factors": anova.factors,
            "fixed": fixed.iter().map(|(k, v)| (anova.factors[*k].clone(), *v)).collect::<Vec<_>>(),
            "r2": anova.r2,
            "solutions": solutions,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?)?;
        return Ok(());
    }
    writeln!(out, "{}", anova.equation_real)?;
    writeln!(
        out,
        "(R^2 {:.4}, adjusted {:.4}, {} runs)",
        anova.r2,
        anova.adj_r2.unwrap_or(f64::NAN),
        anova.runs
    )?;
    for s in &solutions {
        print::solution(&anova, s, a.show, out)?;
    }
    Ok(())
}

/// Reads, filters and fits what `m` asks for.
pub fn load_and_fit(m: &ModelArgs) -> Result<(Data, Anova)> {
    let (data, options) = prepare(m)?;
    let anova = rsm::fit(&data, options)?;
    Ok((data, anova))
}

/// The runs and the fit options `m` asks for.
pub fn prepare(m: &ModelArgs) -> Result<(Data, FitOptions)> {
    let data = runs::load(m)?;
    let order = Order::parse(&m.model).with_context(|| {
        format!(
            "--model {:?} is not a model: allowed linear, 2fi, quadratic",
            m.model
        )
    })?;
    if let Some(a) = m.backward {
        if !(a > 0.0 && a < 1.0) {
            bail!("--backward {a} is out of range: allowed (0, 1)");
        }
    }
    Ok((
        data,
        FitOptions {
            order,
            curvature: m.curvature,
            backward: m.backward,
        },
    ))
}

fn write_fit(a: &FitArgs, out: &mut dyn Write) -> Result<()> {
    let (data, options) = prepare(&a.model)?;
    let anova = rsm::fit(&data, options)?;
    let checks = match &a.reported {
        Some(p) => Some(rsm::compare_reported(
            &anova,
            &data,
            options,
            &Table::read(p)?,
            a.reported_column.as_deref(),
        )?),
        None => None,
    };
    if let Some(dir) = &a.plot {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        for p in plot::fit(&anova, dir)? {
            eprintln!("plot {}", p.display());
        }
    }
    if a.json {
        let mut v = serde_json::to_value(&anova)?;
        if let Some(c) = &checks {
            v["reported_check"] = serde_json::to_value(c)?;
        }
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?)?;
        return Ok(());
    }
    print::anova(&anova, out)?;
    if let (Some(c), Some(p)) = (&checks, &a.reported) {
        print::checks(c, &p.display().to_string(), out)?;
    }
    Ok(())
}

/// `tilth rsm fit`: the ANOVA of the model the arguments ask for (text or JSON), with the
/// published table's check and the plots when asked.
pub fn fit(a: &FitArgs) -> Result<String> {
    super::summary(|out| write_fit(a, out))
}

/// `tilth rsm solve`: the settings that hit each target.
pub fn solve(a: &SolveArgs) -> Result<String> {
    super::summary(|out| write_solve(a, out))
}

/// `tilth rsm path`: the path of steepest ascent or descent, and its sweep design.
pub fn path(a: &PathArgs) -> Result<String> {
    super::summary(|out| write_path(a, out))
}

/// `tilth rsm next`: the best run of a path and the next design's ranges.
pub fn next(a: &NextArgs) -> Result<String> {
    super::summary(|out| write_next(a, out))
}
