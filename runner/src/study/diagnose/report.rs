//! `diagnosis.md`: the ranking, the verdict and the recalibration in words.

use super::HELD;
use super::fit_first::FitFirst;
use super::refit::Refits;
use super::{DiagnoseArgs, Diagnosed, Recalibrated};
use crate::study::calibrate::Param;
use std::collections::BTreeMap;
use tilth_tools::compare::p_text;
use tilth_tools::diagnose::Unidentified;
use tilth_tools::diagnose::verdict::{Kind, Verdict};

/// Everything `diagnosis.md` reports.
pub(super) struct Findings<'a> {
    pub params: &'a [Param],
    pub diagnosed: &'a [Diagnosed],
    pub now: &'a BTreeMap<String, f64>,
    pub before: &'a BTreeMap<String, f64>,
    pub recalibrated: &'a [Recalibrated],
    pub dropped: &'a [String],
    pub verdict: &'a Verdict,
    pub fit_first: Option<&'a FitFirst>,
    pub refits: Option<&'a Refits>,
}

pub(super) fn report(args: &DiagnoseArgs, f: &Findings) -> String {
    let Findings {
        params,
        diagnosed: d,
        now,
        before,
        recalibrated,
        dropped,
        verdict,
        fit_first,
        refits,
    } = *f;
    let mut md = format!(
        "# Diagnosis of {} against {}\n\n",
        args.model.display(),
        args.data.display()
    );
    let free: Vec<String> = params
        .iter()
        .map(|p| format!("{}.{}", p.pair, p.key))
        .collect();
    md += &format!(
        "Free parameters: {}. {} replicate{} per run; significance at a Holm-corrected p < {}.\n\n",
        if free.is_empty() {
            "none".into()
        } else {
            format!(
                "{} (slopes from finite differences of {} % of each range, lengthened up to {} % where the runs' noise hid a parameter's effect: the table's step)",
                free.join(", "),
                crate::sweep::plan::num(100.0 * args.param_step),
                crate::sweep::plan::num(100.0 * args.longest_param_step)
            )
        },
        args.replicates,
        if args.replicates == 1 { "" } else { "s" },
        args.alpha
    );
    if let Some(f) = fit_first {
        md += &format!(
            "The free parameters were fitted to these data first (`{}/fit/fit.md`): {}; chi^2 {:.1} before, {:.1} after, on {} degrees of freedom. The candidates are scored at the fitted values (the restricted estimate of the score test), and \"now\" below is the fitted model. An effect that the free parameters mimic on these readings is absorbed by that fit: without --fit-first the candidates are scored against the model as it was.\n\n",
            args.out.display(),
            f.parameters
                .iter()
                .zip(&f.shift)
                .zip(&f.standard_error)
                .map(|((p, s), e)| match e {
                    Some(e) if *e > 0.0 =>
                        format!("{p} moved {s:+.4} ({:.1} standard errors)", s / e),
                    _ => format!("{p} moved {s:+.4}"),
                })
                .collect::<Vec<_>>()
                .join(", "),
            f.chi2_start,
            f.chi2,
            f.dof
        );
    }
    for (k, v) in now {
        md += &format!(
            "- {k}: RMSE now {v:.4}; what recalibrating the free parameters alone would leave: {:.4}\n",
            before[k]
        );
    }
    if !recalibrated.is_empty() {
        md += &recalibration_table(recalibrated);
    }
    md += "\n| rank | candidate | statistic | p (corrected) | strength | RMSE drop | identifiable |\n|---|---|---|---|---|---|---|\n";
    for (r, c) in d.iter().enumerate() {
        let drop: Vec<String> = c
            .predicted_rmse_drop
            .iter()
            .map(|(k, v)| format!("{k} {v:.3}"))
            .collect();
        md += &format!(
            "| {} | {} | {:.2} | {} | {:.4} | {} | {} |\n",
            r + 1,
            c.score.name,
            c.score.statistic,
            tilth_tools::compare::p_text(c.score.p_value).trim_start_matches("= "),
            c.score.strength,
            drop.join(", "),
            match c.score.unidentified {
                None => "yes".to_string(),
                Some(Unidentified::Absorbed) => format!(
                    "no: absorbed ({:.0} % distinct)",
                    100.0 * c.score.distinct_fraction
                ),
                Some(Unidentified::Unmeasured) => "no: within its noise".to_string(),
            }
        );
    }
    md += "\n";
    if let Some(fits) = refits {
        md += &refit_table(fits, args.alpha);
    }
    md += &verdict_words(verdict, &args.out);
    if let Some(r) = refits.filter(|_| verdict.verdict == Kind::NoEffect) {
        md += &not_excluded(r, &args.out);
    }
    for c in d.iter().filter(|c| !c.score.identifiable) {
        md += &match c.score.unidentified {
            Some(Unidentified::Absorbed) => format!(
                "\n\n{} is not identifiable from these measurements: once the free parameters are recalibrated, only {:.0} % of its signature is left (the threshold is {:.0} %), so its effect cannot be told from theirs. It is not a discovery.",
                c.score.name,
                100.0 * c.score.distinct_fraction,
                100.0 * tilth_tools::diagnose::MIN_DISTINCT
            ),
            _ => format!(
                "\n\n{} is not identifiable at this noise: what the free parameters leave of its signature is no larger than the scatter of its finite difference. Run more replicates or a larger step.",
                c.score.name
            ),
        };
    }
    if !dropped.is_empty() {
        md += &format!("\n\nRows left out: {}.", dropped.join("; "));
    }
    md += "\n";
    md
}

/// The linear recalibration behind the "would leave" numbers, and a warning when it is an
/// extrapolation: a shift out of the range the sensitivities were measured over, or a
/// parameter whose effect was not measured (its least-squares shift is then noise).
fn recalibration_table(recalibrated: &[Recalibrated]) -> String {
    let nums = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut md = "\nThat recalibration, linearised (each free parameter's least-squares shift):\n\n| parameter | now | shift | after | range | step | |\n|---|---|---|---|---|---|---|\n".to_string();
    for r in recalibrated {
        let mut flags = vec![];
        if !r.within_range {
            flags.push("leaves its range");
        }
        if !r.measurable {
            flags.push("no measurable effect");
        }
        md += &format!(
            "| {} | {} | {:+.4} | {} | {} .. {} | {} % | {} |\n",
            r.parameter,
            nums(&r.now),
            r.shift,
            nums(&r.after),
            r.range[0],
            r.range[1],
            crate::sweep::plan::num(100.0 * r.step),
            flags.join(", ")
        );
    }
    let out: Vec<&str> = recalibrated
        .iter()
        .filter(|r| !r.within_range)
        .map(|r| r.parameter.as_str())
        .collect();
    let flat: Vec<&str> = recalibrated
        .iter()
        .filter(|r| !r.measurable)
        .map(|r| r.parameter.as_str())
        .collect();
    if !out.is_empty() || !flat.is_empty() {
        md += "\n**The \"would leave\" numbers are an extrapolation, not a prediction.**";
        if !out.is_empty() {
            md += &format!(
                " The shift takes {} outside the range its sensitivity was measured over, where the linear model has no support.",
                out.join(", ")
            );
        }
        if !flat.is_empty() {
            md += &format!(
                " {} had no effect on these measurements above the noise of its estimate, so its shift is fitted to noise: fix it, measure it with more replicates or a longer --param-step, or add a test that responds to it.",
                flat.join(", ")
            );
        }
        if flat.is_empty() {
            md += " The candidates' statistics and p-values do not rest on this number.";
        }
        md += "\n";
    }
    if !flat.is_empty() {
        md += &format!(
            "\n**A candidate called significant here may stand for {}.** What the candidates are tested against is the residual left once the free parameters' measured effect is taken out; an effect measured as noise takes nothing out, so a misfit that {} would explain stays in the residual, and a candidate with a signature like it takes the credit. (On data from a truth whose rolling friction was 0.05 above the model's and no effect hidden, a 5 % step called a candidate significant in 8 of 20 seeds, a 10 % step in none: docs/discovery-proof.md, \"A free parameter off\".) Fit the free parameters to these data first (--fit-first), or diagnose again with more replicates or a longer --param-step.\n",
            flat.join(", "),
            if flat.len() == 1 { "it" } else { "they" }
        );
    }
    md
}

/// A candidate's name as a reader should see it: a held parameter is not an effect.
fn called(name: &str) -> String {
    match name.strip_prefix(HELD) {
        Some(key) => format!("the held parameter {key}"),
        None => name.to_string(),
    }
}

/// The held parameters among `names`, in a sentence: they could absorb the misfit.
fn could_absorb(names: &[String]) -> String {
    let held: Vec<&str> = names.iter().filter_map(|n| n.strip_prefix(HELD)).collect();
    match held.as_slice() {
        [] => String::new(),
        [one] => format!(
            " The held parameter {one} could absorb the misfit: it may be miscalibrated, and no effect missing. Free it with --param and diagnose again."
        ),
        [rest @ .., last] => format!(
            " The held parameters {} and {last} could absorb the misfit: they may be miscalibrated, and no effect missing. Free them with --param and diagnose again.",
            rest.join(", ")
        ),
    }
}

/// The verdict in words: what the data call for, and what to do next.
/// After a refitted `no_effect`: the effects that fit within the noise too, with their
/// fitted strengths, and how to tell one from the free parameters.
fn not_excluded(r: &Refits, out: &std::path::Path) -> String {
    let fits: Vec<String> = r
        .contenders
        .iter()
        .filter(|c| c.within_noise && c.strength > 0.0 && !c.name.starts_with(HELD))
        .map(|c| format!("{} (fitted {:.4})", c.name, c.strength))
        .collect();
    if fits.is_empty() {
        return String::new();
    }
    format!(
        " These data need no effect, but they do not exclude {}: each fits within the noise beside the free parameters. To tell one from the free parameters, `tilth next --diagnosis {} --menu MENU --rivals free,NAME` ranks the measurements that would.",
        fits.join(", "),
        out.display()
    )
}

/// The contenders' fits on simulations, and how the verdict follows from them.
fn refit_table(r: &Refits, alpha: f64) -> String {
    let p = |x: f64| p_text(x).trim_start_matches("= ").to_string();
    let mut md = format!(
        "Refitted on simulations (`tilth fit` in DIR/refit/; --no-refit skips it): the free parameters alone leave chi^2 {:.1} ({:.1} in normal scores) on {} degrees of freedom (p {}); each contender fitted with them:\n\n\
         | contender | fitted strength | standard error | chi^2 (normal scores) | dof | p | chi^2 drop | p needed (Holm) | needed | within the noise | its fit could still gain | p of its gap if it were the truth (Holm) | excluded |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        r.free.chi2,
        r.free.chi2_scores,
        r.free.dof,
        p(r.free.p_value)
    );
    for c in &r.contenders {
        if let Some(why) = &c.failed {
            md += &format!(
                "| {} | its fit failed, so it is not ruled out: {} ||||||||||||\n",
                c.name,
                why.replace('|', "/").replace('\n', " ")
            );
            continue;
        }
        md += &format!(
            "| {} | {:.4} | {} | {:.1} ({:.1}) | {} | {} | {:.1} | {} | {} | {} | {:.1} | {} | {} |\n",
            c.name,
            c.strength,
            c.standard_error.map_or("-".into(), |s| format!("{s:.4}")),
            c.chi2,
            c.chi2_scores,
            c.dof,
            p(c.p_value),
            c.chi2_drop,
            p(c.p_needed),
            if c.needed { "yes" } else { "no" },
            if c.within_noise { "yes" } else { "no" },
            c.unfinished_gain,
            c.p_worse.map_or("-".into(), p),
            if c.excluded { "yes" } else { "no" }
        );
    }
    md + &format!(
        "\nNeeded: the drop from the free parameters' fit against chi^2(1), Holm-corrected, under {alpha}; within the noise: p >= {alpha}, from the normal scores' chi^2, which allows for standard errors estimated from a few runs each (a row's z then has Student's t tails: `tilth_tools::compare::welch`). Excluded: were it the truth, a gap as large between its fit and the best needed one's (chi^2 in normal scores, less what its fit could still gain: the next step's predicted gain or, out of iterations, its last step's) would come with probability at most exp(-gap/2), Holm-corrected, under {alpha}; a rival kept only by an unfinished fit is fitted on once (DIR/refit/NAME/more/). The verdict below is the fits': the best needed contender, if within the noise, is named when every other needed one is excluded, and is ambiguous with those that are not; none is none of the candidates (or no effect when none is needed and the free parameters' fit is within the noise).\n\n"
    )
}

pub(super) fn verdict_words(v: &Verdict, out: &std::path::Path) -> String {
    let p = |x: f64| p_text(x).trim_start_matches("= ").to_string();
    let effects: Vec<String> = v
        .effects
        .iter()
        .map(|e| {
            format!(
                "{} (strength {:.4} ± {:.4}, p {})",
                called(&e.name),
                e.strength,
                e.standard_error,
                p(e.p_value)
            )
        })
        .collect();
    let misfit = format!(
        "chi^2 {:.1} on {} degrees of freedom, p {}; the free parameters' noise would bring {:.1} of it if their linear shift were real",
        v.misfit.chi2,
        v.misfit.dof,
        p(v.misfit.p_value),
        v.misfit.noise
    );
    let mut md = match v.verdict {
        Kind::Effect => {
            let mut t = format!(
                "**Verdict: {}.** Each is needed beyond the free parameters and the others, and no other candidate explains what it explains (each was tested in its place, below). What is left after {} is within the noise ({misfit}). The strengths are one-step linear estimates: fit them on simulations with `tilth fit --from-diagnosis {}` and compare again.",
                effects.join(" and "),
                if v.effects.len() == 1 { "it" } else { "them" },
                out.display()
            );
            if v.effects.iter().any(|e| e.name.starts_with(HELD)) {
                t += " A held parameter named here is not an effect: it is miscalibrated. Free it with --param and fit it before any effect is added.";
            }
            t
        }
        Kind::Ambiguous => {
            let mut t = format!(
                "**Verdict: ambiguous.** These data cannot tell {} apart: each explains what the first explains (the tests of each given another are below). Naming one of them would be a guess. Run `tilth next --diagnosis {}`: it ranks the measurements that would separate them and writes their conditions.",
                v.ambiguous
                    .iter()
                    .map(|n| called(n))
                    .collect::<Vec<_>>()
                    .join(", "),
                out.display()
            );
            if !effects.is_empty() {
                t += &format!(" Needed before them: {}.", effects.join(", "));
            }
            t += &could_absorb(&v.ambiguous);
            t
        }
        Kind::NoneOfTheCandidates => {
            let mut t = format!(
                "**Verdict: none of the candidates.** After the free parameters{}, what is left is more than the noise ({misfit}), and no candidate's signature explains it. The missing effect is none of these: see docs/adding-an-effect.md, or a parameter held fixed is off (list it in the model's [probes], or weigh it with --probe PAIR.KEY=STEP).",
                if v.effects.is_empty() && v.ambiguous.is_empty() {
                    String::new()
                } else {
                    format!(
                        " and the best candidate ({})",
                        v.effects
                            .first()
                            .map(|e| called(&e.name))
                            .or_else(|| v.ambiguous.first().map(|n| called(n)))
                            .unwrap_or_default()
                    )
                }
            );
            if !v.ambiguous.is_empty() {
                t += &format!(
                    " Of the candidates, {} cannot be told apart on these data.",
                    v.ambiguous
                        .iter()
                        .map(|n| called(n))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                t += &could_absorb(&v.ambiguous);
            }
            t
        }
        Kind::NoEffect => format!(
            "**Verdict: no effect.** No candidate is needed beyond the free parameters, and what they leave is within the noise ({misfit})."
        ),
    };
    md += "\n";
    if !v.encompassing.is_empty() {
        md += "\nEach candidate significant on its own, tested given another (is it still needed once the other is in the model?):\n\n| needed | given | statistic | p |\n|---|---|---|---|\n";
        for e in &v.encompassing {
            md += &format!(
                "| {} | {} | {:.2} | {} |\n",
                called(&e.needed),
                called(&e.given),
                e.statistic,
                p(e.p_value)
            );
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_held_parameters_among_the_rivals_are_named_as_what_could_absorb_the_misfit() {
        let names = |n: &[&str]| n.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(could_absorb(&names(&["fines", "capillary"])), "");
        let one = could_absorb(&names(&["fines", "held:soil-soil.friction"]));
        assert!(
            one.starts_with(" The held parameter soil-soil.friction could absorb"),
            "{one}"
        );
        let three = could_absorb(&names(&[
            "held:soil-soil.friction",
            "fines",
            "held:soil-soil.restitution",
            "held:soil-soil.surface_energy",
        ]));
        assert!(
            three.starts_with(" The held parameters soil-soil.friction, soil-soil.restitution and soil-soil.surface_energy could absorb"),
            "{three}"
        );
    }

    fn param(within_range: bool, measurable: bool) -> Recalibrated {
        Recalibrated {
            parameter: "soil-soil.rolling_friction".into(),
            step: 0.05,
            variant: "param-soil-soil.rolling_friction".into(),
            now: vec![0.2, 0.3],
            shift: 0.5,
            after: vec![0.7, 0.8],
            range: [0.05, 0.45],
            within_range,
            measurable,
            noise_share: 0.05,
        }
    }

    #[test]
    fn an_extrapolated_recalibration_is_named_as_one() {
        let ok = recalibration_table(&[param(true, true)]);
        assert!(ok.contains("| soil-soil.rolling_friction | 0.2000, 0.3000 | +0.5000 | 0.7000, 0.8000 | 0.05 .. 0.45 |"), "{ok}");
        assert!(!ok.contains("extrapolation"), "{ok}");
        let out = recalibration_table(&[param(false, true)]);
        assert!(
            out.contains("leaves its range") && out.contains("outside the range"),
            "{out}"
        );
        let flat = recalibration_table(&[param(true, false)]);
        assert!(
            flat.contains("no measurable effect") && flat.contains("fitted to noise"),
            "{flat}"
        );
        // And the candidates' tests could not take its misfit out: the report says so.
        let stand_in = "may stand for soil-soil.rolling_friction";
        assert!(flat.contains(stand_in), "{flat}");
        assert!(!ok.contains(stand_in) && !out.contains(stand_in), "{out}");
    }
}
