//! A sweep refused before anything runs: every fixed value, every factor at each of its
//! levels and then every whole run must give a valid scene, and no factor or fixed value may
//! set the seed the design numbers.

use super::{Factor, Plan, describe, innermost};
use crate::config::target;
use crate::sweep::file::{self, FactorSection, Source, SweepFile};
use anyhow::{Result, anyhow};
use toml::Spanned;

/// Why a factor or fixed value may not set `simulation.seed`: the design numbers the seeds
/// (run k: `[design] seed` + k - 1), which would overwrite it in every run without a word.
const SEED_REFUSAL: &str = "is set per run by the design: run k uses `[design] seed` + k - 1 \
                            (default seed 1); for several seeds per setting use `[design] \
                            replicates`";

impl Plan {
    /// Refuses the sweep before anything runs: every fixed value, every factor at each of
    /// its levels and then every whole run must give a valid scene.
    pub(super) fn check(&self, source: &Source) -> Result<()> {
        // Parsed again for the spans, which the plan does not keep.
        let sweep: SweepFile = file::parse(source)?;
        refuse_seed_targets(source, &sweep)?;
        self.record
            .resolve(1e-9)
            .map_err(|e| anyhow!("{}: [record] {e}", source.path.display()))?;
        self.check_fixed(source, &sweep)?;
        for (f, spanned) in self.factors.iter().zip(&sweep.factors) {
            self.check_factor(source, f, spanned)?;
        }
        self.check_runs(source)
    }

    /// Every fixed value must name a place in the scene, and the scene with all of them set
    /// must be valid.
    fn check_fixed(&self, source: &Source, sweep: &SweepFile) -> Result<()> {
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
        Ok(())
    }

    /// The factor `f` must name a place in the scene, and each of its levels (in the order
    /// the runs first use them) must give a valid scene on its own, so that a refusal names
    /// the factor rather than a whole run.
    fn check_factor(
        &self,
        source: &Source,
        f: &Factor,
        spanned: &Spanned<FactorSection>,
    ) -> Result<()> {
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
            target::set(&mut probe, &f.target, toml::Value::Float(levels[0].0)).map_err(|e| {
                source.err(
                    &target_span,
                    format!("factor `{}`: unknown target: {e}", f.name),
                )
            })?;
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
        Ok(())
    }

    /// Every whole run must give a valid scene.
    fn check_runs(&self, source: &Source) -> Result<()> {
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
}

/// Refuses a factor or fixed value that sets `simulation.seed` (see [`SEED_REFUSAL`]).
fn refuse_seed_targets(source: &Source, sweep: &SweepFile) -> Result<()> {
    let sets_seed = |path: &str| path.trim_start_matches("scene:") == "simulation.seed";
    for f in &sweep.factors {
        let target = &f.get_ref().target;
        if sets_seed(target.get_ref()) {
            return Err(source.err(
                &target.span(),
                format!(
                    "factor `{}`: `simulation.seed` {SEED_REFUSAL}",
                    f.get_ref().name.get_ref()
                ),
            ));
        }
    }
    if let Some((path, value)) = sweep.fixed.iter().find(|(p, _)| sets_seed(p)) {
        return Err(source.err(
            &value.span(),
            format!("fixed `{path}`: `simulation.seed` {SEED_REFUSAL}"),
        ));
    }
    Ok(())
}
