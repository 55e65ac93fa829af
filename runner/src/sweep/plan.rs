//! A sweep file expanded into runs, each checked against the scene before anything runs.

use super::design::{self, Expanded};
use super::file::{self, FactorSection, Source, SweepFile};
use crate::config;
use crate::config::target;
use crate::lab::experiment;
use crate::lab::protocol::{Protocol, RunSteps};
use crate::record::RecordSection;
use anyhow::{Context, Result, anyhow};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The demo sweep and its scene, embedded so that `tilth sweep run` works anywhere.
pub const DEMO_SWEEP: &str = include_str!("../../../sweeps/demo.toml");
pub const DEMO_SCENE: &str = include_str!("../../../sweeps/scenes/pile.toml");
/// The scene path the demo sweep names.
const DEMO_SCENE_PATH: &str = "scenes/pile.toml";

/// A factor as the plan shows it.
#[derive(Debug, Clone, Serialize)]
pub struct Factor {
    pub name: String,
    pub target: String,
    pub label: Option<String>,
    pub unit: Option<String>,
    /// Real value at coded -1 (or the lowest level).
    pub low: f64,
    /// Real value at coded +1 (or the highest level).
    pub high: f64,
}

/// One run of the sweep.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct PlannedRun {
    /// Run number, 1-based, in run order.
    pub id: usize,
    /// Standard-order number, 1-based.
    pub std: usize,
    /// Replicate, 1-based.
    pub replicate: usize,
    /// Factor name -> coded value.
    pub coded: BTreeMap<String, f64>,
    /// Factor name -> real value.
    pub values: BTreeMap<String, f64>,
    pub seed: u64,
}

/// A scene as text, with the name and directory it came from.
#[derive(Debug, Clone)]
pub struct SceneSource {
    pub origin: String,
    pub dir: PathBuf,
    pub text: String,
    /// An experiment file (`experiment = "..."`) rather than a scene.
    pub experiment: bool,
}

/// An expanded, checked sweep.
#[derive(Debug, Clone)]
pub struct Plan {
    pub name: String,
    /// The sweep file (or the embedded demo's name).
    pub origin: String,
    pub sweep_text: String,
    pub description: Option<String>,
    /// The design in words.
    pub title: String,
    pub factors: Vec<Factor>,
    pub runs: Vec<PlannedRun>,
    pub scene: SceneSource,
    /// Scene values set in every run (path, value).
    pub fixed: Vec<(String, toml::Value)>,
    /// Threads per run.
    pub threads: usize,
    pub record: RecordSection,
    /// Fingerprint of the sweep and scene texts: a resumed sweep must match it.
    pub fingerprint: String,
}

/// FNV-1a, 64 bit: a fingerprint that stays the same across builds and platforms.
pub fn fnv1a(parts: &[&str]) -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    for p in parts {
        for b in p.bytes().chain([0xff]) {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    }
    format!("{h:016x}")
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

impl Plan {
    /// Reads the sweep at `path`, or the embedded demo when `None`, and checks every run.
    pub fn load(path: Option<&Path>) -> Result<Plan> {
        let source = match path {
            Some(p) => Source {
                path: p.to_path_buf(),
                text: std::fs::read_to_string(p)
                    .with_context(|| format!("{}: cannot read", p.display()))?,
            },
            None => Source {
                path: PathBuf::from("sweeps/demo.toml (embedded)"),
                text: DEMO_SWEEP.to_string(),
            },
        };
        let sweep = file::parse(&source)?;
        let scene_path = sweep.experiment.scene.get_ref();
        let scene = match path {
            None if scene_path == DEMO_SCENE_PATH => SceneSource {
                origin: "sweeps/scenes/pile.toml (embedded)".into(),
                dir: PathBuf::from("."),
                text: DEMO_SCENE.to_string(),
                experiment: false,
            },
            _ => {
                let p = source.dir().join(scene_path);
                let text = std::fs::read_to_string(&p).map_err(|e| {
                    source.err(
                        &sweep.experiment.scene.span(),
                        format!("experiment.scene: cannot read {}: {e}", p.display()),
                    )
                })?;
                let experiment = toml::from_str::<toml::Value>(&text)
                    .is_ok_and(|v| experiment::is_experiment(&v));
                SceneSource {
                    origin: p.display().to_string(),
                    dir: p.parent().map(Path::to_path_buf).unwrap_or_default(),
                    text,
                    experiment,
                }
            }
        };
        let plan = Self::expand(&source, sweep, scene)?;
        plan.check(&source)?;
        Ok(plan)
    }

    /// A plan made in code: an experiment (TOML text, relative paths from `dir`) run once per
    /// entry of `runs`, whose `values` set the `factors`' targets.
    pub fn generated(
        name: &str,
        experiment_text: String,
        dir: &Path,
        factors: Vec<Factor>,
        runs: Vec<PlannedRun>,
    ) -> Result<Plan> {
        let plan = Plan {
            name: name.to_string(),
            origin: format!("{name} (generated)"),
            fingerprint: fnv1a(&[&experiment_text, &serde_json::to_string(&runs)?]),
            sweep_text: experiment_text.clone(),
            description: None,
            title: format!("{} runs", runs.len()),
            factors,
            runs,
            scene: SceneSource {
                origin: format!("{name} experiment"),
                dir: dir.to_path_buf(),
                text: experiment_text,
                experiment: true,
            },
            fixed: vec![],
            threads: 1,
            record: RecordSection::default(),
        };
        for run in &plan.runs {
            plan.build(run).map_err(|e| {
                anyhow!(
                    "{name}: run {} ({}) is not valid: {}",
                    run.id,
                    describe(&run.values),
                    innermost(&e)
                )
            })?;
        }
        Ok(plan)
    }

    /// One run of an experiment file (`tilth run EXPERIMENT`): no factors, its own seed.
    pub fn single(path: &Path, coarse: bool) -> Result<Plan> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let value: toml::Value = toml::from_str(&text).map_err(|e| {
            let line = e
                .span()
                .map(|s| format!(":{}", text[..s.start].matches('\n').count() + 1))
                .unwrap_or_default();
            anyhow!("{}{line}: {}", path.display(), e.message())
        })?;
        let get = |k: &str| {
            value
                .get("simulation")
                .and_then(|s| s.get(k))
                .and_then(toml::Value::as_integer)
        };
        let seed = get("seed").unwrap_or(1).max(0) as u64;
        let threads = get("threads").unwrap_or(1).max(1) as usize;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "experiment".into());
        let fixed = if coarse {
            vec![("coarse".to_string(), toml::Value::Boolean(true))]
        } else {
            vec![]
        };
        let plan = Plan {
            name: name.clone(),
            origin: path.display().to_string(),
            sweep_text: text.clone(),
            description: None,
            title: if coarse {
                "one run, coarse".into()
            } else {
                "one run".into()
            },
            factors: vec![],
            runs: vec![PlannedRun {
                id: 1,
                std: 1,
                replicate: 1,
                coded: BTreeMap::new(),
                values: BTreeMap::new(),
                seed,
            }],
            fingerprint: fnv1a(&[&text, if coarse { "coarse" } else { "" }]),
            scene: SceneSource {
                origin: path.display().to_string(),
                dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
                text,
                experiment: true,
            },
            fixed,
            threads,
            record: RecordSection::default(),
        };
        plan.build(&plan.runs[0])?;
        Ok(plan)
    }

    fn expand(source: &Source, sweep: SweepFile, scene: SceneSource) -> Result<Plan> {
        let factors: Vec<&FactorSection> = sweep.factors.iter().map(|f| f.get_ref()).collect();
        let Expanded {
            title,
            rows,
            order,
            replicates,
            seed,
        } = design::expand(source, &sweep.design, &factors)?;
        let mut runs = vec![];
        for r in 0..replicates {
            for &std in &order {
                let id = runs.len() + 1;
                let coded: BTreeMap<String, f64> = factors
                    .iter()
                    .zip(&rows[std])
                    .map(|(f, &c)| (f.name.get_ref().clone(), c))
                    .collect();
                let values = factors
                    .iter()
                    .zip(&rows[std])
                    .map(|(f, &c)| (f.name.get_ref().clone(), f.real(c)))
                    .collect();
                runs.push(PlannedRun {
                    id,
                    std: std + 1,
                    replicate: r + 1,
                    coded,
                    values,
                    seed: seed + id as u64 - 1,
                });
            }
        }
        let factors_out = factors
            .iter()
            .map(|f| Factor {
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
            })
            .collect();
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
            title,
            factors: factors_out,
            runs,
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
        .map(|p| p.with_spans(sweep))
    }

    fn with_spans(self, _sweep: SweepFile) -> Plan {
        self
    }

    /// The scene (or experiment) file with the fixed values, `values` and `seed` set;
    /// experiment targets written `scene:PATH` are returned apart, for the generated scene.
    fn input(
        &self,
        values: &[(&str, f64)],
        seed: Option<u64>,
    ) -> Result<(toml::Value, Vec<(String, toml::Value)>)> {
        let mut v: toml::Value = toml::from_str(&self.scene.text)
            .map_err(|e| anyhow!("{}: {}", self.scene.origin, e.message()))?;
        let mut scene_overrides = vec![];
        let mut set = |path: &str, value: toml::Value| -> Result<()> {
            match path.strip_prefix("scene:") {
                Some(p) if self.scene.experiment => {
                    scene_overrides.push((p.to_string(), value));
                    Ok(())
                }
                _ => target::set(&mut v, path, value),
            }
        };
        for (path, value) in &self.fixed {
            set(path, value.clone()).map_err(|e| anyhow!("fixed `{path}`: {e}"))?;
        }
        for (name, x) in values {
            let f = self
                .factors
                .iter()
                .find(|f| f.name == *name)
                .ok_or_else(|| anyhow!("no factor `{name}`"))?;
            set(&f.target, toml::Value::Float(*x))?;
        }
        if let Some(seed) = seed {
            if let Some(t) = v.as_table_mut() {
                // An experiment file may leave [simulation] out entirely.
                t.entry("simulation")
                    .or_insert_with(|| toml::Value::Table(Default::default()));
            }
            target::set(&mut v, "simulation.seed", toml::Value::Integer(seed as i64))?;
        }
        Ok((v, scene_overrides))
    }

    /// Builds a checked, not yet started simulation and its protocol from `values`.
    fn build_values(
        &self,
        values: &[(&str, f64)],
        seed: Option<u64>,
        tag: &str,
    ) -> Result<(config::Prepared, Box<dyn Protocol>)> {
        let (input, scene_overrides) = self.input(values, seed)?;
        let origin = format!("{}{tag}", self.scene.origin);
        if self.scene.experiment {
            let built = experiment::build(input, &origin, &self.scene.dir, &scene_overrides)?;
            let prepared =
                experiment::prepare(&built, &origin, &self.scene.dir, Some(self.threads))?;
            Ok((prepared, built.protocol))
        } else {
            let prepared =
                config::prepare_value(input, &origin, &self.scene.dir, Some(self.threads))?;
            let steps = prepared.steps;
            Ok((prepared, Box::new(RunSteps { steps })))
        }
    }

    /// The simulation and protocol of `run`.
    pub fn build(&self, run: &PlannedRun) -> Result<(config::Prepared, Box<dyn Protocol>)> {
        let values: Vec<(&str, f64)> = self
            .factors
            .iter()
            .map(|f| (f.name.as_str(), run.values[&f.name]))
            .collect();
        self.build_values(&values, Some(run.seed), &format!(" (run {})", run.id))
    }

    /// Refuses the sweep before anything runs: every fixed value, every factor at each of
    /// its levels and then every whole run must give a valid scene.
    fn check(&self, source: &Source) -> Result<()> {
        let sweep: SweepFile = file::parse(source)?;
        // The design numbers the seeds (run k: `[design] seed` + k - 1): a seed given as a
        // factor or a fixed value would be overwritten in every run without a word.
        let seed_set = |path: &str| path.trim_start_matches("scene:") == "simulation.seed";
        let seed_refusal = "is set per run by the design: run k uses `[design] seed` + k - 1 \
                            (default seed 1); for several seeds per setting use `[design] \
                            replicates`";
        for f in &sweep.factors {
            let target = &f.get_ref().target;
            if seed_set(target.get_ref()) {
                return Err(source.err(
                    &target.span(),
                    format!(
                        "factor `{}`: `simulation.seed` {seed_refusal}",
                        f.get_ref().name.get_ref()
                    ),
                ));
            }
        }
        if let Some((path, value)) = sweep.fixed.iter().find(|(p, _)| seed_set(p)) {
            return Err(source.err(
                &value.span(),
                format!("fixed `{path}`: `simulation.seed` {seed_refusal}"),
            ));
        }
        self.record
            .resolve(1e-9)
            .map_err(|e| anyhow!("{}: [record] {e}", source.path.display()))?;
        for (path, value) in &sweep.fixed {
            let mut v: toml::Value = toml::from_str(&self.scene.text)
                .map_err(|e| anyhow!("{}: {}", self.scene.origin, e.message()))?;
            if self.scene.experiment && path.starts_with("scene:") {
                continue;
            }
            target::set(&mut v, path, value.get_ref().clone())
                .map_err(|e| source.err(&value.span(), format!("fixed `{path}`: {e}")))?;
        }
        self.build_values(&[], None, "").map_err(|e| {
            anyhow!(
                "{}: {} with the sweep's fixed values is not valid: {}",
                source.path.display(),
                self.scene.origin,
                innermost(&e)
            )
        })?;
        for (f, spanned) in self.factors.iter().zip(&sweep.factors) {
            let mut levels: Vec<(f64, usize)> = vec![];
            for run in &self.runs {
                let x = run.values[&f.name];
                if !levels.iter().any(|(l, _)| *l == x) {
                    levels.push((x, run.id));
                }
            }
            let target_span = spanned.get_ref().target.span();
            let (mut probe, _) = self.input(&[], None)?;
            if !(self.scene.experiment && f.target.starts_with("scene:")) {
                target::set(&mut probe, &f.target, toml::Value::Float(levels[0].0)).map_err(
                    |e| {
                        source.err(
                            &target_span,
                            format!("factor `{}`: unknown target: {e}", f.name),
                        )
                    },
                )?;
            }
            for (x, id) in levels {
                self.build_values(&[(f.name.as_str(), x)], None, "")
                    .map_err(|e| {
                        source.err(
                            &spanned.span(),
                            format!(
                                "factor `{}` = {x} (run {id}) is not allowed for `{}`: {}",
                                f.name,
                                f.target,
                                innermost(&e)
                            ),
                        )
                    })?;
            }
        }
        for run in &self.runs {
            self.build(run).map_err(|e| {
                anyhow!(
                    "{}: run {} ({}) is not valid: {}",
                    source.path.display(),
                    run.id,
                    describe(&run.values),
                    innermost(&e)
                )
            })?;
        }
        Ok(())
    }

    /// The plan as JSON: `{name, design, factors, runs: [{id, coded, values, seed, ...}]}`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "name": self.name,
            "sweep": self.origin,
            "design": self.title,
            "scene": self.scene.origin,
            "threads_per_run": self.threads,
            "factors": self.factors,
            "runs": self.runs,
        })
    }

    /// The plan as a table, coded and real values side by side.
    pub fn write_table(&self, out: &mut dyn Write) -> Result<()> {
        writeln!(
            out,
            "{}: {}; {} runs",
            self.name,
            self.title,
            self.runs.len()
        )?;
        if let Some(d) = &self.description {
            writeln!(out, "{}", d.trim())?;
        }
        writeln!(
            out,
            "scene {}, {} thread(s) per run\n",
            self.scene.origin, self.threads
        )?;
        if self.factors.is_empty() {
            // One setting over several seeds: the setting is the fixed values.
            for (target, value) in &self.fixed {
                writeln!(out, "fixed  {target} = {value}")?;
            }
            writeln!(out, "\n{:>4}  {:>4}  {:>6}", "run", "rep", "seed")?;
            for r in &self.runs {
                writeln!(out, "{:>4}  {:>4}  {:>6}", r.id, r.replicate, r.seed)?;
            }
            return Ok(());
        }
        let nw = self
            .factors
            .iter()
            .map(|f| f.name.len())
            .max()
            .unwrap_or(4)
            .max(6);
        let tw = self
            .factors
            .iter()
            .map(|f| f.target.len())
            .max()
            .unwrap_or(6)
            .max(6);
        writeln!(
            out,
            "{:nw$}  {:tw$}  {:>10}  {:>10}  label",
            "factor", "target", "low (-1)", "high (+1)"
        )?;
        for f in &self.factors {
            writeln!(
                out,
                "{:nw$}  {:tw$}  {:>10}  {:>10}  {}{}",
                f.name,
                f.target,
                num(f.low),
                num(f.high),
                f.label.as_deref().unwrap_or(""),
                f.unit
                    .as_ref()
                    .map(|u| format!(" ({u})"))
                    .unwrap_or_default()
            )?;
        }
        writeln!(out)?;
        let cw = self
            .factors
            .iter()
            .map(|f| f.name.len())
            .max()
            .unwrap_or(2)
            .max(6);
        let mut head = format!("{:>4}  {:>4}  {:>4}  {:>6} |", "run", "std", "rep", "seed");
        for f in &self.factors {
            head += &format!(" {:>cw$}", f.name);
        }
        head += " |";
        for f in &self.factors {
            head += &format!(" {:>10}", f.name);
        }
        writeln!(
            out,
            "{:>27}{:^w$}| real values",
            "",
            "coded",
            w = (cw + 1) * self.factors.len() + 1
        )?;
        writeln!(out, "{head}")?;
        for r in &self.runs {
            let mut line = format!(
                "{:>4}  {:>4}  {:>4}  {:>6} |",
                r.id, r.std, r.replicate, r.seed
            );
            for f in &self.factors {
                line += &format!(" {:>cw$}", coded(r.coded[&f.name]));
            }
            line += " |";
            for f in &self.factors {
                line += &format!(" {:>10}", num(r.values[&f.name]));
            }
            writeln!(out, "{line}")?;
        }
        Ok(())
    }
}

/// The last (most specific) message of an error chain, on one line.
pub fn innermost(e: &anyhow::Error) -> String {
    e.chain()
        .last()
        .map(|c| c.to_string())
        .unwrap_or_default()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// `x1 = 0.2, x2 = 0.5`.
pub fn describe(values: &BTreeMap<String, f64>) -> String {
    values
        .iter()
        .map(|(k, v)| format!("{k} = {}", num(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A coded value: `+1`, `-1`, `0`, or three decimals.
fn coded(c: f64) -> String {
    if c == c.round() {
        if c > 0.0 {
            format!("+{c:.0}")
        } else {
            format!("{c:.0}")
        }
    } else {
        format!("{c:+.3}")
    }
}

/// A real value in at most 6 significant digits, without trailing zeros.
pub fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
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
