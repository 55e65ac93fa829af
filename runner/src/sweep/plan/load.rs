//! A sweep file read into a plan: its scene found, its design expanded into numbered runs
//! with their seeds, and its fingerprint taken.

use super::{Factor, Plan, PlannedRun, SceneSource, fnv1a};
use crate::lab::experiment;
use crate::sweep::design::{self, Expanded};
use crate::sweep::file::{self, FactorSection, Source, SweepFile};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The demo sweep and its scene, embedded so that `tilth sweep run` works anywhere.
pub const DEMO_SWEEP: &str = include_str!("../../../../sweeps/demo.toml");
pub const DEMO_SCENE: &str = include_str!("../../../../sweeps/scenes/pile.toml");
/// The scene path the demo sweep names.
const DEMO_SCENE_PATH: &str = "scenes/pile.toml";

impl Plan {
    /// Reads the sweep at `path`, or the embedded demo when `None`, and checks every run.
    pub fn load(path: Option<&Path>) -> Result<Plan> {
        let source = read_sweep(path)?;
        let sweep = file::parse(&source)?;
        let scene = read_scene(&source, &sweep, path.is_none())?;
        let plan = Self::expand(&source, sweep, scene)?;
        plan.check(&source)?;
        Ok(plan)
    }

    /// The plan of a parsed sweep file: its design's runs in run order, replicate-major.
    fn expand(source: &Source, sweep: SweepFile, scene: SceneSource) -> Result<Plan> {
        let factors: Vec<&FactorSection> = sweep.factors.iter().map(|f| f.get_ref()).collect();
        let expanded = design::expand(source, &sweep.design, &factors)?;
        let name = sweep.name.clone().unwrap_or_else(|| {
            source
                .path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "sweep".into())
        });
        Ok(Plan {
            name,
            origin: source.path.display().to_string(),
            sweep_text: source.text.clone(),
            description: sweep.description.clone(),
            runs: planned_runs(&factors, &expanded),
            title: expanded.title,
            factors: factors.iter().map(|f| plan_factor(f)).collect(),
            fingerprint: fnv1a(&[&without_replicates(&source.text), &scene.text]),
            scene,
            fixed: sweep
                .fixed
                .iter()
                .map(|(k, v)| (k.clone(), v.get_ref().clone()))
                .collect(),
            threads: *sweep.experiment.threads.get_ref(),
            record: sweep.record.clone(),
        })
    }
}

/// The sweep file at `path`, or the embedded demo when `None`.
fn read_sweep(path: Option<&Path>) -> Result<Source> {
    Ok(match path {
        Some(p) => Source {
            path: p.to_path_buf(),
            text: std::fs::read_to_string(p)
                .with_context(|| format!("{}: cannot read", p.display()))?,
        },
        None => Source {
            path: PathBuf::from("sweeps/demo.toml (embedded)"),
            text: DEMO_SWEEP.to_string(),
        },
    })
}

/// The scene (or experiment) file the sweep names, relative to the sweep file; the embedded
/// demo's scene for the embedded demo (`demo`), which has no directory to read it from.
fn read_scene(source: &Source, sweep: &SweepFile, demo: bool) -> Result<SceneSource> {
    let scene_path = sweep.experiment.scene.get_ref();
    if demo && scene_path == DEMO_SCENE_PATH {
        return Ok(SceneSource {
            origin: "sweeps/scenes/pile.toml (embedded)".into(),
            dir: PathBuf::from("."),
            text: DEMO_SCENE.to_string(),
            experiment: false,
        });
    }
    let p = source.dir().join(scene_path);
    let text = std::fs::read_to_string(&p).map_err(|e| {
        source.err(
            &sweep.experiment.scene.span(),
            format!("experiment.scene: cannot read {}: {e}", p.display()),
        )
    })?;
    let experiment =
        toml::from_str::<toml::Value>(&text).is_ok_and(|v| experiment::is_experiment(&v));
    Ok(SceneSource {
        origin: p.display().to_string(),
        dir: p.parent().map(Path::to_path_buf).unwrap_or_default(),
        text,
        experiment,
    })
}

/// The runs of an expanded design, numbered replicate-major: all of replicate 1 in run order,
/// then all of replicate 2, ...; run k has seed `seed + k - 1`.
fn planned_runs(factors: &[&FactorSection], expanded: &Expanded) -> Vec<PlannedRun> {
    let mut runs = vec![];
    for r in 0..expanded.replicates {
        for &std in &expanded.order {
            let id = runs.len() + 1;
            let row = &expanded.rows[std];
            let coded: BTreeMap<String, f64> = factors
                .iter()
                .zip(row)
                .map(|(f, &c)| (f.name.get_ref().clone(), c))
                .collect();
            let values = factors
                .iter()
                .zip(row)
                .map(|(f, &c)| (f.name.get_ref().clone(), f.real(c)))
                .collect();
            runs.push(PlannedRun {
                id,
                std: std + 1,
                replicate: r + 1,
                coded,
                values,
                seed: expanded.seed + id as u64 - 1,
            });
        }
    }
    runs
}

/// A factor as the plan shows it: its range is its lowest and highest level when it lists
/// levels instead of low and high.
fn plan_factor(f: &FactorSection) -> Factor {
    Factor {
        name: f.name.get_ref().clone(),
        target: f.target.get_ref().clone(),
        label: f.label.clone(),
        unit: f.unit.clone(),
        low: f
            .low
            .unwrap_or_else(|| f.levels.as_ref().map_or(f64::NAN, |l| l[0])),
        high: f
            .high
            .unwrap_or_else(|| f.levels.as_ref().map_or(f64::NAN, |l| l[l.len() - 1])),
    }
}

/// The sweep text as if `[design] replicates` were 1: runs are numbered replicate-major (all
/// of replicate 1, then all of replicate 2, ...; run k has seed `seed + k - 1`), so a sweep
/// run again with more replicates keeps every run it has and adds the new seeds. The rest of
/// the text, comments included, is kept as written (toml_edit round-trips it), so a sweep
/// with one replicate keeps the fingerprint it had.
fn without_replicates(text: &str) -> String {
    let Ok(mut doc) = text.parse::<toml_edit::DocumentMut>() else {
        return text.to_string();
    };
    let Some(design) = doc.get_mut("design").and_then(|d| d.as_table_like_mut()) else {
        return text.to_string();
    };
    if let Some(v) = design.get_mut("replicates").and_then(|v| v.as_value_mut()) {
        let decor = v.decor().clone();
        *v = toml_edit::Value::from(1i64);
        *v.decor_mut() = decor;
    }
    doc.to_string()
}

#[cfg(test)]
mod tests {
    use super::without_replicates;

    /// The fingerprint leaves out the replicate count and nothing else: a sweep with one
    /// replicate (or none given) keeps its text, hence the fingerprint older builds gave it.
    #[test]
    fn the_identity_text_is_the_sweep_with_one_replicate() {
        let one = "[design]\ntype = \"full_factorial\"\nreplicates = 1  # one\nseed = 3\n";
        assert_eq!(without_replicates(one), one);
        let none = "# no replicates key\n[design]\ntype = \"sobol\"\nruns = 8\n";
        assert_eq!(without_replicates(none), none);
        let five = one.replace("replicates = 1", "replicates = 5");
        assert_eq!(without_replicates(&five), one);
        // Any other change still counts.
        let other_seed = five.replace("seed = 3", "seed = 4");
        assert_ne!(without_replicates(&other_seed), one);
    }
}
