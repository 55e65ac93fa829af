//! What a diagnosis weighs: the candidates asked for, and the held parameters probed beside
//! them (the model file's `[probes]` with `--probe`'s, less the free parameters).

use super::DiagnoseArgs;
use crate::lab::model::Model;
use crate::study::calibrate::Param;
use anyhow::{Result, bail};

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
pub(super) fn check_candidates(
    names: &[String],
    model: &Model,
    path: &std::path::Path,
) -> Result<()> {
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

/// The held parameters to probe, in order: the model file's `[probes]` (unless
/// `--no-model-probes`), then `--probe`'s; a `--probe` of a key the file probes replaces its
/// step. A free parameter (`--param`) is not probed: the recalibration moves it already.
pub(super) fn probes(
    args: &DiagnoseArgs,
    model: &Model,
    params: &[Param],
) -> Result<Vec<(String, f64)>> {
    let file = model.path.display();
    let mut probes: Vec<(String, f64)> = vec![];
    if !args.no_model_probes {
        for (key, &step) in &model.file.probes {
            if !(step.is_finite() && step != 0.0) {
                bail!(
                    "{file}: probes.\"{key}\" = {step} is out of range: allowed a non-zero number (the step the parameter is raised by)"
                );
            }
            check_probed(model, key)
                .map_err(|e| anyhow::anyhow!("{file}: probes.\"{key}\": {e}"))?;
            probes.push((key.clone(), step));
        }
    }
    for s in &args.probes {
        let (key, step) = parse_probe(s)?;
        check_probed(model, &key).map_err(|e| anyhow::anyhow!("--probe {s:?}: {e}"))?;
        match probes.iter_mut().find(|(k, _)| *k == key) {
            Some(p) => p.1 = step,
            None => probes.push((key, step)),
        }
    }
    probes.retain(|(key, _)| {
        !params
            .iter()
            .any(|p| format!("{}.{}", p.pair, p.key) == *key)
    });
    Ok(probes)
}

/// A probe's PAIR names a pair of the model's `[pairs]` or `[bond.pairs]`, or `particles`.
fn check_probed(model: &Model, key: &str) -> Result<()> {
    let (pair, _) = key
        .split_once('.')
        .ok_or_else(|| anyhow::anyhow!("expected PAIR.KEY, e.g. soil-soil.surface_energy"))?;
    let bonded = model
        .file
        .bond
        .as_ref()
        .is_some_and(|b| b.pairs.contains_key(pair));
    if !(model.file.pairs.contains_key(pair) || bonded || pair == "particles") {
        let known: Vec<&str> = model.file.pairs.keys().map(String::as_str).collect();
        bail!(
            "`{pair}` is not a pair of the model; its pairs are {}",
            known.join(", ")
        );
    }
    Ok(())
}
