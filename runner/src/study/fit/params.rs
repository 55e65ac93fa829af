//! The free parameters of a fit: what `--param` and `--from-diagnosis` ask for, their
//! bounds and starts, and the model file with them set.

use super::FitArgs;
use super::from_diagnosis::params_from_diagnosis;
use crate::lab::model::Model;
use crate::study::model_edit::{add_to, has_candidate, switch_on, values_of};
use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;

/// The free parameters: every `--param`, then each of `--from-diagnosis`'s that no
/// `--param` names (an explicit range wins over the diagnosis's).
pub(super) fn free_params(
    args: &FitArgs,
    model: &Model,
    doc: &toml_edit::DocumentMut,
) -> Result<Vec<FreeParam>> {
    let mut asked = args.params.clone();
    if let Some(dir) = &args.from_diagnosis {
        let step = |name: &str| model.file.candidates.get(name).map(|c| c.step);
        for p in params_from_diagnosis(dir, &step)? {
            let label = p.split('=').next().unwrap_or_default().to_string();
            if !asked
                .iter()
                .any(|a| a.split('=').next() == Some(label.as_str()))
            {
                asked.push(p);
            }
        }
    }
    asked
        .iter()
        .map(|s| parse(s, model, doc))
        .collect::<Result<_>>()
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

/// One `--param`: its target, and the bounds of its value (for an offset, shifted by the
/// model's lowest and highest value so that every point of its table stays in range).
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
        has_candidate(model, name, &format!("--param {s:?}"))?;
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
pub(super) fn apply(
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

/// A parameter's name and what its value means, for the report.
pub(super) fn describe(p: &FreeParam) -> String {
    match &p.target {
        Target::Offset { path } => format!("{path} (offset)"),
        Target::Candidate { name } => format!("candidate {name} (strength)"),
    }
}

/// A setting, parameter by parameter, for progress lines and headers.
pub(super) fn show(params: &[FreeParam], theta: &[f64]) -> String {
    params
        .iter()
        .zip(theta)
        .map(|(p, v)| format!("{} {v:+.4}", p.label))
        .collect::<Vec<_>>()
        .join(", ")
}
