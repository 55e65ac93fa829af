//! Sweep files: TOML naming a scene, factors with levels or ranges, a design and fixed values.
//!
//! ```toml
//! format_version = 1
//! name = "demo"                          # default: the file's stem
//! [experiment]
//! scene = "scenes/pile.toml"             # a scene or an experiment file, relative to this one
//! threads = 1                            # per run: 1, or 2 for a large run
//! [design]
//! type = "plackett_burman"               # see DesignKind
//! centre_points = 3
//! [[factors]]
//! name = "x1"
//! target = "pairs[soil-steel].restitution"
//! low = 0.2
//! high = 0.5
//! [fixed]
//! "simulation.duration" = 0.4
//! [record]
//! particles_hz = 50
//! ```
//!
//! Errors carry the file and the line (from the TOML spans) and say what is allowed.

use crate::record::RecordSection;
use anyhow::{Result, anyhow, bail};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The only sweep format this build reads.
pub const FORMAT_VERSION: i64 = 1;

/// A sweep file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    pub format_version: Spanned<i64>,
    /// Shown in tables and used for the default output directory (default: the file stem).
    pub name: Option<String>,
    pub description: Option<String>,
    pub experiment: ExperimentSection,
    pub design: Spanned<toml::Table>,
    #[serde(default)]
    pub factors: Vec<Spanned<FactorSection>>,
    /// Scene values set in every run: target path -> value.
    #[serde(default)]
    pub fixed: BTreeMap<String, Spanned<toml::Value>>,
    #[serde(default)]
    pub record: RecordSection,
}

/// `[experiment]`: what one run is.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentSection {
    /// Scene file (TOML), relative to the sweep file.
    pub scene: Spanned<String>,
    /// Worker threads per run (1 or 2); the scheduler keeps the sum within `--cores`.
    #[serde(default = "one")]
    pub threads: Spanned<usize>,
}

fn one() -> Spanned<usize> {
    Spanned::new(0..0, 1)
}

/// `[[factors]]`: one varied scene value.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FactorSection {
    /// Short name used in tables and JSON (`x1`, `friction`).
    pub name: Spanned<String>,
    /// Where the value goes in the scene: a dotted path, `[k]` or `[name]` to pick from an
    /// array of tables (`pairs[soil-steel].friction`, `walls[floor].point`). When the sweep
    /// runs an experiment file, the path is into that file (`conditions.moisture_pct`,
    /// `repose.drop_height`), and `scene:PATH` sets a value in the scene the experiment
    /// builds (`scene:pairs[soil-soil].rolling_friction`).
    pub target: Spanned<String>,
    /// What it is, for people (`soil-steel restitution`).
    pub label: Option<String>,
    pub unit: Option<String>,
    /// The real value at coded -1.
    pub low: Option<f64>,
    /// The real value at coded +1.
    pub high: Option<f64>,
    /// Explicit real levels (full factorial only), in increasing order.
    pub levels: Option<Vec<f64>>,
}

/// A file's text and name, for messages with line numbers.
pub struct Source {
    pub path: PathBuf,
    pub text: String,
}

impl Source {
    /// `file:line` of a byte range in the text.
    pub fn at(&self, span: &Range<usize>) -> String {
        let line = self.text[..span.start.min(self.text.len())]
            .bytes()
            .filter(|&b| b == b'\n')
            .count()
            + 1;
        format!("{}:{line}", self.path.display())
    }

    /// An error at `span`: `file:line: message`.
    pub fn err(&self, span: &Range<usize>, msg: impl std::fmt::Display) -> anyhow::Error {
        anyhow!("{}: {msg}", self.at(span))
    }

    /// The directory relative paths in the file are taken from.
    pub fn dir(&self) -> PathBuf {
        self.path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    }
}

/// Reads and parses a sweep file; syntax and unknown keys are refused with their line.
pub fn parse(source: &Source) -> Result<SweepFile> {
    let file: SweepFile = toml::from_str(&source.text).map_err(|e| {
        let at = e
            .span()
            .map(|s| source.at(&s))
            .unwrap_or_else(|| source.path.display().to_string());
        anyhow!("{at}: {}", e.message())
    })?;
    if *file.format_version.get_ref() != FORMAT_VERSION {
        return Err(source.err(
            &file.format_version.span(),
            format!(
                "format_version = {} is not supported; this tilth reads sweep format_version = {FORMAT_VERSION}",
                file.format_version.get_ref()
            ),
        ));
    }
    let threads = *file.experiment.threads.get_ref();
    if !(1..=2).contains(&threads) {
        return Err(source.err(
            &file.experiment.threads.span(),
            format!("experiment.threads = {threads} is out of range: allowed 1 or 2"),
        ));
    }
    check_factors(source, &file.factors, &file.design)?;
    Ok(file)
}

fn check_factors(
    source: &Source,
    factors: &[Spanned<FactorSection>],
    design: &Spanned<toml::Table>,
) -> Result<()> {
    // A `replicates` design runs one setting over several seeds: it has no factors, and
    // every other design needs at least one.
    let one_setting =
        design.get_ref().get("type").and_then(|t| t.as_str()) == Some(super::design::ONE_SETTING);
    match (one_setting, factors.first()) {
        (true, Some(f)) => {
            return Err(source.err(
                &f.span(),
                format!(
                    "[design] type = \"{}\" runs one setting over several seeds and takes no [[factors]]; put the setting in [fixed]",
                    super::design::ONE_SETTING
                ),
            ));
        }
        (false, None) => bail!(
            "{}: the sweep has no [[factors]]; add at least one (or run one setting over several seeds with [design] type = \"{}\")",
            source.path.display(),
            super::design::ONE_SETTING
        ),
        _ => {}
    }
    let mut names: BTreeMap<&str, usize> = BTreeMap::new();
    let mut targets: BTreeMap<&str, &str> = BTreeMap::new();
    for f in factors {
        let f = f.get_ref();
        let name = f.name.get_ref().as_str();
        let ok_name = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !ok_name {
            return Err(source.err(
                &f.name.span(),
                format!("factor name `{name}` must be letters, digits, `_` or `-`"),
            ));
        }
        if names.insert(name, 0).is_some() {
            return Err(source.err(
                &f.name.span(),
                format!("factor name `{name}` is used twice; names must be unique"),
            ));
        }
        let target = f.target.get_ref().as_str();
        if let Some(other) = targets.insert(target, name) {
            return Err(source.err(
                &f.target.span(),
                format!("factors `{other}` and `{name}` both set `{target}`"),
            ));
        }
        match (f.low, f.high, &f.levels) {
            (Some(lo), Some(hi), None) if lo.is_finite() && hi.is_finite() && lo < hi => {}
            (Some(lo), Some(hi), None) => {
                return Err(source.err(
                    &f.name.span(),
                    format!("factor `{name}`: low = {lo} must be below high = {hi}"),
                ));
            }
            (None, None, Some(levels)) => {
                let increasing = levels.windows(2).all(|w| w[0] < w[1]);
                if levels.len() < 2 || !increasing || levels.iter().any(|v| !v.is_finite()) {
                    return Err(source.err(
                        &f.name.span(),
                        format!(
                            "factor `{name}`: levels must be at least 2 finite values in increasing order"
                        ),
                    ));
                }
            }
            _ => {
                return Err(source.err(
                    &f.name.span(),
                    format!("factor `{name}`: give either `low` and `high`, or `levels`"),
                ));
            }
        }
    }
    Ok(())
}

impl FactorSection {
    /// Real value of a coded value: low/high map to -1/+1 linearly; with explicit levels,
    /// coded values of an evenly spaced grid on [-1, 1] pick the levels.
    pub fn real(&self, coded: f64) -> f64 {
        let v = match (&self.levels, self.low, self.high) {
            (Some(levels), _, _) => {
                let k = ((coded + 1.0) / 2.0 * (levels.len() - 1) as f64).round() as usize;
                return levels[k.min(levels.len() - 1)];
            }
            (None, Some(lo), _) if coded == -1.0 => return lo,
            (None, _, Some(hi)) if coded == 1.0 => return hi,
            (None, Some(lo), Some(hi)) => lo + (hi - lo) * (coded + 1.0) / 2.0,
            _ => return f64::NAN,
        };
        // 12 significant digits: 0.25, not 0.25000000000000006, in tables and scenes.
        format!("{v:.11e}").parse().unwrap_or(v)
    }

    /// Number of explicit levels (for a full factorial), or `None` for a low/high factor.
    pub fn level_count(&self) -> Option<usize> {
        self.levels.as_ref().map(Vec::len)
    }
}
