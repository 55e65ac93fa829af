//! `diagnosis.json` as `tilth fit --from-diagnosis` and `tilth next` read it back.

use crate::study::calibrate::Param;
use anyhow::{Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tilth_tools::diagnose::verdict::Verdict;

#[derive(Deserialize)]
pub struct DiagnosisFile {
    pub model: PathBuf,
    pub replicates: usize,
    pub coarse: bool,
    pub param_step: f64,
    pub alpha: f64,
    pub free_parameters: Vec<Param>,
    #[serde(default)]
    pub probes: Vec<Probe>,
    pub verdict: Verdict,
    pub candidates: Vec<CandidateIn>,
    pub rows: Vec<serde_json::Value>,
    pub columns: ColumnsIn,
    /// Each free parameter's step and variant (absent before steps were lengthened: then
    /// `param_step` and `param-PAIR.KEY`).
    #[serde(default)]
    pub recalibration: Vec<RecalibrationIn>,
    /// The contenders' fits (absent with `--no-refit`).
    #[serde(default)]
    pub refit: Option<RefitIn>,
}

/// A free parameter's finite difference, as far as it is read back.
#[derive(Deserialize)]
pub struct RecalibrationIn {
    pub parameter: String,
    pub step: Option<f64>,
    pub variant: Option<String>,
}

/// The refit, as far as it is read back.
#[derive(Deserialize)]
pub struct RefitIn {
    pub free: NullIn,
    pub contenders: Vec<ContenderIn>,
}

/// The free parameters' own fit.
#[derive(Deserialize)]
pub struct NullIn {
    pub dir: PathBuf,
    /// Its misfit, sum of z^2 over the rows.
    #[serde(default)]
    pub chi2: Option<f64>,
}

/// One contender's fit: its name, fitted strength and directory (with `model.toml`).
#[derive(Deserialize)]
pub struct ContenderIn {
    pub name: String,
    /// None when its fit failed.
    pub strength: Option<f64>,
    pub dir: PathBuf,
    /// Its misfit at the fitted strength; None when the fit failed.
    #[serde(default)]
    pub chi2: Option<f64>,
}

/// A held parameter the diagnosis probed, with its step as measured (lengthened or not).
#[derive(Deserialize)]
pub struct Probe {
    pub parameter: String,
    pub step: f64,
    /// Its model's variant (`probe-KEY`, or `probe-KEY-step-STEP` once lengthened).
    pub variant: Option<String>,
}

/// A candidate's score, as far as it is read back.
#[derive(Deserialize)]
pub struct CandidateIn {
    pub name: String,
    pub strength: f64,
    /// Its score statistic against no effect: the drop in chi^2 it would bring, linearised.
    #[serde(default)]
    pub statistic: f64,
}

/// The standardised columns, one number per entry of `rows`.
#[derive(Deserialize)]
pub struct ColumnsIn {
    pub free: BTreeMap<String, Vec<f64>>,
    pub candidates: BTreeMap<String, Signature>,
}

#[derive(Deserialize)]
pub struct Signature {
    pub sensitivity: Vec<f64>,
    pub variance: Vec<f64>,
}

/// Reads `dir/diagnosis.json`; `what` names the option that asked for it.
pub fn read(dir: &Path, what: &str) -> Result<(DiagnosisFile, PathBuf)> {
    let path = dir.join("diagnosis.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{what}: cannot read {}", path.display()))?;
    let d = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not a diagnosis with a verdict and columns (written by `tilth diagnose` of this version?)",
            path.display()
        )
    })?;
    Ok((d, path))
}
