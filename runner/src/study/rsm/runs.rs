//! The table of runs an `rsm` command fits: read, keep the finished runs, filter with
//! `--where`, code the factors with `--ranges` or `--levels`, rename with `--names`.

use super::ModelArgs;
use anyhow::{Context, Result, bail};
use tilth_tools::rsm::{Data, Table};

/// `LABEL=VALUE` or `VALUE`.
pub fn labelled(item: &str, what: &str) -> Result<(String, f64)> {
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

pub fn load(m: &ModelArgs) -> Result<Data> {
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
