//! A run turned into the simulation it is: the scene (or experiment) with the sweep's fixed
//! values, the run's factor values and its seed set, then prepared.

use super::{Plan, PlannedRun};
use crate::config;
use crate::config::target;
use crate::lab::experiment;
use crate::lab::protocol::{Protocol, RunSteps};
use anyhow::{Result, anyhow};

/// Values to set in the scene an experiment builds (path, value), from targets written
/// `scene:PATH`.
pub(super) type SceneOverrides = Vec<(String, toml::Value)>;

impl Plan {
    /// The simulation and protocol of `run`.
    pub fn build(&self, run: &PlannedRun) -> Result<(config::Prepared, Box<dyn Protocol>)> {
        let values: Vec<(&str, f64)> = self
            .factors
            .iter()
            .map(|f| (f.name.as_str(), run.values[&f.name]))
            .collect();
        self.build_values(&values, Some(run.seed), &format!(" (run {})", run.id))
    }

    /// Builds a checked, not yet started simulation and its protocol from `values`; `tag`
    /// follows the scene's name in errors.
    pub(super) fn build_values(
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

    /// The scene (or experiment) file with the fixed values, `values` and `seed` set;
    /// experiment targets written `scene:PATH` are returned apart, for the generated scene.
    pub(super) fn input(
        &self,
        values: &[(&str, f64)],
        seed: Option<u64>,
    ) -> Result<(toml::Value, SceneOverrides)> {
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
}
