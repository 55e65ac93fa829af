//! `tilth fit --from-diagnosis DIR`: the free parameters that `tilth diagnose` wrote in
//! `DIR/diagnosis.json`, acted on as its verdict says: the diagnosis's free parameters over
//! their ranges, and each effect the verdict names, its strength free from the diagnosis's
//! estimate. Any other verdict is refused, with what to do instead.

use anyhow::{Result, bail};
use std::path::Path;
use tilth_tools::diagnose::verdict::Kind;

/// The `--param` strings the verdict in `dir` calls for. An effect's strength runs over
/// [0, max(3 x, x + 4 se, 2 step)] from its estimate x (0 if negative): wide enough that the
/// one-step estimate, a linearisation, does not bound the fit.
pub fn params_from_diagnosis(
    dir: &Path,
    steps: &dyn Fn(&str) -> Option<f64>,
) -> Result<Vec<String>> {
    let (d, path) = crate::study::diagnose::file::read(dir, "--from-diagnosis")?;
    let v = &d.verdict;
    match v.verdict {
        Kind::Effect => {}
        Kind::Ambiguous => bail!(
            "{}: the verdict is ambiguous among {}: fitting one of them would name it without evidence. Run `tilth next --diagnosis {}` and add the measurement it suggests, or fit a candidate by hand with --param candidate.NAME=LOW:HIGH",
            path.display(),
            v.ambiguous.join(", "),
            dir.display()
        ),
        Kind::NoneOfTheCandidates => bail!(
            "{}: the verdict is none_of_the_candidates: no candidate explains the misfit (docs/adding-an-effect.md)",
            path.display()
        ),
        Kind::NoEffect => bail!(
            "{}: the verdict is no_effect: fit the free parameters alone with --param PAIR.KEY=LOW:HIGH",
            path.display()
        ),
    }
    let mut out: Vec<String> = d
        .free_parameters
        .iter()
        .map(|f| format!("{}.{}={}:{}", f.pair, f.key, f.low, f.high))
        .collect();
    for e in &v.effects {
        let Some(step) = steps(&e.name) else {
            bail!(
                "{}: the verdict names {}, which is not a candidate of the model (a held parameter is freed with --param PAIR.KEY=LOW:HIGH)",
                path.display(),
                e.name
            );
        };
        let x = e.strength.max(0.0);
        let se = if e.standard_error.is_finite() {
            e.standard_error
        } else {
            0.0
        };
        let high = (3.0 * x).max(x + 4.0 * se).max(2.0 * step.abs());
        out.push(format!("candidate.{}=0:{high}@{x}", e.name));
    }
    Ok(out)
}
