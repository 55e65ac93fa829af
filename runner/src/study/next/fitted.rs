//! `tilth next` on a refitted diagnosis: every rival's fitted model (`DIR/refit/NAME/`)
//! simulates the menu, and each measurement is scored by how far apart the rivals' predictions
//! are against the noise a measurement of it carries
//! ([`tilth_tools::diagnose::discriminate::fitted_separations`]). Nothing is linearised: a
//! rival several steps strong predicts what it predicts.

use super::{NextArgs, Scored, Suggestion, Unscored, group};
use crate::study::diagnose::file::DiagnosisFile;
use crate::study::lab_runs::{Simulate, prefetch, simulate};
use crate::study::measurements::Measurement;
use crate::study::synth::Noise;
use crate::sweep::execute;
use anyhow::Result;
use std::collections::BTreeMap;
use std::path::PathBuf;
use tilth_tools::compare::mean_sd;
use tilth_tools::diagnose::discriminate::{Fitted, fitted_separations};

/// The rival that stands for "no effect": the free parameters' own fit.
pub const FREE: &str = "free";

/// Each rival's fitted model and strength, when the diagnosis refitted every one of them
/// ([`FREE`] is the free parameters' fit, at strength 0).
pub(super) fn fitted_rivals(d: &DiagnosisFile, rivals: &[String]) -> Option<Vec<(PathBuf, f64)>> {
    let refit = d.refit.as_ref()?;
    rivals
        .iter()
        .map(|n| {
            let (dir, strength) = match n.as_str() {
                FREE => (&refit.free.dir, 0.0),
                _ => {
                    let c = refit.contenders.iter().find(|c| &c.name == n)?;
                    (&c.dir, c.strength?)
                }
            };
            let model = dir.join("model.toml");
            model.is_file().then_some((model, strength))
        })
        .collect()
}

/// Each rival's misfit on the diagnosed rows, for its weight
/// ([`tilth_tools::diagnose::discriminate::weights`]): its refit's chi^2, None where the fit
/// failed; without a refit (`--no-refit`), the linear one, the free parameters' misfit less
/// the rival's score statistic (the misfit itself cancels in the weights).
pub(super) fn misfits(d: &DiagnosisFile, rivals: &[String]) -> Vec<Option<f64>> {
    rivals
        .iter()
        .map(|n| match &d.refit {
            Some(refit) if n == FREE => refit.free.chi2,
            Some(refit) => (refit.contenders.iter())
                .find(|c| &c.name == n)
                .and_then(|c| c.strength.and(c.chi2)),
            None => (d.candidates.iter())
                .find(|c| &c.name == n)
                .map(|c| -c.statistic),
        })
        .collect()
}

/// Every menu measurement scored with the rivals' fitted models.
pub(super) fn fitted_options(
    args: &NextArgs,
    d: &DiagnosisFile,
    rivals: &[String],
    models: &[(PathBuf, f64)],
    menu: &[Measurement],
    noise: &BTreeMap<String, Noise>,
) -> Result<Scored> {
    let set = args.lab.set.parse()?;
    let r = d.replicates;
    let stop = execute::stop_on_signals()?;
    let outs: Vec<PathBuf> = rivals
        .iter()
        .map(|n| {
            args.out
                .join("runs")
                .join(format!("fitted-{}", n.replace(':', "-")))
        })
        .collect();
    let hows: Vec<Simulate> = models
        .iter()
        .zip(&outs)
        .map(|((model, _), o)| Simulate {
            model,
            data: &args.menu,
            out: o,
            replicates: r,
            first_seed: 1,
            lab: &args.lab,
            set: &set,
        })
        .collect();
    prefetch(menu, &hows)?;
    let mut values: Vec<Vec<Vec<f64>>> = vec![];
    let mut problems: Vec<Vec<Vec<String>>> = vec![];
    for (k, how) in hows.iter().enumerate() {
        if !args.lab.quiet {
            eprintln!(
                "rival {} of {}: {} as fitted",
                k + 1,
                rivals.len(),
                rivals[k]
            );
        }
        let (v, p): (Vec<Vec<f64>>, Vec<Vec<String>>) =
            simulate(menu, how, &stop)?.into_iter().unzip();
        values.push(v);
        problems.push(p);
    }
    let runs = (2 + d.free_parameters.len() + d.candidates.len()) * r;
    let mut options = vec![];
    let mut unscored = vec![];
    for (test, conditions, members) in group(menu) {
        let why = failures(rivals, &problems, &members, r);
        // Readings every rival ran completely, with the lab's variance of one measurement:
        // --noise, else the runs' own scatter (their mean over the rivals).
        let kept: Vec<usize> = members
            .into_iter()
            .filter(|&i| values.iter().all(|v| v[i].len() == r))
            .collect();
        let lab_var: Vec<f64> = kept
            .iter()
            .map(|&i| {
                let scatter = values
                    .iter()
                    .map(|v| mean_sd(&v[i]).1.unwrap_or(0.0))
                    .sum::<f64>()
                    / values.len() as f64;
                let mean = mean_sd(&values[0][i]).0;
                let lab = noise
                    .get(&menu[i].observable)
                    .map_or(scatter, |n| n.sd(mean));
                lab * lab / args.specimens as f64
            })
            .collect();
        if kept.is_empty() {
            unscored.push(Unscored {
                test,
                conditions,
                why,
            });
            continue;
        }
        let per_rival: Vec<Vec<Vec<f64>>> = values
            .iter()
            .map(|v| kept.iter().map(|&i| v[i].clone()).collect())
            .collect();
        let pairs = fitted_separations(
            &Fitted {
                names: rivals,
                values: &per_rival,
                lab_var: &lab_var,
            },
            d.alpha,
        );
        let observables = kept.iter().map(|&i| menu[i].observable.clone()).collect();
        options.push(Suggestion::new(
            (test, conditions, observables),
            pairs,
            runs,
        ));
    }
    Ok((options, unscored))
}

/// Per rival whose runs of a measurement (`members`, its readings) failed: how many of the
/// `r`, and the first one's problem up to its first sentence's end.
fn failures(
    rivals: &[String],
    problems: &[Vec<Vec<String>>],
    members: &[usize],
    r: usize,
) -> Vec<String> {
    let mut why = vec![];
    for (name, p) in rivals.iter().zip(problems) {
        let Some(worst) = members.iter().map(|&i| &p[i]).max_by_key(|p| p.len()) else {
            continue;
        };
        if let Some(first) = worst.first() {
            let short = first.split(". ").next().unwrap_or(first);
            why.push(format!(
                "{name}: {} of {r} runs failed ({short})",
                worst.len()
            ));
        }
    }
    if why.is_empty() {
        why.push("no reading scatters and --noise gives none".to_string());
    }
    why
}

#[cfg(test)]
mod tests {
    use super::failures;

    #[test]
    fn failures_name_each_rival_whose_runs_failed_with_the_first_problem() {
        let rivals = ["twisting".to_string(), "capillary".to_string()];
        let jam = "run 1: the funnel jammed at t = 0.58 s. The outlet is 10 diameters wide";
        // [rival][menu row] -> problems; the measurement's readings are rows 0 and 1.
        let problems = vec![
            vec![
                vec![],
                vec![jam.to_string(), "run 3: x".into(), "run 4: y".into()],
            ],
            vec![vec![], vec![]],
        ];
        assert_eq!(
            failures(&rivals, &problems, &[0, 1], 4),
            ["twisting: 3 of 4 runs failed (run 1: the funnel jammed at t = 0.58 s)"]
        );
        // No run failed: the readings were left out for want of scatter.
        assert_eq!(
            failures(&rivals, &problems, &[0], 4),
            ["no reading scatters and --noise gives none"]
        );
    }
}
