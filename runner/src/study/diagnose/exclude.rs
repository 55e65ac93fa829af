//! Which contenders are needed, and which of those the best one's fit excludes.
//!
//! A rival b is excluded beside the best needed contender a (least chi^2) when the gap
//! between their fits, G = chi^2_b - chi^2_a in normal scores less what b's fit could still
//! gain, is one that b as the truth would leave with probability under `--alpha`, bounded by
//! exp(-G/2) ([`tilth_tools::diagnose::nonnested::gap_p`]) and Holm-corrected over the
//! rivals. The bound uses the noise the rows state: the best fit's own misfit test
//! (within the noise) is what vouches for it.
//!
//! The bound holds for fits at their minima. `tilth fit` stops after `--fit-iterations`, so
//! a rival's fit can stop while its chi^2 still falls; that chi^2 is then lowered by what
//! the fit could still gain before it is compared ([`unfinished_gain`]), and a rival that
//! only this keeps from exclusion is fitted on once from where it stopped
//! ([`worth_finishing`]).

use super::refit::{Contender, chi2_sf};
use tilth_tools::diagnose::nonnested::gap_p;

/// What a fit (its `fit.json`) could still gain, and whether it was still moving: the
/// predicted chi^2 gain of the Gauss-Newton step at its best setting (`tilth fit`'s stop
/// rule) and, when it ran out of iterations on an accepted step (still moving, no step
/// from there tried), the chi^2 that step removed, if more: a step on the same slope may
/// gain as much again, and the linear prediction understates a curved response. A fit
/// whose steps from its best were all refused keeps only the prediction. 0 when the history
/// says nothing.
pub(super) fn unfinished_gain(fit: &serde_json::Value) -> (f64, bool) {
    let steps: Vec<&serde_json::Value> = fit["history"].as_array().into_iter().flatten().collect();
    let accepted: Vec<(f64, f64)> = (steps.iter())
        .filter(|s| s["accepted"] == true)
        .filter_map(|s| {
            Some((
                s["chi2"].as_f64()?,
                s["predicted_gain"].as_f64().unwrap_or(0.0),
            ))
        })
        .collect();
    let Some(&(best, predicted)) = accepted.last() else {
        return (0.0, false);
    };
    let moving = fit["stopped"] == "iterations"
        && accepted.len() >= 2
        && steps.last().is_some_and(|s| s["accepted"] == true);
    let last_step = if moving {
        accepted[accepted.len() - 2].0 - best
    } else {
        0.0
    };
    (predicted.max(last_step).max(0.0), moving)
}

/// Needed (the chi^2 drop against chi^2(1), Holm over the contenders whose fits were made),
/// then excluded beside the best ([`exclude_worse`]).
pub(super) fn judge(fits: &mut [Contender], alpha: f64) {
    let raw: Vec<f64> = fits
        .iter()
        .filter(|c| c.failed.is_none())
        .map(|c| chi2_sf(c.chi2_drop.max(0.0), 1.0))
        .collect();
    for (c, p) in fits
        .iter_mut()
        .filter(|c| c.failed.is_none())
        .zip(tilth_tools::diagnose::holm_adjust(&raw))
    {
        c.p_needed = p;
        c.needed = c.chi2_drop > 0.0 && p < alpha;
    }
    exclude_worse(fits, alpha);
}

/// The best needed contender's index: the least chi^2.
fn best_needed(fits: &[Contender]) -> Option<usize> {
    (0..fits.len())
        .filter(|&k| fits[k].needed)
        .min_by(|&a, &b| fits[a].chi2.total_cmp(&fits[b].chi2))
}

/// The gap of `rival` beside `best`, in normal scores, less `slack`.
fn gap(best: &Contender, rival: &Contender, slack: f64) -> f64 {
    rival.chi2_scores - best.chi2_scores - slack
}

/// Sets `p_worse` and `excluded` on each needed contender beside the best needed one.
fn exclude_worse(fits: &mut [Contender], alpha: f64) {
    for c in fits.iter_mut() {
        c.p_worse = None;
        c.excluded = false;
    }
    let Some(best) = best_needed(fits) else {
        return;
    };
    let others: Vec<usize> = (0..fits.len())
        .filter(|&k| k != best && fits[k].needed)
        .collect();
    let raw: Vec<f64> = others
        .iter()
        .map(|&k| gap_p(gap(&fits[best], &fits[k], fits[k].unfinished_gain)))
        .collect();
    for (&k, p) in others.iter().zip(tilth_tools::diagnose::holm_adjust(&raw)) {
        fits[k].p_worse = Some(p);
        fits[k].excluded = p < alpha;
    }
}

/// The needed rivals, not excluded, that would be if their fits were finished: their gap
/// without the unfinished gain passes the test Holm gives the largest p (alpha itself),
/// with the gain it does not, and the fit was still moving (a fit whose steps from its best
/// were refused would take the same steps again).
pub(super) fn worth_finishing(fits: &[Contender], alpha: f64) -> Vec<usize> {
    let Some(best) = best_needed(fits) else {
        return vec![];
    };
    (0..fits.len())
        .filter(|&k| k != best && fits[k].needed && !fits[k].excluded)
        .filter(|&k| fits[k].unfinished_gain > 0.0 && fits[k].still_moving)
        .filter(|&k| gap_p(gap(&fits[best], &fits[k], 0.0)) < alpha)
        .collect()
}

/// A contender's `--param` for fitting on from its fitted model, which has its strength in
/// already: a candidate's `--param` adds to the model's strength, so its range is shifted by
/// the fitted strength and it starts at 0; a held parameter is an offset from the model's
/// value within absolute bounds, so it stays. The fit's estimate is then added to
/// `strength`.
pub(super) fn restart_at(param: &str, strength: f64) -> String {
    let shifted = param
        .split_once('=')
        .filter(|(key, _)| key.starts_with("candidate.") && strength.is_finite())
        .and_then(|(key, range)| {
            let (lo, hi) = range.split('@').next()?.split_once(':')?;
            let (lo, hi) = (lo.parse::<f64>().ok()?, hi.parse::<f64>().ok()?);
            Some(format!("{key}={}:{}@0", lo - strength, hi - strength))
        });
    shifted.unwrap_or_else(|| param.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A needed contender with chi^2 (and normal scores) `chi2`, its fit able to gain `gain`.
    fn fit(name: &str, chi2: f64, gain: f64) -> Contender {
        let mut c = Contender::failed(
            name,
            String::new(),
            std::path::Path::new("."),
            String::new(),
        );
        (c.chi2, c.chi2_scores, c.dof, c.failed) = (chi2, chi2, 16.0, None);
        (c.needed, c.within_noise, c.unfinished_gain) = (true, true, gain);
        c.still_moving = gain > 0.0;
        c
    }

    #[test]
    fn a_rival_is_excluded_by_a_gap_beyond_the_noise_less_what_its_fit_could_gain() {
        // Gaps 6, 14 and 14: raw bounds e^-3 = 0.050, e^-7 = 9.1e-4; Holm: the two small
        // ones x3 and x2 (2.7e-3, 2.7e-3 after the running max), the large one x1 (0.050).
        let mut fits = vec![
            fit("near", 26.0, 0.0),
            fit("best", 20.0, 0.0),
            fit("far", 34.0, 0.0),
            fit("far-too", 34.0, 0.0),
        ];
        exclude_worse(&mut fits, 0.01);
        assert_eq!(fits[1].p_worse, None, "the best");
        assert!((fits[0].p_worse.unwrap() - (-3f64).exp()).abs() < 1e-12);
        assert!(!fits[0].excluded);
        assert!((fits[2].p_worse.unwrap() - 3.0 * (-7f64).exp()).abs() < 1e-12);
        assert!(fits[2].excluded && fits[3].excluded);
        // The same gap, but the fit stopped with 8 still to gain: 14 - 8 = 6 is not beyond.
        (fits[2].unfinished_gain, fits[2].still_moving) = (8.0, true);
        (fits[3].unfinished_gain, fits[3].still_moving) = (8.0, false);
        exclude_worse(&mut fits, 0.01);
        assert!(!fits[2].excluded, "{:?}", fits[2].p_worse);
        assert_eq!(
            worth_finishing(&fits, 0.01),
            [2],
            "only the one still moving is worth it, not the one whose steps were refused"
        );
        // One decisive row excludes as well as the same chi^2 spread over every row: the
        // rows' noise is known.
        let mut one_row = vec![fit("one-row", 36.0, 0.0), fit("best", 20.0, 0.0)];
        exclude_worse(&mut one_row, 0.01);
        assert!(one_row[0].excluded);
    }

    #[test]
    fn what_an_unfinished_fit_could_gain() {
        let j = |stopped: &str, steps: serde_json::Value| serde_json::json!({"stopped": stopped, "history": steps});
        let steps = serde_json::json!([
            {"accepted": true, "chi2": 144.0, "predicted_gain": 87.0},
            {"accepted": true, "chi2": 88.0, "predicted_gain": 19.5},
            {"accepted": false, "chi2": 105.0},
            {"accepted": true, "chi2": 42.0},
        ]);
        // Out of iterations after a step that removed 46: 46, not the 0 it never predicted.
        assert_eq!(
            unfinished_gain(&j("iterations", steps.clone())),
            (46.0, true)
        );
        let refused = serde_json::json!([
            {"accepted": true, "chi2": 30.0, "predicted_gain": 12.0},
            {"accepted": true, "chi2": 14.0, "predicted_gain": 1.5},
            {"accepted": false, "chi2": 19.0},
        ]);
        // Its step from the best refused: the prediction alone, out of iterations or not.
        assert_eq!(
            unfinished_gain(&j("iterations", refused.clone())),
            (1.5, false)
        );
        assert_eq!(unfinished_gain(&j("at_noise", refused)), (1.5, false));
        assert_eq!(unfinished_gain(&serde_json::json!({})), (0.0, false));
        assert_eq!(
            restart_at("candidate.fines=0:0.5@0.1", 0.25),
            "candidate.fines=-0.25:0.25@0"
        );
        assert_eq!(
            restart_at("soil-soil.restitution=0.3:0.8", 0.1),
            "soil-soil.restitution=0.3:0.8"
        );
    }
}
