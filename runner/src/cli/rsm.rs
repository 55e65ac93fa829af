//! `tilth rsm fit|solve|path`: response surfaces on tables of runs (the work is in
//! `tilth_tools::rsm`).

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::rsm::{self, Anova, Data, FitOptions, Order, Table};

#[derive(Debug, Subcommand)]
pub enum RsmCommand {
    /// Fit a linear, 2FI or quadratic model and print its ANOVA (Type III), R^2, adjusted
    /// and predicted R^2, adequate precision, and the equation in coded and real units.
    Fit(FitArgs),
    /// Every setting whose predicted response hits a target (one per condition): a ridge
    /// when one target cannot separate the factors, and a statement saying so.
    Solve(SolveArgs),
    /// The path of steepest ascent (or descent) from a first-order fit, as a table and as the
    /// `[design]` block of a sweep file.
    Path(PathArgs),
    /// The best run of a path that was run (closest to the targets) and the next design's
    /// ranges around it.
    Next(NextArgs),
}

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

pub fn rsm(cmd: &RsmCommand, out: &mut dyn Write) -> Result<()> {
    match cmd {
        RsmCommand::Fit(a) => fit(a, out),
        RsmCommand::Solve(a) => solve(a, out),
        RsmCommand::Path(a) => path(a, out),
        RsmCommand::Next(a) => next(a, out),
    }
}

fn path(a: &PathArgs, out: &mut dyn Write) -> Result<()> {
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

fn next(a: &NextArgs, out: &mut dyn Write) -> Result<()> {
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

/// `LABEL=VALUE` or `VALUE`.
fn labelled(item: &str, what: &str) -> Result<(String, f64)> {
    let (label, value) = match item.rsplit_once('=') {
        Some((l, v)) => (l.trim().to_string(), v.trim()),
        None => (item.trim().to_string(), item.trim()),
    };
    let v: f64 = value
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite())
        .with_context(|| format!("{what} {item:?}: {value:?} is not a number"))?;
    Ok((label, v))
}

fn solve(a: &SolveArgs, out: &mut dyn Write) -> Result<()> {
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
            if let Some(path) = crate::study::rsm_plot::contour(&anova, s, &fixed, dir)? {
                eprintln!("plot {}", path.display());
            }
        }
        if let Some(path) = crate::study::rsm_plot::curve(&anova, &solutions, &fixed, dir)? {
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
        super::rsm_print::solution(&anova, s, a.show, out)?;
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
    let data = load(m)?;
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

fn load(m: &ModelArgs) -> Result<Data> {
    let mut table = Table::read(&m.csv)?;
    // A sweep's results table: runs that did not finish have no trustworthy response.
    if let Ok(status) = table.text("status") {
        let keep: Vec<bool> = status.iter().map(|s| s == "done").collect();
        let dropped: Vec<String> = table
            .lines
            .iter()
            .zip(&keep)
            .filter(|(_, k)| !**k)
            .map(|(l, _)| l.to_string())
            .collect();
        if !dropped.is_empty() {
            eprintln!(
                "warning: {}: {} run(s) whose status is not `done` left out (lines {})",
                m.csv.display(),
                dropped.len(),
                dropped.join(", ")
            );
            table = table.filter(&keep);
        }
    }
    for f in &m.filters {
        let (col, cond) = parse_where(f)?;
        let cells = table.text(col)?;
        let keep: Vec<bool> = cells.iter().map(|c| cond.holds(c)).collect();
        table = table.filter(&keep);
        if table.rows.is_empty() {
            bail!("{}: no row has {col} {}", m.csv.display(), cond.describe());
        }
    }
    let ranges = parse_ranges(&m.ranges, &m.factors, "--ranges")?;
    let mut data = Data::from_table(&table, &m.factors, &m.response, ranges.as_deref())?;
    if let Some(levels) = parse_ranges(&m.levels, &m.factors, "--levels")? {
        data = data.from_coded(&levels);
    }
    if !m.names.is_empty() {
        data = data.renamed(&m.names)?;
    }
    Ok(data)
}

/// What `--where COLUMN=...` asks of a cell.
#[derive(Debug, PartialEq)]
enum Where {
    /// `COLUMN=VALUE`: the same text, or the same number (`6` matches `6.0`).
    Equal(String),
    /// `COLUMN=LO:HI`, either end optional: a number within the closed range.
    Within(Option<f64>, Option<f64>),
}

impl Where {
    fn holds(&self, cell: &str) -> bool {
        let x = cell.trim().parse::<f64>().ok();
        match self {
            Where::Equal(want) => {
                cell == want || matches!((x, want.parse::<f64>()), (Some(a), Ok(b)) if a == b)
            }
            Where::Within(lo, hi) => {
                x.is_some_and(|x| lo.is_none_or(|lo| x >= lo) && hi.is_none_or(|hi| x <= hi))
            }
        }
    }

    fn describe(&self) -> String {
        match self {
            Where::Equal(v) => format!("= {v}"),
            Where::Within(lo, hi) => format!(
                "in [{}, {}]",
                lo.map_or("-inf".into(), |v| v.to_string()),
                hi.map_or("inf".into(), |v| v.to_string())
            ),
        }
    }
}

/// `COLUMN=VALUE` or `COLUMN=LO:HI` (see `--where`).
fn parse_where(f: &str) -> Result<(&str, Where)> {
    let (col, value) = f
        .split_once('=')
        .with_context(|| format!("--where {f:?}: expected COLUMN=VALUE or COLUMN=LO:HI"))?;
    let (col, value) = (col.trim(), value.trim());
    let Some((lo, hi)) = value.split_once(':') else {
        return Ok((col, Where::Equal(value.to_string())));
    };
    let end = |s: &str| -> Result<Option<f64>> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => bail!(
                "--where {f:?}: {s:?} is not a number (COLUMN=LO:HI takes numbers; either end may be left out)"
            ),
        }
    };
    let (lo, hi) = (end(lo)?, end(hi)?);
    match (lo, hi) {
        (None, None) => bail!("--where {f:?}: a range needs at least one end, LO:HI"),
        (Some(a), Some(b)) if a > b => {
            bail!("--where {f:?}: the range's low end {a} is above its high end {b}")
        }
        _ => Ok((col, Where::Within(lo, hi))),
    }
}

fn parse_ranges(
    list: &[String],
    factors: &[String],
    flag: &str,
) -> Result<Option<Vec<(f64, f64)>>> {
    if list.is_empty() {
        return Ok(None);
    }
    let mut out = vec![None; factors.len()];
    for item in list {
        let (name, range) = item
            .split_once('=')
            .with_context(|| format!("{flag} {item:?}: expected FACTOR=LOW:HIGH"))?;
        let k = factors
            .iter()
            .position(|f| f == name.trim())
            .with_context(|| format!("{flag} {item:?}: {name} is not one of --factors"))?;
        let (lo, hi) = range
            .split_once(':')
            .with_context(|| format!("{flag} {item:?}: expected FACTOR=LOW:HIGH"))?;
        let parse = |s: &str| {
            s.trim()
                .parse::<f64>()
                .with_context(|| format!("{flag} {item:?}: {s:?} is not a number"))
        };
        out[k] = Some((parse(lo)?, parse(hi)?));
    }
    out.into_iter()
        .zip(factors)
        .map(|(r, f)| {
            r.with_context(|| format!("{flag}: no range for factor {f} (give all or none)"))
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

fn fit(a: &FitArgs, out: &mut dyn Write) -> Result<()> {
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
        for p in crate::study::rsm_plot::fit(&anova, dir)? {
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
    super::rsm_print::anova(&anova, out)?;
    if let (Some(c), Some(p)) = (&checks, &a.reported) {
        super::rsm_print::checks(c, &p.display().to_string(), out)?;
    }
    Ok(())
}
