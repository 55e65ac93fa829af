//! `tilth next` on a refitted diagnosis: every rival's fitted model (`DIR/refit/NAME/`)
//! simulates the menu, and each measurement is scored by how far apart the rivals' predictions
//! are against the noise a measurement of it carries
//! ([`tilth_tools::diagnose::discriminate::fitted_separations`]). Nothing is linearised: a
//! rival several steps strong predicts what it predicts.

use super::{NextArgs, Suggestion, group};
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
                    (&c.dir, c.strength)
                }
            };
            let model = dir.join("model.toml");
            model.is_file().then_some((model, strength))
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
) -> Result<Vec<Suggestion>> {
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
    for (k, how) in hows.iter().enumerate() {
        if !args.lab.quiet {
            eprintln!(
                "rival {} of {}: {} as fitted",
                k + 1,
                rivals.len(),
                rivals[k]
            );
        }
        values.push(
            simulate(menu, how, &stop)?
                .into_iter()
                .map(|s| s.0)
                .collect(),
        );
    }
    let runs = (2 + d.free_parameters.len() + d.candidates.len()) * r;
    let mut options = vec![];
    for (test, conditions, members) in group(menu) {
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
    Ok(options)
}
