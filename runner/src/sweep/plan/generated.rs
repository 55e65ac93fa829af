//! Plans without a sweep file: one generated in code by the lab commands, and the single run
//! of an experiment file (`tilth run EXPERIMENT`).

use super::{Factor, Plan, PlannedRun, SceneSource, describe, fnv1a, innermost};
use crate::record::RecordSection;
use anyhow::{Context, Result, anyhow};
use std::collections::BTreeMap;
use std::path::Path;

impl Plan {
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
}
