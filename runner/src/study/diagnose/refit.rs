//! `diagnose`'s refit (unless `--no-refit`): each contender fitted on simulations, not
//! extrapolated.
//!
//! The linear verdict scores every candidate by one finite difference at the model. An
//! effect several steps strong is then extrapolated: its one-step strength is off and the
//! misfit it leaves can fail the test, so a right candidate can end
//! `none_of_the_candidates`; and two candidates whose first-order signatures differ can both
//! fit. Here the free parameters alone are fitted (`tilth fit`, the null model, into
//! `DIR/refit/free/`, or `DIR/fit/` with `--fit-first`), and then each contender with them:
//! a candidate, or a `--probe`d parameter, that the linear diagnosis found significant, kept
//! in its verdict, or scored at a corrected p under [`CONTENDER_P`] (an effect with a
//! positive strength). Each contender gets three tests:
//! - needed: the drop of chi^2 from the null fit, D = chi^2_free - chi^2_C, against
//!   chi^2(1) (conservative at a strength bounded at 0), Holm-corrected over the contenders;
//! - within the noise: P(chi^2_dof > Q_C) >= alpha, the verdict's misfit test, Q_C the sum
//!   of the rows' normal scores squared (`tilth fit`'s `chi2_scores`: it allows for standard
//!   errors estimated from a few runs, [`tilth_tools::compare::welch`]);
//! - excluded: a gap to the best needed contender's fit that it would leave as the truth
//!   with probability under alpha (`exclude.rs`: the known noise, what an unfinished fit
//!   could still gain, Holm-corrected over the others).
//!
//! The verdict: the best needed contender, if within the noise, is named with its fitted
//! strength when every other needed one is excluded, and is `ambiguous` with those that are
//! not; a best outside the noise is `none_of_the_candidates`; none needed is `no_effect` when
//! the null fit is within the noise, else `none_of_the_candidates`. Two effects are not fitted together: a truth with two ends
//! ambiguous, `none_of_the_candidates`, or with the one whose fit alone is within the noise.

use super::{DiagnoseArgs, Diagnosed, HELD};
use crate::study::measurements::Measurement;
use anyhow::{Context, Result};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::path::Path;
use tilth_tools::diagnose::verdict::{Kind, Misfit, Named, Verdict};

/// Corrected p-value under which a candidate is refitted, significant or not: a
/// linearisation can understate a strong effect's score, and a contender left out could be
/// the truth beside a named one.
pub const CONTENDER_P: f64 = 0.1;

/// One contender's fit.
#[derive(Debug, Clone, Serialize)]
pub struct Contender {
    pub name: String,
    /// The `--param` its fit freed besides the free parameters.
    pub param: String,
    /// The fitted strength (a held parameter: its offset from the model's value).
    pub strength: f64,
    pub standard_error: Option<f64>,
    pub chi2: f64,
    /// The rows' normal scores' sum of squares: what the misfit test takes.
    pub chi2_scores: f64,
    pub dof: f64,
    /// P(chi^2_dof > chi2_scores).
    pub p_value: f64,
    /// chi^2 of the free parameters' fit minus this fit's.
    pub chi2_drop: f64,
    /// P(chi^2_1 > chi2_drop), Holm-corrected over the contenders.
    pub p_needed: f64,
    pub needed: bool,
    pub within_noise: bool,
    /// What its fit could still gain: the predicted chi^2 gain of the next step at its best
    /// setting or, when it ran out of iterations on an accepted step, that step's gain if
    /// larger ([`super::exclude::unfinished_gain`]).
    pub unfinished_gain: f64,
    /// Its fit ran out of iterations on an accepted step: fitting on may lower its chi^2.
    pub still_moving: bool,
    /// Against the best needed contender: the bound on the chance of a gap as large if it
    /// were the truth ([`tilth_tools::diagnose::nonnested::gap_p`]), Holm-corrected over the
    /// others (None for the best itself or one not needed).
    pub p_worse: Option<f64>,
    /// Its fit is worse than the best's beyond doubt (p_worse < alpha).
    pub excluded: bool,
    /// Each row's standardised residual at the fit.
    pub z: Vec<f64>,
    pub dir: String,
    /// Why its fit could not be made (its runs failed: a funnel that jams at a step of the
    /// fit); such a contender is neither needed nor excluded, and is never ruled out.
    pub failed: Option<String>,
}

/// The free parameters' own fit, the null model of the contenders.
#[derive(Debug, Clone, Serialize)]
pub struct NullFit {
    pub chi2: f64,
    pub chi2_scores: f64,
    pub dof: f64,
    pub p_value: f64,
    pub within_noise: bool,
    pub dir: String,
}

/// A contender's finite-difference step and, for a held parameter, the model's values of it.
pub(super) type StepOf<'a> = dyn Fn(&Diagnosed) -> Result<(f64, Vec<f64>)> + 'a;

/// What the refit found.
#[derive(Debug, Clone, Serialize)]
pub struct Refits {
    pub free: NullFit,
    pub contenders: Vec<Contender>,
}

impl Contender {
    /// A contender whose fit failed with `why`.
    pub(super) fn failed(name: &str, param: String, dir: &Path, why: String) -> Contender {
        Contender {
            name: name.to_string(),
            param,
            strength: f64::NAN,
            standard_error: None,
            chi2: f64::NAN,
            chi2_scores: f64::NAN,
            dof: f64::NAN,
            p_value: f64::NAN,
            chi2_drop: f64::NAN,
            p_needed: f64::NAN,
            needed: false,
            within_noise: false,
            unfinished_gain: 0.0,
            still_moving: false,
            p_worse: None,
            excluded: false,
            z: vec![],
            dir: dir.display().to_string(),
            failed: Some(why),
        }
    }

    /// A contender fitted into `dir` (`f`), beside the free parameters' chi^2.
    fn fitted(
        name: &str,
        param: String,
        dir: &Path,
        f: Fitted,
        free_chi2: f64,
        alpha: f64,
    ) -> Self {
        let p_value = chi2_sf(f.chi2_scores, f.dof);
        Contender {
            name: name.to_string(),
            param,
            strength: f.estimate,
            standard_error: f.standard_error,
            chi2: f.chi2,
            chi2_scores: f.chi2_scores,
            dof: f.dof,
            p_value,
            chi2_drop: free_chi2 - f.chi2,
            p_needed: f64::NAN,
            needed: false,
            within_noise: p_value >= alpha,
            unfinished_gain: f.unfinished_gain.0,
            still_moving: f.unfinished_gain.1,
            p_worse: None,
            excluded: false,
            z: f.z,
            dir: dir.display().to_string(),
            failed: None,
        }
    }
}

/// The contenders of a linear diagnosis, best first.
fn contenders<'a>(verdict: &Verdict, diagnosed: &'a [Diagnosed], alpha: f64) -> Vec<&'a Diagnosed> {
    let kept = |n: &str| {
        verdict.effects.iter().any(|e| e.name == n) || verdict.ambiguous.iter().any(|a| a == n)
    };
    let mut out: Vec<&Diagnosed> = diagnosed
        .iter()
        // A held parameter may be off either way; an effect's strength is not negative.
        .filter(|d| d.score.identifiable && (d.score.strength > 0.0 || d.held_parameter))
        .filter(|d| kept(&d.score.name) || d.score.p_value < CONTENDER_P.max(alpha))
        .collect();
    out.sort_by(|a, b| b.score.statistic.total_cmp(&a.score.statistic));
    out
}

/// The `--param` a contender is fitted with: a candidate's strength over [0, max(3 x,
/// x + 4 se, 2 step)] from its estimate x (as `fit --from-diagnosis`); a held parameter
/// over its model values -/+ 4 probe steps (not below 0).
fn contender_param(d: &Diagnosed, step: f64, held_values: &[f64]) -> String {
    let x = d.score.strength;
    match d.score.name.strip_prefix(HELD) {
        Some(key) => {
            let lo = held_values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = held_values
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max);
            let reach = (4.0 * step.abs()).max(2.0 * x.abs());
            format!("{key}={}:{}", (lo - reach).max(0.0), hi + reach)
        }
        None => {
            let se = (x / d.score.statistic.max(1e-12).sqrt()).abs();
            let high = (3.0 * x).max(x + 4.0 * se).max(2.0 * step.abs());
            format!("candidate.{}=0:{high}@{x}", d.score.name)
        }
    }
}

pub(super) fn chi2_sf(x: f64, dof: f64) -> f64 {
    ChiSquared::new(dof.max(1.0)).map_or(f64::NAN, |d| d.sf(x))
}

/// What one fit left: chi^2 (and its normal scores' sum, the misfit test's), dof, the
/// last parameter's estimate and standard error, and what it could still gain.
struct Fitted {
    chi2: f64,
    chi2_scores: f64,
    dof: f64,
    estimate: f64,
    standard_error: Option<f64>,
    z: Vec<f64>,
    unfinished_gain: (f64, bool),
}

fn read_fit(dir: &Path) -> Result<Fitted> {
    let path = dir.join("fit.json");
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&path)?)
        .with_context(|| format!("{}: not JSON", path.display()))?;
    let last = |key: &str| {
        j[key]
            .as_array()
            .and_then(|a| a.last())
            .and_then(|v| v.as_f64())
    };
    let chi2 = j["chi2"].as_f64().unwrap_or(f64::NAN);
    Ok(Fitted {
        chi2,
        chi2_scores: j["chi2_scores"].as_f64().unwrap_or(chi2),
        dof: j["dof"].as_f64().unwrap_or(f64::NAN),
        estimate: last("estimate").unwrap_or(f64::NAN),
        standard_error: last("standard_error"),
        z: (j["z"].as_array().into_iter().flatten())
            .filter_map(|v| v.as_f64())
            .collect(),
        unfinished_gain: super::exclude::unfinished_gain(&j),
    })
}

/// `tilth fit` of `model`'s free parameters and `extra` into `dir`.
fn fit_into(
    args: &DiagnoseArgs,
    (model, data): (&Path, &Path),
    dir: &Path,
    extra: Option<&str>,
) -> Result<Fitted> {
    std::fs::create_dir_all(dir)?;
    let mut params = args.params.clone();
    params.extend(extra.map(String::from));
    let fit = crate::study::fit::FitArgs {
        model: model.to_path_buf(),
        data: data.to_path_buf(),
        params,
        from_diagnosis: None,
        replicates: args.replicates,
        iterations: args.fit_iterations,
        to_minimum: false,
        out: dir.to_path_buf(),
        lab: args.lab.clone(),
    };
    crate::study::fit::fit(&fit)?;
    read_fit(dir)
}

/// The verdict the refits give, from the linear one (`encompassing` kept); `score` gives a
/// contender's linear statistic and corrected p-value.
fn refitted_verdict(
    linear: &Verdict,
    refits: &Refits,
    score: &dyn Fn(&str) -> (f64, f64),
) -> Verdict {
    let fits = &refits.contenders;
    let mut needed: Vec<&Contender> = fits.iter().filter(|c| c.needed).collect();
    needed.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
    let any_needed = !needed.is_empty();
    let best = needed.first().copied();
    // The best if it is within the noise, and every needed rival not excluded beside it.
    let ok: Vec<&Contender> = match best {
        Some(b) if b.within_noise => needed.iter().copied().filter(|c| !c.excluded).collect(),
        _ => vec![],
    };
    let misfit = match best {
        Some(c) => (c.chi2_scores, c.dof, c.p_value),
        None => (
            refits.free.chi2_scores,
            refits.free.dof,
            refits.free.p_value,
        ),
    };
    let misfit = Misfit {
        chi2: misfit.0,
        noise: 0.0,
        dof: misfit.1.max(0.0) as usize,
        p_value: misfit.2,
    };
    let (verdict, effects, mut ambiguous) = match ok.as_slice() {
        [] if !any_needed && refits.free.within_noise => (Kind::NoEffect, vec![], vec![]),
        [] => (Kind::NoneOfTheCandidates, vec![], vec![]),
        [one] => {
            let (statistic, p_value) = score(&one.name);
            let named = Named {
                name: one.name.clone(),
                strength: one.strength,
                standard_error: one.standard_error.unwrap_or(f64::NAN),
                statistic,
                p_value,
            };
            (Kind::Effect, vec![named], vec![])
        }
        several => (
            Kind::Ambiguous,
            vec![],
            several.iter().map(|c| c.name.clone()).collect(),
        ),
    };
    // A contender whose fit failed is not ruled out: beside any effect named, it is a rival.
    let unjudged: Vec<String> = fits
        .iter()
        .filter(|c| c.failed.is_some())
        .map(|c| c.name.clone())
        .collect();
    let (verdict, effects) = match verdict {
        Kind::Effect | Kind::Ambiguous if !unjudged.is_empty() => {
            ambiguous.extend(effects.iter().map(|e| e.name.clone()));
            ambiguous.extend(unjudged);
            (Kind::Ambiguous, vec![])
        }
        _ => (verdict, effects),
    };
    Verdict {
        verdict,
        effects,
        ambiguous,
        encompassing: linear.encompassing.clone(),
        misfit,
        alpha: linear.alpha,
    }
}

/// The free parameters' fit, every contender's, and the verdict they give; None with
/// `--no-refit`, after a `no_effect` verdict, or with no contender.
pub(super) fn refit(
    args: &DiagnoseArgs,
    rows: &[Measurement],
    linear: &Verdict,
    diagnosed: &[Diagnosed],
    step_of: &StepOf,
) -> Result<Option<(Verdict, Refits)>> {
    if args.no_refit || linear.verdict == Kind::NoEffect {
        return Ok(None);
    }
    let chosen = contenders(linear, diagnosed, args.alpha);
    if chosen.is_empty() {
        return Ok(None);
    }
    let root = args.out.join("refit");
    std::fs::create_dir_all(&root)?;
    let data = super::fit_first::data_for(args, rows, &root)?;
    let say = |what: &str| {
        if !args.lab.quiet {
            eprintln!("refitting {what} on simulations");
        }
    };
    // The null model: with --fit-first it is fitted already.
    let free_dir = if args.fit_first {
        args.out.join("fit")
    } else {
        root.join("free")
    };
    let free = if args.fit_first {
        read_fit(&free_dir)?
    } else {
        say("the free parameters alone");
        fit_into(args, (&args.model, &data), &free_dir, None)?
    };
    // Each contender's fit starts where the free parameters' ended (the fitted model), so
    // that it begins at the null model's chi^2 shifted only by the contender.
    let free_model = free_dir.join("model.toml");
    let free_p = chi2_sf(free.chi2_scores, free.dof);
    let mut fits = vec![];
    for d in &chosen {
        say(&format!("{} with the free parameters", d.score.name));
        let (step, held_values) = step_of(d)?;
        let param = contender_param(d, step, &held_values);
        let dir = root.join(d.score.name.replace(':', "-"));
        let f = match fit_into(args, (&free_model, &data), &dir, Some(&param)) {
            Ok(f) => f,
            Err(e) => {
                let why = format!("{e:#}");
                eprintln!("refitting {}: {why}; it stays a rival", d.score.name);
                fits.push(Contender::failed(&d.score.name, param, &dir, why));
                continue;
            }
        };
        fits.push(Contender::fitted(
            &d.score.name,
            param,
            &dir,
            f,
            free.chi2,
            args.alpha,
        ));
    }
    super::exclude::judge(&mut fits, args.alpha);
    // A rival that only its unfinished fit keeps from exclusion is fitted on from where it
    // stopped, once: the decision rests on it, so it is worth the runs.
    for k in super::exclude::worth_finishing(&fits, args.alpha) {
        let (name, first) = (fits[k].name.clone(), &fits[k]);
        say(&format!("{name} on from where its fit stopped"));
        let param = super::exclude::restart_at(&first.param, first.strength);
        let dir = Path::new(&first.dir).join("more");
        let model = Path::new(&first.dir).join("model.toml");
        match fit_into(args, (&model, &data), &dir, Some(&param)) {
            // It starts at the same setting, so it is no worse; equal, it says the fit is done.
            Ok(f) if f.chi2 <= first.chi2 => {
                // Its estimate adds to the strength the fitted model has in already.
                let strength = first.strength + f.estimate;
                fits[k] = Contender::fitted(&name, param, &dir, f, free.chi2, args.alpha);
                fits[k].strength = strength;
            }
            Ok(_) => {}
            Err(e) => eprintln!("refitting {name} on: {e:#}; its first fit stands"),
        }
    }
    super::exclude::judge(&mut fits, args.alpha);
    let refits = Refits {
        free: NullFit {
            chi2: free.chi2,
            chi2_scores: free.chi2_scores,
            dof: free.dof,
            p_value: free_p,
            within_noise: free_p >= args.alpha,
            dir: free_dir.display().to_string(),
        },
        contenders: fits,
    };
    let score = |name: &str| {
        chosen
            .iter()
            .find(|d| d.score.name == name)
            .map_or((f64::NAN, f64::NAN), |d| {
                (d.score.statistic, d.score.p_value)
            })
    };
    Ok(Some((refitted_verdict(linear, &refits, &score), refits)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A contender's fit: chi^2 on 14 dof, needed or not, excluded beside the best or not.
    fn fit(name: &str, chi2: f64, needed: bool, excluded: bool) -> Contender {
        let p_value = chi2_sf(chi2, 14.0);
        Contender {
            name: name.into(),
            param: String::new(),
            strength: 0.1,
            standard_error: Some(0.01),
            chi2,
            chi2_scores: chi2,
            dof: 14.0,
            p_value,
            chi2_drop: 20.0,
            p_needed: if needed { 1e-4 } else { 0.5 },
            needed,
            within_noise: p_value >= 0.01,
            unfinished_gain: 0.0,
            still_moving: false,
            p_worse: None,
            excluded,
            z: vec![],
            dir: String::new(),
            failed: None,
        }
    }

    fn refits(free_chi2: f64, contenders: Vec<Contender>) -> Refits {
        let p_value = chi2_sf(free_chi2, 15.0);
        Refits {
            free: NullFit {
                chi2: free_chi2,
                chi2_scores: free_chi2,
                dof: 15.0,
                p_value,
                within_noise: p_value >= 0.01,
                dir: String::new(),
            },
            contenders,
        }
    }

    fn linear() -> Verdict {
        Verdict {
            verdict: Kind::NoneOfTheCandidates,
            effects: vec![],
            ambiguous: vec![],
            encompassing: vec![],
            misfit: Misfit {
                chi2: 40.0,
                noise: 1.0,
                dof: 14,
                p_value: 2e-4,
            },
            alpha: 0.01,
        }
    }

    #[test]
    fn the_fits_decide_the_verdict() {
        let score = |_: &str| (12.0, 0.001);
        let v = |r: Refits| refitted_verdict(&linear(), &r, &score);
        // chi^2_14 at 0.01 is 29.14: 20 is within the noise, 35 and 60 are not.
        let one = v(refits(
            50.0,
            vec![
                fit("fines", 20.0, true, false),
                fit("twisting", 35.0, true, true),
            ],
        ));
        assert_eq!(one.verdict, Kind::Effect);
        assert_eq!(one.effects[0].name, "fines");
        assert_eq!(
            (one.effects[0].strength, one.effects[0].standard_error),
            (0.1, 0.01)
        );
        assert_eq!((one.misfit.chi2, one.misfit.dof), (20.0, 14));
        // A rival not excluded beside the best stays, within the noise or not.
        let two = v(refits(
            50.0,
            vec![fit("a", 35.0, true, false), fit("b", 18.0, true, false)],
        ));
        assert_eq!(two.verdict, Kind::Ambiguous);
        assert_eq!(two.ambiguous, ["b", "a"], "best fit first");
        let none = v(refits(
            70.0,
            vec![fit("a", 35.0, true, false), fit("b", 60.0, true, true)],
        ));
        assert_eq!(none.verdict, Kind::NoneOfTheCandidates);
        assert_eq!(none.misfit.chi2, 35.0, "the best needed fit's misfit");
        // Within the noise but not needed: the free parameters explain the data.
        let null = v(refits(
            18.0,
            vec![fit("a", 17.0, false, false), fit("b", 16.5, false, false)],
        ));
        assert_eq!(null.verdict, Kind::NoEffect);
        assert_eq!(null.misfit.chi2, 18.0, "the free parameters' fit");
        let unexplained = v(refits(45.0, vec![fit("a", 44.0, false, false)]));
        assert_eq!(unexplained.verdict, Kind::NoneOfTheCandidates);
    }

    #[test]
    fn a_contender_whose_fit_failed_is_never_ruled_out() {
        let score = |_: &str| (12.0, 0.001);
        let v = |r: Refits| refitted_verdict(&linear(), &r, &score);
        let jammed = || Contender::failed("twisting", String::new(), Path::new("."), "jam".into());
        // The fits alone would name fines; the contender that could not be fitted stays.
        let named = v(refits(
            50.0,
            vec![fit("fines", 20.0, true, false), jammed()],
        ));
        assert_eq!(named.verdict, Kind::Ambiguous);
        assert_eq!(named.ambiguous, ["fines", "twisting"]);
        assert!(named.effects.is_empty());
        let several = v(refits(
            50.0,
            vec![
                fit("a", 35.0, true, false),
                fit("b", 18.0, true, false),
                jammed(),
            ],
        ));
        assert_eq!(several.ambiguous, ["b", "a", "twisting"]);
        // Nothing named: the verdict stands, and no failed fit is called an effect.
        let none = v(refits(70.0, vec![fit("a", 60.0, true, false), jammed()]));
        assert_eq!(none.verdict, Kind::NoneOfTheCandidates);
    }

    #[test]
    fn the_fits_are_judged_by_the_chi2_tail() {
        // e^{-x/2} (1 + x/2) is P(chi^2_4 > x).
        let x: f64 = 9.0;
        assert!((chi2_sf(x, 4.0) - (-x / 2.0).exp() * (1.0 + x / 2.0)).abs() < 1e-12);
    }
}
